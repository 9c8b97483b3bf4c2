"""`calibrate evaluate`'s nested options refuse bad input: exit 2, one line, nothing written
(issue 29)."""

from __future__ import annotations

import pytest

from transfertwin.cli import main

BAD = [
    ("zero CV seeds", ["--cv-seeds", "0"]),
    ("one inner fold", ["--inner-folds", "1"]),
    ("negative penalty in the grid", ["--penalties", "0,-0.1"]),
    ("penalty grid not numbers", ["--penalties", "deep"]),
    ("zero resamples", ["--resamples", "0"]),
    ("a candidate folder that is not there", ["--objects", "nowhere,also-nowhere"]),
]


@pytest.mark.parametrize(("case", "extra"), BAD, ids=[c for c, _ in BAD])
def test_evaluate_refuses_bad_nested_options(case, extra, tmp_path, monkeypatch, capfd) -> None:
    monkeypatch.chdir(tmp_path)
    code = main(["calibrate", "evaluate", *extra, "--out", "ev"])
    _, err = capfd.readouterr()
    assert code == 2, (case, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("transfertwin: error: "), err
    assert list(tmp_path.iterdir()) == []
