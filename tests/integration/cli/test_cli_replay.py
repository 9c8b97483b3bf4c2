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
    assert "status ok, y1 0, y2 None" in out
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
