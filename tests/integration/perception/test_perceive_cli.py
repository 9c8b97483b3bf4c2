"""`transfertwin perceive`: detected AABBs beside the true one, and the picture."""

from __future__ import annotations

import json
from pathlib import Path

from transfertwin.cli import main

ARGS = ["perceive", "--object", "o1", "--face", "front", "--conveyor", "left", "--theta", "0",
        "--size", "160x120", "--json"]  # fmt: skip


def test_perceive_prints_detection_next_to_truth_and_draws(tmp_path: Path, capsys) -> None:
    image = tmp_path / "cloud.png"
    assert main([*ARGS, "--clean", "--dock-error=-4,2,0.5", "--image", str(image)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["conveyor"] == "left" and out["dock_error"]["x_mm"] == -4.0
    assert len(out["scan"]["boxes"]) == 1 and len(out["servo"]["boxes"]) == 1
    assert out["error_mm"] < 10.0
    assert abs(out["servo"]["boxes"][0]["y"] - out["truth"]["y"]) < 0.01
    assert image.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_perceive_same_seed_same_output(capsys) -> None:
    outputs = []
    for _ in range(2):
        assert main([*ARGS, "--seed", "3"]) == 0
        outputs.append(capsys.readouterr().out)
    assert outputs[0] == outputs[1]
