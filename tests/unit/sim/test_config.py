"""Frozen configurations: validation and dotted overrides."""

from __future__ import annotations

import pytest

from transfertwin import InputError
from transfertwin.sim import PhysicsConfig, SceneConfig


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


def test_camera_sampling_is_whole_physics_steps():
    cfg = SceneConfig(camera_rate_hz=30.0)
    assert cfg.steps_per_sample() == 17  # 1/30 s at 2 ms steps, rounded
