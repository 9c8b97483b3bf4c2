"""The implausible-event guard (`PhysicsConfig.guard`) and compliant features."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.objects import Protrusion, ProxySpec, load_builtin, proxy_model
from transfertwin.sim import DockingError, SceneConfig, SimulationUnstable, VirtualTransferSystem
from transfertwin.sim._system import _UNSTABLE
from transfertwin.study.experiment import ExperimentSpec, run_experiment

GUARD = SceneConfig().with_overrides(**{"physics.guard": True})


def _system(scene: SceneConfig, depth_m: float = 0.0) -> VirtualTransferSystem:
    base = load_builtin("o3", features=False)
    model = proxy_model(base, ProxySpec("p", "o3", (Protrusion("front", depth_m),)))
    m = model.mass
    return VirtualTransferSystem(model.hulls, m.mass_kg, m.com_m, m.inertia_kg_m2, scene,
                                 feature_hulls=model.feature_hulls)  # fmt: skip


def _settled(scene: SceneConfig) -> VirtualTransferSystem:
    system = _system(scene)
    system.reset(DockingError())
    system.place("front", 0.0, -0.3, 0.1)
    system.step(100)  # settles on the TM's left belt
    return system


def test_a_settled_object_is_plausible_and_the_guard_is_off_by_default() -> None:
    _settled(GUARD).step(50)
    assert SceneConfig().physics.guard is False


@pytest.mark.parametrize("kick", ["launch", "lift", "sink"])
def test_the_guard_catches_launches_energy_jumps_and_deep_penetration(kick: str) -> None:
    system = _settled(GUARD)
    plain = _settled(SceneConfig())
    for s in (system, plain):
        q, v = s._qadr, s._vadr
        if kick == "launch":  # 2 m/s along x: 13x belt speed, nothing falls
            s.data.qvel[v] = 2.0
        elif kick == "lift":  # 0.3 m up at rest: +2.9 J/kg of potential energy
            s.data.qpos[q + 2] += 0.3
        else:  # 40 mm into the belt
            s.data.qpos[q + 2] -= 0.04
        mujoco.mj_forward(s.model, s.data)
    word = {"launch": "speed", "lift": "energy", "sink": "penetration"}[kick]
    with pytest.raises(SimulationUnstable, match=f"implausible: .*{word}"):
        system.step(1)
    plain.step(1)  # without the guard nothing is noticed


@pytest.mark.parametrize("where", ["qpos", "qvel", "qacc"])
def test_a_state_mujoco_resets_is_reported_as_diverged(
    where: str, tmp_path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # MuJoCo answers a NaN in the position, velocity or acceleration by resetting the data
    # (a warning, no exception): the step must not go on from the reset state unnoticed.
    monkeypatch.chdir(tmp_path)  # MuJoCo logs its warning to MUJOCO_LOG.TXT here
    system = _settled(SceneConfig())
    if where == "qpos":
        system.data.qpos[system._qadr] = math.nan
    elif where == "qvel":
        system.data.qvel[system._vadr] = math.inf
    else:
        system.data.qfrc_applied[system._vadr] = math.nan
    with pytest.raises(SimulationUnstable, match="physics diverged"):
        system.step(3)
    w = mujoco.mjtWarning
    codes = range(*_UNSTABLE.indices(len(system.data.warning)))
    assert list(codes) == [int(w.mjWARN_BADQPOS), int(w.mjWARN_BADQVEL), int(w.mjWARN_BADQACC)]


def test_an_unstable_run_is_re_run_once_at_a_finer_timestep() -> None:
    # A limit below any belt motion: every transfer is implausible, the re-run as well.
    scene = GUARD.with_overrides(**{"physics.guard_speed_factor": 0.01})
    result = run_experiment(ExperimentSpec("o3", "front", "both", 90, scene=scene, seed=1))
    assert result.status == "unstable"
    assert result.message.startswith("re-run at 2.5 ms after: implausible: object speed")
    off = scene.with_overrides(**{"physics.guard_retry_timestep_factor": None})
    result = run_experiment(ExperimentSpec("o3", "front", "both", 90, scene=off, seed=1))
    assert result.status == "unstable" and not result.message.startswith("re-run")


def test_compliant_features_get_their_own_contact_settings() -> None:
    soft = SceneConfig().with_overrides(**{"physics.feature_solref": (0.05, 0.75)})
    rigid, compliant = _system(SceneConfig(), 0.01), _system(soft, 0.01)
    last = rigid.model.ngeom - 1  # the object's geoms come last; its feature is the last hull
    assert rigid.model.geom_priority[last] == 0
    assert compliant.model.geom_priority[last] == 2
    assert np.allclose(compliant.model.geom_solref[last], (0.05, 0.75))
    assert np.allclose(compliant.model.geom_friction[last][0], soft.mu)
    assert compliant.model.geom_priority[last - 1] == 0  # the body stays rigid


def test_guard_settings_are_checked() -> None:
    bads = (
        {"physics.guard_retry_timestep_factor": 1.5},
        {"physics.guard_speed_factor": 0.0},
        {"physics.feature_solref": (0.0, 1.0)},
    )
    for bad in bads:
        with pytest.raises(InputError):
            SceneConfig().with_overrides(**bad)
    assert math.isclose(SceneConfig().physics.guard_retry_timestep_factor, 0.5)
