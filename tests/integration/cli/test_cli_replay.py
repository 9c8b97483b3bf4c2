"""`transfertwin replay` (issue 31): writes the replay's files, and refuses bad input with one
line on stderr, exit code 2 and nothing written."""

from __future__ import annotations

import json

import pytest

from transfertwin.cli import main

R = ["replay", "--object", "o1", "--face", "front", "--conveyor", "both", "--theta", "90"]


def test_replay_writes_its_document_and_glb(tmp_path, capsys):
    doc, glb = tmp_path / "r.json", tmp_path / "r.glb"
    code = main([*R, "--gap-mm", "80", "--seed", "3", "--json", str(doc), "--glb", str(glb)])
    out = capsys.readouterr().out
    assert code == 0, out
    head = "o1, front face, both conveyors, θ = 90°, run 0, seed 3: failed on the way there: "
    assert head in out
    assert "None" not in out and "y1" not in out and "simulated time" in out
    data = json.loads(doc.read_text())
    assert data["version"] == 1 and data["markers"][-1]["kind"] == "failure"
    assert data["spec"]["gap_m"] == pytest.approx(0.08)
    assert glb.read_bytes()[:4] == b"glTF"


@pytest.mark.parametrize(
    ("args", "words"),
    [
        ([*R, "--run", "1"], "--run needs --db"),
        ([*R, "--db", "s.sqlite", "--run", "0", "--seed", "2"], "--seed"),
        ([*R, "--db", "missing.sqlite", "--run", "0"], "no such file"),
        ([*R, "--db", "s.csv", "--run", "0"], "a study store"),
        ([*R, "--db", "s.sqlite"], "--db needs --run"),
        ([*R, "--gif", "x.png"], "expected a file ending in .gif"),
        ([*R[:4], "up", *R[5:]], "face"),
        ([*R, "--dock-error", "1,2"], "--dock-error"),
        ([*R, "--port", "70000"], "--port"),
        (["replay", "--object", "o99", *R[3:]], "o99"),
        (["replay", "--face", "front"], "needs --object, --conveyor, --theta"),
        ([*R, "--row", "1"], "--row needs --calibration"),
        (["replay", "--calibration", "nowhere", "--row", "0"], "no metrics.json"),
        (["replay", "--calibration", "nowhere"], "--calibration needs --row"),
        ([*R, "--calibration", "nowhere", "--row", "0"], "comes from its folder"),
        ([*R, "--mp4", "x.gif"], "expected a file ending in .mp4"),
        ([*R, "--mp4", "x.mp4", "--fps", "0"], "--fps must be in 1..50"),
        ([*R, "--plant-seed", "3"], "only with --plant-rows"),
        (["replay", "--plant-rows", "s.csv"], "--plant-rows needs --row"),
        (["replay", "--plant-rows", "s.csv", "--row", "0", "--object", "o1"],
         "comes from its table"),
        (["replay", "--plant-rows", "s.csv", "--row", "0", "--plant-seed", "1"],
         "not a plant table"),
        (["replay", "--plant-rows", "no.csv", "--row", "0", "--plant-seed", "1"], "no such file"),
        (["replay", "--plant-rows", "s.csv", "--row", "0", "--plant-seed", "1",
          "--plant-seed-file", "s.csv"], "give one of them"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(tmp_path, monkeypatch, capsys, args, words):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.csv").write_text("x\n")
    code = main(args)
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and err[0].startswith("transfertwin: error:") and words in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.csv"]


def test_replay_of_a_plant_row_writes_its_document(tmp_path, capsys):
    """A plant table's row, its plant named by a seed file (as a plant floor keeps it)."""
    import csv

    from transfertwin.plant import PLANT_COLUMNS, EmulatedPlant, PlantRequest

    seed = 918273
    rows = EmulatedPlant(seed).run([PlantRequest("o3", "back", "both", 45, "TU_B")])
    table = tmp_path / "plant_test.csv"
    with table.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, PLANT_COLUMNS, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    secret = tmp_path / "plant.secret"
    secret.write_text(f"{seed}\n")
    doc = tmp_path / "p.json"
    code = main(["replay", "--plant-rows", str(table), "--row", "0", "--plant-seed-file",
                 str(secret), "--json", str(doc)])  # fmt: skip
    out = capsys.readouterr().out
    assert code == 0, out
    assert "plant experiment 0: o3 back, both, θ = 45°, TU_B: logged " in out
    assert str(seed) not in out + doc.read_text()
    data = json.loads(doc.read_text())
    assert data["source"]["kind"] == "plant"
    assert data["result"] == {**rows[0], "transfer_time_s": data["result"]["transfer_time_s"]}
