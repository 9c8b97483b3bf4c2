"""`transfertwin dock`: emergent docking errors with the real table's columns; same seed, same
bytes; --image draws the run (issue 14, item 10)."""

from __future__ import annotations

import csv
from pathlib import Path

from transfertwin.cli import main


def test_dock_writes_the_measured_columns_and_repeats_bit_for_bit(tmp_path: Path, capsys) -> None:
    a, b, png = tmp_path / "a.csv", tmp_path / "b.csv", tmp_path / "run.png"
    argv = ["dock", "--station", "C", "--runs", "2", "--seed", "3"]
    assert main([*argv, "--out", str(a), "--image", str(png)]) == 0
    printed = capsys.readouterr().out
    assert "TU_C" in printed and "-2.91" in printed  # the real TU_C x mean beside ours
    assert main([*argv, "--out", str(b)]) == 0
    assert a.read_bytes() == b.read_bytes()
    rows = list(csv.DictReader(a.open()))
    assert len(rows) == 2 and {r["transfer_unit"] for r in rows} == {"TU_C"}
    for r in rows:
        assert r["status"] == "ok"
        for c in ("x_mm", "y_mm", "theta_deg"):
            measured, true = float(r[f"dock_err_{c}"]), float(r[f"true_err_{c}"])
            assert abs(measured - true) < (0.3 if c == "theta_deg" else 1.5)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
