"""The plant seed's file (``plant.secret``): owner-only, one non-negative integer."""

from __future__ import annotations

import stat

import pytest

from transfertwin._errors import InputError
from transfertwin.plant import PLANT_SEED_FILE, read_plant_seed, write_plant_seed


def test_the_seed_round_trips_through_an_owner_only_file(tmp_path) -> None:
    path = write_plant_seed(tmp_path / "r" / PLANT_SEED_FILE, 918273)
    assert path.name == "plant.secret" and read_plant_seed(path) == 918273
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    path.chmod(0o644)  # written again: owner-only again
    write_plant_seed(path, 5)
    assert stat.S_IMODE(path.stat().st_mode) == 0o600 and read_plant_seed(path) == 5


@pytest.mark.parametrize("text", ["", "x\n", "-3\n", "1.5\n"])
def test_anything_but_a_non_negative_integer_is_refused(tmp_path, text) -> None:
    path = tmp_path / PLANT_SEED_FILE
    path.write_text(text)
    with pytest.raises(InputError, match="non-negative integer"):
        read_plant_seed(path)
    with pytest.raises(InputError, match="cannot read"):
        read_plant_seed(tmp_path / "missing.secret")
