"""`transfertwin calibrate sensitivity` end to end on two real rows."""

from __future__ import annotations

import csv
import json

from tests.conftest import plain_body_proxy
from transfertwin.cli import main


def test_sensitivity_writes_csv_json_png_and_a_table(tmp_path, capsys):
    out = tmp_path / "sens"
    plain = plain_body_proxy(tmp_path)  # o1's body: its shipped features catch by themselves
    argv = ["calibrate", "sensitivity", "--limit", "2", "--params", "tu_height_offset_m=0:0.04",
            "--levels", "2", "--workers", "1", "--object-map", f"o1={plain}",
            "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "tu_height_offset_m" in text and "real success share" in text
    rows = list(csv.DictReader((out / "sensitivity.csv").open()))
    assert [r["factor"] for r in rows] == ["base", "tu_height_offset_m", "tu_height_offset_m"]
    assert float(rows[2]["share"]) < float(rows[1]["share"])
    payload = json.loads((out / "sensitivity.json").read_text())
    assert payload["method"] == "one-at-a-time" and payload["n_rows"] == 2
    assert payload["effects"][0]["factor"] == "tu_height_offset_m"
    assert (out / "sensitivity.png").read_bytes()[:4] == b"\x89PNG"
