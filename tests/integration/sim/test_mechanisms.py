"""Each candidate gap mechanism of the scene reaches the physics (real MuJoCo).

TU height step, pitch and roll, feature friction and the centre-of-mass offset all default to
today's behaviour; here each is switched on and shown to move the geometry it claims to move
and to change an outcome (or the end state) of a transfer that is unchanged at its default.
"""

from __future__ import annotations

import json
import math

import mujoco
import numpy as np
import pytest

from tests.conftest import box_hulls, box_inertia, plain_body_proxy
from transfertwin.sim import DockingError, SceneConfig, VirtualTransferSystem
from transfertwin.study import ExperimentSpec, run_experiment


def _system(**overrides) -> VirtualTransferSystem:
    cfg = SceneConfig().with_overrides(**overrides)
    system = VirtualTransferSystem(box_hulls(), 3.0, np.zeros(3), box_inertia(3.0), cfg)
    system.reset(DockingError())
    return system


def _geom_pos(system: VirtualTransferSystem, name: str) -> np.ndarray:
    return system.data.geom_xpos[system.model.geom(name).id].copy()


_PLAIN: dict[str, str] = {}


@pytest.fixture(scope="module", autouse=True)
def _plain_o1(tmp_path_factory) -> None:
    """o1's plain body (a proxy without protrusions): its shipped resting features would
    catch at the gap by themselves and hide each mechanism's own effect."""
    _PLAIN["o1"] = plain_body_proxy(tmp_path_factory.mktemp("plain"))


def _run(overrides: dict, ref: str | None = None, face: str = "front", conveyor: str = "both"):
    scene = SceneConfig().with_overrides(**overrides)
    spec = ExperimentSpec(ref or _PLAIN["o1"], face, conveyor, 0, scene=scene, seed=1)
    return run_experiment(spec)


def test_height_step_moves_every_tu_belt_geom_and_no_tm_geom():
    flat, step = _system(), _system(**{"layout.tu_height_offset_m": 0.004})
    for name in ("tu_left_deck", "tu_right_pulley_start", "tu_left_pulley_end"):
        dz = _geom_pos(step, name) - _geom_pos(flat, name)
        assert dz == pytest.approx([0.0, 0.0, 0.004], abs=1e-12)
    assert np.array_equal(_geom_pos(step, "tm_left_deck"), _geom_pos(flat, "tm_left_deck"))


def test_pitch_turns_the_tu_about_the_gap_line():
    pitch = _system(**{"layout.tu_pitch_deg": 3.0})
    flat = _system()
    near, far = "tu_left_pulley_start", "tu_left_pulley_end"
    lever = _geom_pos(flat, far)[0] - SceneConfig().gap_m  # far pulley's x in the TU frame
    rise = _geom_pos(pitch, far)[2] - _geom_pos(flat, far)[2]
    assert rise == pytest.approx(lever * math.sin(math.radians(3.0)), rel=0.02)
    # The near pulley lies next to the axis: it hardly moves.
    assert abs(_geom_pos(pitch, near)[2] - _geom_pos(flat, near)[2]) < 0.002


def test_roll_raises_the_left_belt_and_lowers_the_right():
    roll, flat = _system(**{"layout.tu_roll_deg": 2.0}), _system()
    dz_left = _geom_pos(roll, "tu_left_deck")[2] - _geom_pos(flat, "tu_left_deck")[2]
    dz_right = _geom_pos(roll, "tu_right_deck")[2] - _geom_pos(flat, "tu_right_deck")[2]
    y = SceneConfig().layout.belt_centre_y("left")
    assert dz_left == pytest.approx(y * math.sin(math.radians(2.0)), rel=0.05)
    assert dz_right == pytest.approx(-dz_left, rel=0.02)  # decks sit r below the axis


def test_a_large_height_step_catches_an_object_that_crosses_a_flat_gap():
    assert _run({}).success == 1
    stuck = _run({"layout.tu_height_offset_m": 0.04})
    assert (stuck.status, stuck.y1) == ("ok", 0)
    assert abs(stuck.state_end_1[1]) < 0.12  # still at the gap


def test_a_downhill_pitch_changes_the_outcome():
    assert _run({}).y1 == 1
    assert _run({"layout.tu_pitch_deg": -10.0}).y1 == 0


def test_roll_drifts_the_object_sideways_on_the_tu():
    # +6 deg raises the left belt: an object on it crosses, slid down towards the centre
    # (+8 deg stalls it at the gap)
    flat, roll = _run({}, conveyor="left"), _run({"layout.tu_roll_deg": 6.0}, conveyor="left")
    assert flat.y1 == 1 and roll.y1 == 1
    assert flat.state_end_1[2] - roll.state_end_1[2] > 0.02  # y: slid towards the centre


def test_com_offset_shifts_the_body_inertial_frame():
    base = _system()
    shifted = _system(com_offset_m=0.02)
    body = base.model.body("object").id
    assert shifted.model.body_ipos[body] - base.model.body_ipos[body] == pytest.approx(
        [0.02, 0.0, 0.0]
    )


def test_com_offset_changes_the_outcome_over_a_wide_gap():
    # At a 60 mm gap the plain core crosses; a centre of mass moved 30 mm towards the
    # nose tips the nose into the gap, and the core sticks there.
    assert _run({"gap_m": 0.06}).y1 == 1
    assert _run({"gap_m": 0.06, "com_offset_m": 0.03}).y1 == 0


@pytest.fixture(scope="module")
def o1_proxy(tmp_path_factory) -> str:
    path = tmp_path_factory.mktemp("proxy") / "o1.proxy.json"
    # 8 mm below the back face: it catches at the gap, unless its friction is high
    prot = {"face": "back", "depth_m": 0.008, "x_frac": 0.5, "y_frac": 0.5,
            "size_x_m": 0.006, "size_y_m": 0.03, "height_m": None}  # fmt: skip
    path.write_text(json.dumps({"object_id": "o1", "base": "o1", "protrusions": [prot]}))
    return str(path)


def test_feature_friction_reaches_only_the_proxy_protrusion(o1_proxy):
    from transfertwin.study.experiment import system_for

    off = system_for(o1_proxy, "m", SceneConfig())
    on = system_for(o1_proxy, "m", SceneConfig(feature_mu=1.7))
    hulls = [i for i in range(on.model.ngeom) if on.model.geom(i).name.startswith("object_")]
    last = hulls[-1]
    assert on.model.geom_priority[last] == 2 and on.model.geom_friction[last][0] == 1.7
    assert off.model.geom_priority[last] == 0
    assert all(on.model.geom_priority[i] == 0 for i in hulls[:-1])
    assert mujoco.mj_name2id(on.model, mujoco.mjtObj.mjOBJ_BODY, "object") >= 0


def test_feature_friction_changes_the_outcome_of_a_catching_proxy(o1_proxy):
    assert _run({}, ref=o1_proxy, face="back").success == 0
    assert _run({"feature_mu": 2.0}, ref=o1_proxy, face="back").success == 1


def test_contact_settings_reach_the_object_belt_contacts():
    # The belts' contact priority makes MuJoCo take every contact parameter from them:
    # physics.solref/solimp/condim must be set there, or they do nothing.
    for solref, condim in (((0.02, 1.0), 3), ((0.05, 0.8), 4)):
        system = _system(**{"physics.solref": solref, "physics.condim": condim})
        system.place("front", 0.0, -0.3, 0.0)
        system.clock.wait(0.2)
        assert system.data.ncon > 0
        contact = system.data.contact[0]
        assert tuple(contact.solref) == pytest.approx(solref)
        assert contact.dim == condim
