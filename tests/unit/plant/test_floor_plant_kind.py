"""A floor on the mismatch plant: the plant's kind beside its seed in the floor's secret
file, and the modules' plant physics of that kind."""

from __future__ import annotations

import numpy as np
import pytest

from transfertwin import InputError
from transfertwin.cps.floor import read_plant_kind, read_plant_seed, write_plant_seed
from transfertwin.plant import PlantPhysics


def test_the_secret_file_names_a_kind_other_than_in_class(tmp_path) -> None:
    plain = write_plant_seed(tmp_path / "a.secret", 7)
    assert plain.read_text() == "7\n"  # the in-class plant's file is unchanged
    assert (read_plant_seed(plain), read_plant_kind(plain)) == (7, "in-class")
    other = write_plant_seed(tmp_path / "b.secret", 7, "mismatch")
    assert other.read_text() == "7 mismatch\n"
    assert (read_plant_seed(other), read_plant_kind(other)) == (7, "mismatch")
    bad = tmp_path / "c.secret"
    bad.write_text("7 mismatch extra\n")
    with pytest.raises(InputError, match="non-negative integer"):
        read_plant_kind(bad)


def test_the_mismatch_plants_physics_differ_from_the_in_class_plants() -> None:
    same = PlantPhysics(7).system("o1")
    other = PlantPhysics(7, "mismatch").system("o1")
    assert other is not same
    # its structural differences are in the compiled model: geometry, mass distribution
    differs = (other.model.nbody != same.model.nbody
               or other.model.ngeom != same.model.ngeom
               or not np.allclose(other.model.body_inertia, same.model.body_inertia))  # fmt: skip
    assert differs
    with pytest.raises(InputError, match="in-class, mismatch"):
        PlantPhysics(7, "bullet")  # another engine: not a floor's
