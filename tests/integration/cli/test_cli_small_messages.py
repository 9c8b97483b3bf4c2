"""Small things a newcomer reads (issue 30, item 9): no Python `None` in the demo table,
sweeps and tunes name their metric and the tune its untuned baseline, the study's summary
rate says it is wall-clock with start-up, and a mesh's first hull decomposition is announced.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest
import trimesh

from transfertwin.cli._calibrate_out import best_line, trial_line
from transfertwin.cli._study import run_summary_line
from transfertwin.cli._transfer import demo_row, hull_notice
from transfertwin.objects import hull_cache_path, load_object
from transfertwin.study.experiment import ExperimentResult


def result(y1: int | None, y2: int | None, success: int | None, status: str = "ok"):
    return ExperimentResult("o1", "front", "both", 30, 0, 0, 0.0, 0.0, 0.0, y1, y2, success,
                            4.2 if status == "ok" else math.nan, status)  # fmt: skip


def test_demo_rows_say_the_outcome_in_words() -> None:
    assert demo_row(result(0, None, 0)) == [
        "front", "both", "30", "failed on the way there: stopped on a belt, short of the goal"
    ]  # fmt: skip
    assert demo_row(result(None, None, None, "unstable"))[3].startswith("not determined")
    assert demo_row(result(1, 1, 1))[3] == "delivered and brought back in 4.20 s"
    assert not any("None" in cell for cell in demo_row(result(0, None, 0)))


def test_a_sweep_trial_names_its_setting_and_metric() -> None:
    assert trial_line("S0", {"physics.solver": "Newton"}, "f05", 0.86) == (
        "S0 physics.solver=Newton: F0.5 0.860"
    )
    assert trial_line("T3", {"mu": 0.540779, "gap_mm": 23.746}, "brier", 0.1234) == (
        "T3 mu=0.5408 gap_mm=23.75: Brier 0.123"
    )
    assert trial_line("B", {}, "recall", 0.5) == "B (base settings): recall 0.500"


def test_the_best_trial_stands_beside_the_untuned_baseline() -> None:
    line = best_line("T7", {"mu": 0.5}, "f05", 0.91, 0.86)
    assert line == "best: T7 mu=0.5: F0.5 0.910; untuned baseline F0.5 0.860 (better)"
    assert best_line("T1", {"mu": 0.5}, "brier", 0.2, 0.1).endswith("Brier 0.100 (not better)")


def test_the_study_summary_rate_is_wall_clock_with_start_up() -> None:
    line = run_summary_line(120, 60.0, 120, 400)
    assert line.startswith("120 new results in 60.0 s (2.00 exp/s wall-clock, including start-up")
    assert line.endswith("120/400 done")


def test_a_meshs_first_hull_decomposition_is_announced_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("TRANSFERTWIN_CACHE", str(tmp_path / "cache"))
    mesh = tmp_path / "part.stl"
    trimesh.creation.box(extents=(0.2, 0.09, 0.08)).export(mesh)
    assert hull_notice("o7") == "" and hull_cache_path("o7") is None
    notice = hull_notice(str(mesh))
    assert notice.startswith("computing convex hulls (CoACD) for part.stl, once; cached by "
                             "content hash in ")  # fmt: skip
    path = hull_cache_path(mesh)
    assert path is not None and not path.exists()
    load_object(mesh)
    assert path.is_file()  # the file load_object wrote is the one announced
    assert hull_notice(str(mesh)) == ""
    assert hull_notice(str(tmp_path / "missing.stl")) == ""  # the experiment reports that
