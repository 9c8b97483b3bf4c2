"""Replays of plant experiments (issue 31): from the plant's recording (a camera's poses, the
barriers, the belt commands, the log), drawn in the twin's scene; no hidden value of the plant
in the document; the same plant and row give the same bits. And the MP4 export."""

from __future__ import annotations

import base64
import csv
import dataclasses
import json
import re
import stat

import numpy as np
import pytest

from tests.integration.cps.test_plant_assets import _hidden_numbers, _patterns
from transfertwin._errors import InputError
from transfertwin.objects import load_object
from transfertwin.plant import PLANT_COLUMNS, EmulatedPlant, PlantRequest, write_plant_seed
from transfertwin.replay import (
    OTS_CODES,
    gif_frame_times,
    plant_row,
    plant_source,
    record_plant,
    replay_payload,
    write_mp4,
)

#: The plant: a seed that appears nowhere else in the document.
SEED = 918273
REQUESTS = [PlantRequest("o1", "front", "both", 90), PlantRequest("o3", "back", "both", 45, "TU_B")]


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    """A plant table as a rehearsal writes it (csv.DictWriter, PLANT_COLUMNS)."""
    rows = EmulatedPlant(SEED).run(REQUESTS)
    path = tmp_path_factory.mktemp("plant") / "plant_calibration.csv"
    with path.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, PLANT_COLUMNS, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    return path, rows


@pytest.fixture(scope="module")
def replayed(table):
    found = plant_row(table[0], 1, plant_seed=SEED)  # o3 at TU_B (named): a success
    replay = record_plant(found)
    doc = replay_payload(replay, source=plant_source(found, replay), title="plant")
    return found, replay, doc


def test_the_replay_is_the_logged_experiment_and_draws(table, replayed):
    _, rows = table
    _, replay, doc = replayed
    logged = {k: v for k, v in replay.logged.items() if k != "transfer_time_s"}
    assert logged == rows[1] and replay.logged["transfer_time_s"] > 0
    assert doc["result"]["success"] == rows[1]["success"] == 1
    frames = doc["frames"]
    n = len(frames["t"])
    assert n > 50 and len(frames["pos"]) == len(frames["quat"]) == n
    pos = np.array(frames["pos"])
    assert np.abs(pos[-1] - pos[0]).max() > 0.05 or np.ptp(pos[:, 0]) > 0.2  # it moves
    assert len(set(frames["barriers"])) > 2  # the barriers switch
    assert np.abs(np.array(frames["belts"])).max() > 0  # the belts were commanded
    assert [m["kind"] for m in doc["markers"]] == ["none", "pre", "success", "pre", "success"]
    assert set(frames["ots"]) >= {OTS_CODES["non_terminal"], OTS_CODES["success"]}
    assert doc["spec"]["docking_error_mm_deg"] == [
        rows[1]["dock_err_x_mm"], rows[1]["dock_err_y_mm"], rows[1]["dock_err_theta_deg"]]


def test_the_document_holds_no_hidden_value(replayed):
    """No value drawn for the plant (scene, docking, the object's truth) nor its seed is
    written in the document; the object is the twin's mesh; the motion is on the camera's
    grid (1 mm, 1e-3, 1 ms), so a truth value rounded to 3 decimals (a feature's place in
    x_frac, y_frac) can show up there only by coincidence, and is left out of the search."""
    doc = replayed[2]
    text = json.dumps(doc)
    hidden = [v for v in _hidden_numbers(SEED, ["o3"]) if len(repr(v).split(".")[-1]) > 3]
    assert len(hidden) > 30
    pattern = _patterns(hidden)
    from transfertwin.plant._truth import draw_object, draw_scene

    assert pattern.search(json.dumps(dataclasses.asdict(draw_scene(SEED))))  # it can fail
    assert pattern.search(f"{draw_object(SEED, 'o3').com_offset_m[0] * 1000:.4f}")
    found = pattern.search(text)
    assert found is None, text[max(0, found.start() - 80) : found.end() + 80]
    assert not re.search(rf"(?<![\d.]){SEED}(?![\d.])", text)
    # The object drawn is the twin's mesh of the core, not the plant's.
    twin = load_object("o3").mesh
    verts = np.frombuffer(base64.b64decode(doc["scene"]["object_mesh"]["vertices"]), "<f4")
    assert np.array_equal(verts.reshape(-1, 3), np.asarray(twin.vertices, dtype=np.float32))
    # The motion is on the camera's grid; the scene is the twin's nominal one.
    frames = doc["frames"]
    for key, step in (("pos", 1e-3), ("quat", 1e-3), ("t", 1e-3), ("travel", 1e-3)):
        values = np.asarray(frames[key], dtype=float)
        assert np.allclose(values, np.round(values / step) * step, atol=1e-12), key
    from transfertwin.sim import SceneConfig

    assert doc["spec"]["gap_m"] == SceneConfig().gap_m and doc["spec"]["seed"] is None


def test_the_same_plant_and_row_give_the_same_bits(table, replayed):
    path, doc = table[0], replayed[2]
    again = plant_row(path, 1, plant_seed=SEED)
    assert again.plant.experiments_run == 0
    replay = record_plant(again)
    assert again.plant.experiments_run == 0  # a replay is not an experiment
    second = replay_payload(replay, source=plant_source(again, replay), title="plant")
    assert json.dumps(second) == json.dumps(doc)


def test_a_row_of_another_plant_or_table_is_refused(table, tmp_path):
    path, _ = table
    with pytest.raises(InputError, match="not made by this plant"):
        record_plant(plant_row(path, 1, plant_seed=SEED + 1))
    with pytest.raises(InputError, match="--plant-seed or --plant-seed-file"):
        plant_row(path, 0)
    with pytest.raises(InputError, match=r"--row must be in 0\.\.1"):
        plant_row(path, 2, plant_seed=SEED)
    bad = tmp_path / "t.csv"
    bad.write_text("object_id,face\no1,front\n")
    with pytest.raises(InputError, match="not a plant table"):
        plant_row(bad, 0, plant_seed=SEED)
    seed_file = tmp_path / "plant.secret"
    seed_file.write_text("x\n")
    with pytest.raises(InputError, match="non-negative integer"):
        plant_row(path, 0, plant_seed_file=seed_file)


def test_the_rehearsal_beside_the_table_names_the_plant(table, tmp_path):
    path, _ = table
    copy = tmp_path / "K10" / "plant_calibration.csv"
    copy.parent.mkdir()
    copy.write_bytes(path.read_bytes())
    (tmp_path / "rehearsal.json").write_text(json.dumps({"config": {"objects": ["o3"]}}))
    # The record names the plant's kind, not its seed: that is in plant.secret beside it.
    with pytest.raises(InputError, match=r"no plant\.secret beside it"):
        plant_row(copy, 1)
    seed_file = write_plant_seed(tmp_path / "plant.secret", SEED)
    assert stat.S_IMODE(seed_file.stat().st_mode) == 0o600
    found = plant_row(copy, 1)
    assert found.note == f"the plant of {tmp_path.name}/rehearsal.json (in-class)"
    assert found.plant.kind == "in-class" and str(SEED) not in found.note
    assert plant_row(copy, 1, plant_seed_file=seed_file).note.startswith("the plant of --plant")
    # A plant floor's work folder: its plant.secret beside the table.
    (copy.parent / "plant.secret").write_text(f"{SEED}\n")
    assert plant_row(copy, 1).note == "the plant of K10/plant.secret (in-class)"


def test_a_rehearsal_with_mismatch_parts_off_names_that_plant(table, tmp_path):
    path, _ = table
    copy = tmp_path / "plant_calibration.csv"
    copy.write_bytes(path.read_bytes())
    config = {"plant_kind": "mismatch", "mismatch_off": ["sag", "contact"]}
    (tmp_path / "rehearsal.json").write_text(json.dumps({"config": config}))
    write_plant_seed(tmp_path / "plant.secret", SEED)
    found = plant_row(copy, 0)
    where = f"the plant of {tmp_path.name}/rehearsal.json"
    assert found.note == f"{where} (mismatch without sag, contact)"
    assert repr(found.plant) == (f"EmulatedPlant(seed={SEED}, kind='mismatch', "
                                 "mismatch_off=('contact', 'sag'))")  # fmt: skip
    # another kind or seed named by hand: that plant, whole
    assert plant_row(copy, 0, plant_kind="in-class").plant.kind == "in-class"
    assert "mismatch_off" not in repr(plant_row(copy, 0, plant_seed=SEED + 1).plant)
    config["mismatch_off"] = ["gravity"]
    (tmp_path / "rehearsal.json").write_text(json.dumps({"config": config}))
    with pytest.raises(InputError, match=r"rehearsal\.json: mismatch parts"):
        plant_row(copy, 0)


def test_an_mp4_holds_the_frames(replayed, tmp_path):
    import imageio_ffmpeg

    _, replay, _ = replayed
    path = write_mp4(replay, tmp_path / "r.mp4", fps=5, speed=4.0, width=160, height=90)
    data = path.read_bytes()
    assert data[4:8] == b"ftyp"  # an ISO base media (MP4) file
    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    frames = [np.frombuffer(f, np.uint8).reshape(90, 160, 3) for f in reader]
    assert meta["size"] == (160, 90) and meta["fps"] == 5 and "h264" in meta["codec"]
    assert len(frames) == len(gif_frame_times(replay.duration_s, 5, 4.0))
    assert frames[0].std() > 5 and np.abs(frames[0].astype(int) - frames[-1]).mean() > 1
    again = write_mp4(replay, tmp_path / "s.mp4", fps=5, speed=4.0, width=160, height=90)
    assert again.read_bytes() == data  # the same bits
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.mp4", "s.mp4"]
