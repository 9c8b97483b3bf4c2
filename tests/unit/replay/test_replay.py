"""Replays (issue 31): the recorded experiment is the experiment (same bits), its OTS time line
follows the belt sets, and its exports (JSON document, animated glTF, GIF) hold the motion."""

from __future__ import annotations

import base64
import dataclasses
import io

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.replay import (
    OTS_CODES,
    compare_with_row,
    gif_frame_times,
    glb_bytes,
    record_experiment,
    replay_payload,
    study_spec,
    transfer_spec,
    write_gif,
)
from transfertwin.store import SQLiteResultStore
from transfertwin.study.docking import docking_model
from transfertwin.study.experiment import StudyPlan, run_experiment, run_study


@pytest.fixture(scope="module")
def success():
    """o1 lying front on the left belt at 90°: there and back, both succeed."""
    return record_experiment(transfer_spec("o1", "front", "left", 90, seed=3))


@pytest.fixture(scope="module")
def gap_failure():
    """A gap of 80 mm: o1 drops into it on the way to the TU (failure)."""
    return record_experiment(transfer_spec("o1", "front", "both", 90, seed=3, gap_mm=80))


def test_a_replay_has_the_bits_of_the_experiment(success):
    plain = run_experiment(dataclasses.replace(success.spec, record=False))
    assert success.result.row() == plain.row()
    # Every pose the controller sampled is among the recorded ones, bit for bit.
    sampled = run_experiment(success.spec).frames
    recorded = {tuple(q) for q in success.qpos.tolist()}
    assert len(sampled) > 50 and {tuple(f.qpos) for f in sampled} <= recorded
    assert success.t_s[0] > 0 and np.all(np.diff(success.t_s) > 0)


def test_the_time_line_has_the_ots_transitions(success):
    kinds = [m.kind for m in success.markers]
    assert kinds == ["none", "pre", "success", "pre", "success"]
    r = success.result
    there_pre, there_end, back_pre, back_end = success.markers[1:]
    assert there_end.t_s - there_pre.t_s == pytest.approx(r.t_end_1_s, abs=1e-6)
    assert back_end.t_s - back_pre.t_s == pytest.approx(r.t_end_2_s, abs=1e-6)
    codes = success.ots
    i_end = int(np.flatnonzero(success.t_s == there_end.t_s)[0])
    assert codes[i_end] == OTS_CODES["success"]
    between = codes[(success.t_s > there_pre.t_s) & (success.t_s < there_end.t_s)]
    assert len(between) > 10 and set(between.tolist()) == {OTS_CODES["non_terminal"]}
    # Belts run during each transfer (the TU's too) and stand still while settling.
    moving = np.abs(success.belts).max(axis=1) > 0
    assert moving[(success.t_s > there_pre.t_s + 0.1) & (success.t_s < there_end.t_s)].all()
    assert not moving[success.t_s < there_pre.t_s].any()
    # The object interrupts the TU's near barrier on its way over, and the TM's on the way back.
    assert success.barriers[:i_end, 2].any()
    assert success.barriers[i_end:, 0].any()


def test_a_failure_ends_with_the_object_in_the_gap(gap_failure):
    r = gap_failure.result
    assert (r.status, r.y1, r.y2) == ("ok", 0, None)
    end = gap_failure.markers[-1]
    assert end.kind == "failure"
    i = int(np.flatnonzero(gap_failure.t_s == end.t_s)[0])
    assert gap_failure.ots[i] == OTS_CODES["failure"]
    x = gap_failure.qpos[i, 0]
    assert 0.0 < x < 0.08  # between the TM's tip and the TU's near end
    assert gap_failure.tu_pose == pytest.approx((0.08, 0.0, 0.0))


def test_the_document_carries_scene_and_motion(gap_failure):
    doc = replay_payload(gap_failure)
    frames = doc["frames"]
    n = len(gap_failure.t_s)
    assert len(frames["t"]) == len(frames["pos"]) == len(frames["quat"]) == n
    assert frames["ots"] == gap_failure.ots.tolist()
    names = {p["name"] for p in doc["scene"]["parts"]}
    assert {"tm_left_deck", "tu_right_pulley_end", "object_hull_0"} <= names
    verts = np.frombuffer(base64.b64decode(doc["scene"]["object_mesh"]["vertices"]), "<f4")
    assert verts.size % 3 == 0 and verts.size > 300
    travel = np.array(frames["travel"])
    assert np.all(np.diff(travel[:, 0]) >= -1e-9) and travel[-1, 0] > 0.2  # the TM belt ran
    assert doc["result"]["y1"] == 0 and doc["result"]["y2"] is None  # NaN-free JSON
    assert [m["kind"] for m in doc["markers"]] == ["none", "pre", "failure"]


def test_the_glb_animates_the_object_and_the_barriers(gap_failure):
    import pygltflib
    import trimesh

    data = glb_bytes(gap_failure)
    assert data == glb_bytes(gap_failure)  # deterministic
    gltf = pygltflib.GLTF2.load_from_bytes(data)
    (anim,) = gltf.animations
    nodes = {i: n.name for i, n in enumerate(gltf.nodes)}
    targets = {(nodes[c.target.node], c.target.path) for c in anim.channels}
    assert {("object", "translation"), ("object", "rotation"), ("tu_near_cut", "scale")} <= targets
    times = gltf.accessors[anim.samplers[0].input]
    assert times.count == len(gap_failure.t_s)
    assert times.max[0] == pytest.approx(gap_failure.t_s[-1] - gap_failure.t_s[0], abs=1e-5)
    assert all(n.matrix is None for n in gltf.nodes if n.name in ("object", "tu_near_cut"))
    scene = trimesh.load(io.BytesIO(data), file_type="glb")
    assert len(scene.geometry) >= 20


def test_a_gif_shows_the_replay(gap_failure, tmp_path):
    from PIL import Image

    path = write_gif(gap_failure, tmp_path / "r.gif", fps=4, speed=2.0, width=160, height=90)
    with Image.open(path) as im:
        assert im.n_frames == len(gif_frame_times(gap_failure.duration_s, 4, 2.0))
        first = np.asarray(im.convert("RGB"))
        im.seek(im.n_frames - 1)
        last = np.asarray(im.convert("RGB"))
    assert first.std() > 5 and np.abs(first.astype(int) - last).sum() > 0
    with pytest.raises(InputError):
        gif_frame_times(3.0, 0, 1.0)


def test_a_study_row_replays_with_its_stored_bits(tmp_path):
    db = tmp_path / "s.sqlite"
    plan = StudyPlan(objects=("o1",), theta_step=180, runs=2, seed=5,
                     docking=docking_model("copula", None))  # fmt: skip
    with SQLiteResultStore(db) as store:
        run_study(plan, store, workers=1, max_experiments=2)
        row = next(iter(store.rows()))
    found = study_spec(db, "o1", row["face"], row["conveyor"], row["theta_deg"], row["run"])
    assert found.row == row and found.spec.seed == row["seed"]
    result = record_experiment(found.spec).result
    assert compare_with_row(result, row) == {"same": True, "differences": []}
    tampered = dict(row, t_end_s=row["t_end_s"] + 0.005)
    assert not compare_with_row(result, tampered)["same"]
    with pytest.raises(InputError, match=r"--run must be in 0\.\.1"):
        study_spec(db, "o1", row["face"], row["conveyor"], row["theta_deg"], 2)
    with pytest.raises(InputError, match="not in the study"):
        study_spec(db, "o2", row["face"], row["conveyor"], row["theta_deg"], 0)


def test_gif_captions_say_what_happens_in_words(success, gap_failure):
    from transfertwin.replay import caption_text

    captions = [caption_text(success, i, float(t)) for i, t in enumerate(success.t_s)]
    text = " | ".join(captions)
    for words in ("object placed, settling", "crossing TM → TU", "delivered to the TU",
                  "crossing TU → TM"):  # fmt: skip
        assert words in text, words
    assert captions[-1].split(" · ")[1].startswith("delivered and brought back in")
    assert "OTS" not in text and "non-terminal" not in text and "None" not in text
    last = caption_text(gap_failure, len(gap_failure.t_s) - 1, gap_failure.duration_s)
    assert "failed on the way there: fell below the belts" in last


def test_gif_frames_label_tm_tu_and_the_direction_of_travel(success):
    from transfertwin.replay import render_frames, travel_of

    crossing = [i for i, c in enumerate(success.ots) if c == OTS_CODES["non_terminal"]]
    i = crossing[len(crossing) // 4]
    assert travel_of(success, i) == 1
    (frame,) = render_frames(success, np.array([success.t_s[i]]), width=640, height=360)
    px = np.asarray(frame).astype(int)
    arrow = px[360 - 26 : 360 - 10, int(0.36 * 640) : int(0.64 * 640)]
    red = (np.abs(arrow - [230, 60, 40]).sum(axis=2) < 40).sum()
    assert red > 100, "no travel arrow at the bottom of the frame"
    label = px[0:30, 0:300]
    dark = (np.abs(label - [30, 30, 30]).sum(axis=2) < 10).sum()
    white = (label.min(axis=2) > 230).sum()
    assert dark > 1000 and white > 50, "no caption box at the top left"
