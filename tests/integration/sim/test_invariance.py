"""Physics invariance of a symmetric box (issue 15, item 15).

A 120 x 80 x 60 mm box turned over ('back') or mirrored (left <-> right, docking error
y and yaw negated) is the same box in the same place, so its outcomes should agree.

What we found (docs/design-choices.md, "Contact asymmetry"): everything transfertwin
builds is symmetric (one hull that is the box itself, centre of mass at the origin, the
same resting pose and the same deck contacts for both faces), and with MuJoCo's multiccd
off front and back give bit-identical runs. With multiccd on (the default, kept because
without it a single-hull box rocks and sinks into the belt) MuJoCo's contact generation
for the box's leading edge on a pulley depends on the mesh's orientation: 'front' gets a
single corner contact and stalls at the roller, 'back' gets a contact at both corners and
crosses. The statistical invariance test therefore fails today and is marked xfail
(strict: it will report when a MuJoCo version or scene change fixes it).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh

from transfertwin.objects import load_object
from transfertwin.sim import DockingError, SceneConfig
from transfertwin.study.experiment import ExperimentSpec, run_experiment, system_for
from transfertwin.study.fullstate import clopper_pearson

ERR = (-8.82, 9.66, 1.34)  # the docking error of the report (mm, mm, deg)


@pytest.fixture(scope="module")
def box(tmp_path_factory) -> str:
    path = tmp_path_factory.mktemp("box") / "box120.stl"
    trimesh.creation.box(extents=(120.0, 80.0, 60.0)).export(path)
    return str(path)


def _row(box, face, conveyor, err, seed, scene=None):
    spec = ExperimentSpec(box, face, conveyor, 0, docking_error=DockingError.from_mm_deg(*err),
                          seed=seed, units="mm", scene=scene or SceneConfig())  # fmt: skip
    return run_experiment(spec).row()


def test_a_box_is_built_symmetric_and_rests_the_same_on_both_faces(box):
    model = load_object(box, units="mm")
    assert len(model.hulls) == 1  # the hull of a box is the box itself
    hull = model.hulls[0]
    assert hull.shape == (8, 3)
    np.testing.assert_allclose(np.sort(np.abs(hull), axis=0), [[0.06, 0.04, 0.03]] * 8, atol=1e-7)
    np.testing.assert_allclose(model.mass.com_m, 0.0, atol=1e-12)
    np.testing.assert_allclose(model.mass.inertia_kg_m2, np.diag(np.diag(model.mass.inertia_kg_m2)),
                               atol=1e-12)  # fmt: skip

    system = system_for(box, "mm", SceneConfig())
    rest = {}
    for face in ("front", "back"):
        system.reset(DockingError.from_mm_deg(*ERR))
        tx, ty, _ = system.tu_pose
        system.place(face, 0.0, tx + 0.25, ty)
        system.clock.wait(0.6)
        pos, rot = system.object_pose()
        corners = np.array([[sx * 0.06, sy * 0.04, sz * 0.03] for sx in (-1, 1)
                            for sy in (-1, 1) for sz in (-1, 1)]) @ rot.T + pos  # fmt: skip
        contacts = sorted(
            tuple(np.round(c.pos, 5)) for c in system.data.contact[: system.data.ncon]
        )
        rest[face] = (np.sort(np.round(corners, 5), axis=0), contacts)
    # the same volume in the same place, touching the belts at the same points
    np.testing.assert_allclose(rest["front"][0], rest["back"][0], atol=1e-5)
    assert rest["front"][1] == rest["back"][1]


def test_without_multiccd_front_and_back_are_the_same_run(box):
    """The cause: with one contact per pair the two faces give bit-identical runs."""
    scene = SceneConfig().with_overrides(**{"physics.multiccd": False})
    front = _row(box, "front", "left", ERR, 0, scene)
    back = _row(box, "back", "left", ERR, 0, scene)
    for key in ("y1", "y2", "t_end_1_s", "t_end_2_s", "state_end_1", "state_end_2"):
        a, b = front[key], back[key]
        if key.startswith("state"):
            a, b = json.loads(a), json.loads(b)
            a.pop(-3), b.pop(-3)  # the state names the face
        assert a == b, key


def _successes(box, face, conveyor, err, n):
    return sum(_row(box, face, conveyor, err, seed)["success"] == 1 for seed in range(n))


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="MuJoCo multiccd edge contacts depend on the mesh's "
                   "orientation (see module docstring)")  # fmt: skip
def test_symmetric_box_outcomes_agree_for_front_back_and_mirrored_states(box):
    n = 8
    mirrored = (ERR[0], -ERR[1], -ERR[2])
    counts = {
        ("front", "left"): _successes(box, "front", "left", ERR, n),
        ("back", "left"): _successes(box, "back", "left", ERR, n),
        ("front", "right"): _successes(box, "front", "right", mirrored, n),
        ("back", "right"): _successes(box, "back", "right", mirrored, n),
    }
    intervals = {k: clopper_pearson(v, n) for k, v in counts.items()}
    for a, b in (
        (("front", "left"), ("back", "left")),
        (("front", "right"), ("back", "right")),
        (("front", "left"), ("front", "right")),
        (("back", "left"), ("back", "right")),
    ):
        lo_a, hi_a = intervals[a].low, intervals[a].high
        lo_b, hi_b = intervals[b].low, intervals[b].high
        # each estimate lies in the other's interval
        assert lo_b <= counts[a] / n <= hi_b and lo_a <= counts[b] / n <= hi_a, (a, b, counts)
