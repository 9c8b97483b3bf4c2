"""The calibration designs (`calibration_design`): the study's random one unchanged, and the
space-filling one a Latin hypercube over face and θ per object."""

from __future__ import annotations

import pytest

from transfertwin._errors import InputError
from transfertwin.ots import THETA_SINGLE
from transfertwin.rehearsal import RehearsalConfig, calibration_design


def test_the_random_design_is_the_studys_own() -> None:
    got = [(r.object_id, r.face, r.conveyor, r.theta_deg)
           for r in calibration_design(["o1", "o2"], 4, 0)]  # fmt: skip
    assert got == [("o1", "front", "both", -32), ("o2", "back", "both", -63),
                   ("o1", "front", "both", -139), ("o2", "front", "right", -7)]  # fmt: skip


@pytest.mark.parametrize("k", [6, 10, 11])
def test_space_filling_hits_every_theta_stratum_and_both_faces_per_object(k: int) -> None:
    objects = ["o1", "o2", "o3"]
    design = calibration_design(objects, k, 7, design="space-filling")
    assert [r.object_id for r in design] == [objects[i % 3] for i in range(k)]
    for obj in objects:
        mine = [r for r in design if r.object_id == obj]
        n = len(mine)
        strata = sorted(int((r.theta_deg + 179) * n / 360) for r in mine)
        assert strata == list(range(n))  # one state in each of n equal θ strata
        fronts = sum(r.face == "front" for r in mine)
        assert abs(fronts - (n - fronts)) <= 1  # the faces as even as n allows
        for r in mine:
            assert -179 <= r.theta_deg <= 180
            assert (r.conveyor == "both") == (r.theta_deg not in set(THETA_SINGLE))
    again = calibration_design(objects, k, 7, design="space-filling")
    assert again == design  # the same seed, the same states


def test_an_unknown_design_is_refused() -> None:
    with pytest.raises(InputError, match="design must be one of random, space-filling"):
        calibration_design(["o1"], 3, 0, design="sobol")
    with pytest.raises(InputError, match="--design must be one of"):
        RehearsalConfig(plant_seed=1, objects=("o1",), calibration_experiments=10,
                        design="grid")  # fmt: skip
