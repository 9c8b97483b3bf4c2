"""Real MuJoCo: belts drive, gaps are crossed or not, barriers see, the HAL is the protocol."""

from __future__ import annotations

import numpy as np
import pytest

from tests.conftest import box_hulls, box_inertia
from transfertwin.control import Clock, ObjectSensor, UnitHAL
from transfertwin.sim import DockingError, SceneConfig, VirtualTransferSystem, scene_profile

MASS = 3.0


def _system(**overrides) -> VirtualTransferSystem:
    cfg = SceneConfig().with_overrides(**overrides) if overrides else SceneConfig()
    system = VirtualTransferSystem(box_hulls(), MASS, np.zeros(3), box_inertia(MASS), cfg)
    system.reset(DockingError())
    return system


def _run_all(system: VirtualTransferSystem, speed: float) -> None:
    for hal in (system.tm, system.tu):
        for belt in ("left", "right"):
            hal.set_belt_speed(belt, speed)


def test_virtual_units_implement_the_hal_protocols():
    system = _system()
    assert isinstance(system.tm, UnitHAL) and isinstance(system.tu, UnitHAL)
    assert isinstance(system.clock, Clock)
    assert isinstance(system, ObjectSensor)


def test_box_on_running_belt_reaches_belt_speed():
    system = _system()
    system.place("front", 0.0, -0.45, 0.0)
    system.clock.wait(0.3)
    assert system.object_speed() < 0.01
    _run_all(system, 0.15)
    system.clock.wait(1.0)
    vx = system.data.qvel[0]
    assert vx == pytest.approx(0.15, rel=0.05)


def test_box_crosses_nominal_gap_onto_transfer_unit():
    system = _system()
    system.place("front", 0.0, -0.325, 0.0)
    system.clock.wait(0.3)
    assert system.observe()[0] == 0  # possessed by the TM
    _run_all(system, 0.15)
    system.clock.wait(4.5)
    a, x, _, z, _, _, sz, _ = system.observe()
    assert a == 1  # possessed by the TU
    assert x > 0.2
    assert z - sz > -0.005  # still on the belt surface


def test_single_belt_only_moves_what_lies_on_it():
    system = _system()
    system.place("front", 0.0, -0.325, 0.1)  # on the left belt
    system.clock.wait(0.3)
    system.tm.set_belt_speed("right", 0.15)
    system.clock.wait(1.0)
    assert abs(system.observe()[1] - (-0.325)) < 0.01


def test_mu_zero_transfers_nothing():
    system = _system(mu=0.0)
    system.place("front", 0.0, -0.325, 0.0)
    system.clock.wait(0.3)
    _run_all(system, 0.15)
    system.clock.wait(3.0)
    assert abs(system.observe()[1] - (-0.325)) < 0.02


def test_gap_wider_than_object_swallows_it():
    system = _system(gap_m=0.3)
    system.place("front", 0.0, -0.325, 0.0)
    system.clock.wait(0.3)
    _run_all(system, 0.15)
    system.clock.wait(5.0)
    _, _, _, z, _, _, sz, _ = system.observe()
    assert z - sz < -0.1  # fell into the gap


def test_light_barriers_see_the_object_pass():
    system = _system()
    system.place("front", 0.0, -0.325, 0.0)
    system.clock.wait(0.3)
    assert system.tm.barriers() == {"near": False, "far": False}
    _run_all(system, 0.15)
    seen = {"tm_near": False, "tu_near": False}
    for _ in range(40):
        system.clock.wait(0.1)
        seen["tm_near"] |= system.tm.barriers()["near"]
        seen["tu_near"] |= system.tu.barriers()["near"]
    assert seen == {"tm_near": True, "tu_near": True}


def test_docking_error_moves_the_transfer_unit_without_recompiling():
    system = _system()
    model_before = system.model
    system.reset(DockingError.from_mm_deg(-20.0, 10.0, 1.5))
    assert system.model is model_before
    x, y, _ = system.tu_pose
    system.clock.wait(0.002)
    tu_body = system.model.body("tu").id
    assert system.data.xpos[tu_body][:2] == pytest.approx([x, y])
    assert x > SceneConfig().gap_m + 0.019


def test_controller_stops_belts_at_the_receivers_far_barrier():
    from transfertwin.control import OTSController
    from transfertwin.ots import BeltThresholds, TransferDirection

    system = _system()
    system.place("front", 0.0, -0.325, 0.0)
    system.clock.wait(0.3)
    # A success threshold the object can never meet: it runs on to the TU's far end.
    th = BeltThresholds(x_success=0.49, t_max=8.0)
    ctl = OTSController(system.tm, system.tu, system, system.clock, thresholds=th,
                        belt_speed_m_s=0.15, sample_period_s=0.034)  # fmt: skip
    record = ctl.transfer(TransferDirection.TM_TO_TU, "front", "both")
    assert record.y == 0
    assert system.tu.belt_speed("left") == 0.0
    _, x, _, z, sx, _, sz, _ = system.observe()
    assert x + sx <= SceneConfig().gap_m + 0.5 + 0.01  # stopped at the end, not run off
    assert z - sz > -0.005


def test_lean_multiccd_follows_the_objects_hull_count_and_a_box_rests_flat():
    import mujoco  # after transfertwin, which picks the headless GL backend

    from transfertwin.objects import load_object

    off = int(mujoco.mjtDisableBit.mjDSBL_MULTICCD)
    lean = {"physics.max_hulls": 8, "physics.multiccd": None}  # the 'lean' profile
    box = _system(**lean)  # one hull: multi-CCD stays on, so the box rests still on its face
    assert not box.model.opt.disableflags & off
    box.place("front", 0.0, -0.45, 0.0)
    box.clock.wait(0.3)
    assert box.object_speed() < 0.01
    core = load_object("o1")  # 12+ hulls, merged to the budget: multi-CCD off
    system = VirtualTransferSystem(core.hulls, core.mass.mass_kg, core.mass.com_m,
                                   core.mass.inertia_kg_m2, scene_profile("lean"),
                                   feature_hulls=core.feature_hulls)  # fmt: skip
    assert system.model.ngeom - box.model.ngeom == 8 + core.feature_hulls - 1
    assert system.model.opt.disableflags & off
    assert not _system().model.opt.disableflags & off  # the defaults keep it on
    rocking = _system(**{"physics.multiccd": False})  # why the box keeps it: without,
    assert rocking.model.opt.disableflags & off  # one contact per pair, and it rocks
    rocking.place("front", 0.0, -0.45, 0.0)
    rocking.clock.wait(0.3)
    assert rocking.object_speed() > 0.01
