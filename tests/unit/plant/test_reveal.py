"""`reveal_truth`: the plant's hidden values, for scoring a rehearsal afterwards."""

from __future__ import annotations

import pytest

from transfertwin._errors import InputError
from transfertwin.plant import MISMATCH_PARTS, EmulatedPlant, reveal_truth


def test_revealed_mass_and_centre_agree_with_the_plants_scale_and_balance() -> None:
    """The scale reads the mass to 0.2 % and the balances the centre to about 1 mm per axis:
    the revealed values must lie within a few of those errors of the readings."""
    plant = EmulatedPlant(1)
    truth = reveal_truth(1, ["o3", "o7"])
    for oid in ("o3", "o7"):
        reading, hidden = plant.weigh(oid), truth.object(oid)
        assert hidden.mass_kg == pytest.approx(reading.mass_kg, rel=0.01)
        for true_mm, read_m in zip(hidden.com_mm, reading.com_m, strict=True):
            assert abs(true_mm - read_m * 1000.0) < 5.0


def test_revealed_values_follow_the_plants_priors() -> None:
    truth = reveal_truth(3, ["o1", "o2", "o3", "o4"])
    assert 0.38 <= truth.scene.mu <= 0.62 and 9.0 <= truth.scene.gap_mm <= 16.0
    for obj in truth.objects:
        assert [face for face, _ in obj.depth_mm] == ["front", "back"]
        for _, depth in obj.depth_mm:
            assert depth == 0.0 or 4.0 <= depth <= 26.0
        assert 30.0 <= obj.contact_ms <= 80.0
    assert truth.kind == "in-class" and truth.structural_parts == ()


def test_a_mismatch_plant_lists_its_structural_parts() -> None:
    truth = reveal_truth(1, ["o3"], kind="mismatch", mismatch_off=("sag",))
    assert truth.structural_parts == tuple(p for p in MISMATCH_PARTS if p != "sag")
    # its centre of mass carries the mismatch's shift, as the plant's balance reads it
    reading = EmulatedPlant(1, kind="mismatch").weigh("o3")
    for true_mm, read_m in zip(truth.object("o3").com_mm, reading.com_m, strict=True):
        assert abs(true_mm - read_m * 1000.0) < 5.0


@pytest.mark.parametrize(
    ("seed", "objects", "kind", "message"),
    [(-1, ["o3"], "in-class", "seed"), (1, ["o99"], "in-class", "no object o99"),
     (1, ["o3"], "real", "plant kind")],
)  # fmt: skip
def test_bad_requests_are_refused(seed, objects, kind, message) -> None:
    with pytest.raises(InputError, match=message):
        reveal_truth(seed, objects, kind=kind)
