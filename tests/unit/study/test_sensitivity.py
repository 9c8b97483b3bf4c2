"""Sensitivity analysis: outcome classes, yaw bands, signatures and factor parsing (no MuJoCo)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from transfertwin import InputError
from transfertwin.sim import SceneConfig
from transfertwin.study.calibration import (
    FACTORS,
    factor_levels,
    outcome,
    parse_factors,
    scene_at,
    signature,
    yaw_band,
)


def _row(status="ok", success=0, y1=0, x=0.0, z=0.04, sz=0.04, end2=None):
    state = json.dumps([1.0, x, 0.0, z, 0.1, 0.05, sz, 0.0, 0.0, 2.0, 5.0])
    return {"status": status, "success": success, "y1": y1,
            "state_end_1": state if y1 == 0 else "[]",
            "state_end_2": end2 if end2 is not None else ""}  # fmt: skip


@pytest.mark.parametrize(
    ("row", "kind"),
    [
        (_row(success=1, y1=1), "success"),
        (_row(status="unstable", success=None, y1=None), "not_ok"),
        (_row(x=0.03), "stuck"),  # timed out on the gap
        (_row(x=-0.11), "stuck"),
        (_row(x=0.3), "other"),  # failed far from the gap
        (_row(x=0.01, z=-0.05, sz=0.04), "fell"),  # bottom 90 mm below the belt
        (_row(y1=1, end2=json.dumps([0, 0.02, 0, 0.04, 0.1, 0.05, 0.04, 0, 0, 2, 5])), "stuck"),
        (_row(y1=1, end2=""), "other"),
    ],
)
def test_outcome_classes(row, kind):
    assert outcome(row) == kind


@pytest.mark.parametrize(
    ("theta", "band"),
    [(0, "0-30"), (29, "0-30"), (-30, "30-60"), (150, "30-60"), (180, "0-30"),
     (90, "60-90"), (-90, "60-90"), (120, "60-90"), (-179, "0-30"), (59, "30-60")],
)  # fmt: skip
def test_yaw_band_folds_theta_onto_0_to_90(theta, band):
    assert yaw_band(theta) == band


def test_signature_groups_runs_and_rows():
    rows = [
        {"object_id": "o1", "face": "front", "conveyor": "left", "theta_deg": 0},
        {"object_id": "o1", "face": "back", "conveyor": "both", "theta_deg": 90},
        {"object_id": "o2", "face": "back", "conveyor": "both", "theta_deg": 45},
    ]
    sig = signature(rows, np.array([[1, 0, 1], [1, 1, 1]]))
    assert sig["face"] == {"front": 1.0, "back": 0.75}
    assert sig["conveyor"] == {"left": 1.0, "both": 0.75, "right": None}
    assert sig["yaw"] == {"0-30": 1.0, "30-60": 1.0, "60-90": 0.5}
    assert sig["object_face"] == {"o1/back": 0.5, "o1/front": 1.0, "o2/back": 1.0}


def test_default_factors_cover_the_candidate_mechanisms():
    names = {f.name for f in parse_factors(None, SceneConfig())}
    assert names == {f.name for f in FACTORS}
    assert {"tu_height_offset_m", "tu_pitch_deg", "tu_roll_deg", "pulley_radius_m", "gap_mm",
            "mu", "solref_timeconst_s", "feature_mu", "com_offset_m"} <= names  # fmt: skip


def test_parse_factors_ranges_and_generic_settings():
    f = parse_factors("gap_mm=10:20, tu_roll_deg, layout.belt_speed_m_s=0.1:0.2", SceneConfig())
    assert [(x.name, x.low, x.high) for x in f] == [
        ("gap_mm", 10.0, 20.0), ("tu_roll_deg", -3.0, 3.0), ("layout.belt_speed_m_s", 0.1, 0.2)
    ]  # fmt: skip
    assert scene_at(SceneConfig(), f[0], 15.0).gap_m == pytest.approx(0.015)
    assert scene_at(SceneConfig(), f[2], 0.12).layout.belt_speed_m_s == 0.12


def test_solref_factor_keeps_the_base_damping():
    base = SceneConfig().with_overrides(**{"physics.solref": (0.02, 0.7)})
    (f,) = parse_factors("solref_timeconst_s=0.01:0.04", base)
    assert scene_at(base, f, 0.03).physics.solref == (0.03, 0.7)


@pytest.mark.parametrize(
    "text", ["nothing=0:1", "mu=1:0", "mu=0.3", "mu=x:y", "physics.solver=0:1",
             "tu_height_offset_m=-0.1:0.1", "t_max_s", "mu,mu", ","],
)  # fmt: skip
def test_parse_factors_rejects_bad_input(text):
    with pytest.raises(InputError):
        parse_factors(text, SceneConfig())


def test_factor_levels_are_evenly_spaced():
    (f,) = parse_factors("mu=0.2:0.8", SceneConfig())
    assert factor_levels(f, 4) == pytest.approx((0.2, 0.4, 0.6, 0.8))
    with pytest.raises(InputError):
        factor_levels(f, 1)
    assert math.isclose(factor_levels(f, 2)[1], 0.8)
