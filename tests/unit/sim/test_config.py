"""Frozen configurations: validation and dotted overrides."""

from __future__ import annotations

import pytest

from transfertwin import InputError
from transfertwin.sim import MULTICCD_HULLS, PhysicsConfig, SceneConfig, scene_profile


def test_overrides_accept_dotted_names_and_keep_the_original():
    base = SceneConfig()
    changed = base.with_overrides(mu=0.3, **{"physics.solver": "CG", "layout.belt_speed_m_s": 0.1})
    assert (changed.mu, changed.physics.solver, changed.layout.belt_speed_m_s) == (0.3, "CG", 0.1)
    assert (base.mu, base.physics.solver) == (0.489, "Newton")


@pytest.mark.parametrize(
    "bad", [{"bogus": 1}, {"physics.bogus": 1}, {"nowhere.x": 1}, {"physics.solver": "magic"}]
)
def test_overrides_reject_unknown_settings(bad):
    with pytest.raises(InputError):
        SceneConfig().with_overrides(**bad)


def test_invalid_values_are_input_errors():
    with pytest.raises(InputError):
        PhysicsConfig(timestep_s=0)
    with pytest.raises(InputError):
        SceneConfig(mu=-0.1)
    with pytest.raises(InputError):
        SceneConfig(gap_m=0.6)


@pytest.mark.parametrize("facets", [-1, 1, 7, 257, 12.0, True, "32"])
def test_pulley_facets_are_zero_or_a_prism(facets):
    with pytest.raises(InputError, match="pulley_facets"):
        PhysicsConfig(pulley_facets=facets)
    assert PhysicsConfig().pulley_facets == 32  # prism pulleys by default
    assert PhysicsConfig(pulley_facets=0).pulley_facets == 0  # MuJoCo's cylinders


def test_camera_sampling_is_whole_physics_steps():
    cfg = SceneConfig(camera_rate_hz=30.0).with_overrides(**{"physics.timestep_s": 0.002})
    assert cfg.steps_per_sample() == 17  # 1/30 s at 2 ms steps, rounded
    assert SceneConfig().steps_per_sample() == 13  # 1/15 s at 5 ms steps, rounded


def test_physics_config_reaches_the_compiled_model():
    import mujoco
    import numpy as np

    from tests.conftest import box_hulls, box_inertia
    from transfertwin.sim import build_spec

    cfg = SceneConfig().with_overrides(
        **{"physics.solver": "CG", "physics.cone": "pyramidal", "physics.multiccd": False,
           "physics.timestep_s": 0.001, "physics.impratio": 3.0}
    )  # fmt: skip
    m = build_spec(box_hulls(), 1.0, np.zeros(3), box_inertia(1.0), cfg).compile()
    assert m.opt.solver == mujoco.mjtSolver.mjSOL_CG
    assert m.opt.cone == mujoco.mjtCone.mjCONE_PYRAMIDAL
    assert m.opt.timestep == 0.001 and m.opt.impratio == 3.0
    assert m.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_MULTICCD)
    default = build_spec(box_hulls(), 1.0, np.zeros(3), box_inertia(1.0), SceneConfig()).compile()
    assert not default.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_MULTICCD)


def test_unmeasured_mechanisms_default_to_none_and_accept_overrides():
    base = SceneConfig()
    assert (base.layout.tu_height_offset_m, base.layout.tu_pitch_deg) == (0.0, 0.0)
    assert (base.layout.tu_roll_deg, base.feature_mu, base.com_offset_m) == (0.0, None, 0.0)
    cfg = base.with_overrides(
        feature_mu=0.3, com_offset_m=0.01,
        **{"layout.tu_height_offset_m": -0.003, "layout.tu_pitch_deg": 2.0,
           "layout.tu_roll_deg": -1.0},
    )  # fmt: skip
    assert (cfg.layout.tu_height_offset_m, cfg.layout.tu_pitch_deg) == (-0.003, 2.0)
    assert (cfg.layout.tu_roll_deg, cfg.feature_mu, cfg.com_offset_m) == (-1.0, 0.3, 0.01)


@pytest.mark.parametrize(
    "bad",
    [
        {"layout.tu_height_offset_m": 0.06},
        {"layout.tu_pitch_deg": 11.0},
        {"layout.tu_roll_deg": float("nan")},
        {"feature_mu": -0.1},
        {"com_offset_m": 0.2},
    ],
)
def test_unmeasured_mechanisms_reject_out_of_range_values(bad):
    with pytest.raises(InputError):
        SceneConfig().with_overrides(**bad)


def test_speed_lever_settings_are_validated():
    assert SceneConfig().stall_mode == "progress" and SceneConfig().physics.max_hulls is None
    assert SceneConfig().with_overrides(stall_mode="still").stall_mode == "still"
    for bad in ({"stall_mode": "soon"}, {"physics.max_hulls": 0}, {"physics.max_hulls": 2.5},
                {"physics.multiccd": "yes"}, {"physics.multiccd": 1}):  # fmt: skip
        with pytest.raises(InputError):
            SceneConfig().with_overrides(**bad)


def test_multiccd_of_the_lean_profile_depends_on_the_objects_hull_count():
    assert SceneConfig().physics.multiccd is True and SceneConfig().physics.multiccd_for(26)
    physics = scene_profile("lean").physics
    assert physics.multiccd is None and physics.max_hulls == 8
    assert physics.multiccd_for(1) and physics.multiccd_for(MULTICCD_HULLS - 1)
    assert not physics.multiccd_for(MULTICCD_HULLS) and not physics.multiccd_for(26)
    forced = SceneConfig().with_overrides(**{"physics.multiccd": True}).physics
    assert forced.multiccd_for(26)
    assert not SceneConfig().with_overrides(**{"physics.multiccd": False}).physics.multiccd_for(1)
    reference = scene_profile("reference").physics
    assert reference.multiccd_for(26) and reference.max_hulls is None
