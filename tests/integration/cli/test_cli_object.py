"""`calibrate object` searches the mass distribution with the depths; `calibrate evaluate`
reports the hybrid beside the twin (tiny row set)."""

from __future__ import annotations

import json

import numpy as np

from transfertwin.cli import main
from transfertwin.data import calibration_csv_path
from transfertwin.objects import load_object, read_proxy


def test_calibrate_object_fits_shape_and_mass_and_evaluate_reports_the_hybrid(
    tmp_path, capsys
) -> None:
    lines = calibration_csv_path().read_text().splitlines()
    real = tmp_path / "real.csv"  # o1: front 0, 3 succeed, 1, 4 fail; back 6 fails
    real.write_text("\n".join([lines[0], *(lines[1 + i] for i in (0, 1, 3, 4, 6))]) + "\n")
    out = tmp_path / "fit"
    argv = ["calibrate", "object", "--real", str(real), "--object", "o1", "--depths-mm", "30",
            "--com-shifts-mm", "20", "--runs", "1", "--workers", "1",
            "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "o1 mass: real 0.40" in text and "centre-of-mass shift: +0 mm" in text
    assert "+20 mm" in text and "front half" in text and "not a scan" in text
    spec = read_proxy(out / "o1.proxy.json")
    saved = json.loads((out / "o1.proxy.json").read_text())
    assert saved["com_shift_m"] == spec.com_shift_m in (0.0, 0.02)
    obj = load_object(str(out / "o1.proxy.json"))
    assert abs(obj.mass.com_m[0] - spec.com_shift_m) < 1e-6
    with np.load(out / "o1.candidates.npz") as data:
        assert list(data["shifts_m"]) == [0.0, 0.02] and data["front_p"].shape == (2, 2, 4)
    ev = tmp_path / "ev"
    assert main(["calibrate", "evaluate", "--real", str(real), "--objects", str(out),
                 "--folds", "2", "--repeats", "1", "--cv-seeds", "2", "--resamples", "100",
                 "--out", str(ev)]) == 0  # fmt: skip
    assert "hybrid_cv" in capsys.readouterr().out
    figures = json.loads((ev / "evaluation.json").read_text())
    assert {"twin_cv", "hybrid_cv", "hybrid_in_sample"} <= set(figures)
    assert set(figures["chosen"]["o1"]) == {"shift", "front", "back"}


def test_calibrate_object_searches_the_protrusion_position_on_request(tmp_path, capsys) -> None:
    lines = calibration_csv_path().read_text().splitlines()
    real = tmp_path / "real.csv"
    real.write_text("\n".join([lines[0], *(lines[1 + i] for i in (0, 1, 3, 4, 6))]) + "\n")
    out = tmp_path / "fit"
    argv = ["calibrate", "object", "--real", str(real), "--object", "o1", "--depths-mm", "30",
            "--com-shifts-mm", "0", "--positions", "0.3", "--runs", "1", "--workers", "1",
            "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "30 mm @0.5 " in text and "30 mm @0.3 " in text  # the centre and x 0.3
    spec = read_proxy(out / "o1.proxy.json")
    with np.load(out / "o1.candidates.npz") as data:
        assert list(data["front_positions"]) == [0.5, 0.5, 0.3]
        assert list(data["front_depths_m"]) == [0.0, 0.03, 0.03]
        k = int(data["front_chosen"])
        front = next(p for p in spec.protrusions if p.face == "front")
        assert (front.depth_m, front.x_frac) == (data["front_depths_m"][k],
                                                 data["front_positions"][k])  # fmt: skip
    ev = tmp_path / "ev"
    assert main(["calibrate", "evaluate", "--real", str(real), "--objects", str(out),
                 "--folds", "2", "--repeats", "1", "--position-penalty", "0", "--cv-seeds", "2",
                 "--resamples", "100",
                 "--out", str(ev)]) == 0  # fmt: skip
    figures = json.loads((ev / "evaluation.json").read_text())
    assert set(figures["chosen"]["o1"]) == {"shift", "front", "back"}
