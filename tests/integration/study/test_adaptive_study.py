"""`study run --sampling adaptive` at tiny size: stops early, resumes after an interruption to
the rows of an uninterrupted run (none twice), and `analyze` reads the store unchanged."""

from __future__ import annotations

import json
import math

from transfertwin.cli import main
from transfertwin.store import SQLiteResultStore
from transfertwin.study.experiment import StudyPlan


def _run(db, box_stl, *extra: str) -> int:
    return main(["study", "run", "--db", str(db), "--objects", str(box_stl), "--units", "mm",
                 "--theta-step", "180", "--runs", "6", "--seed", "3", "--workers", "1",
                 "--sampling", "adaptive", "--adaptive-first-runs", "2", "--adaptive-batch", "2",
                 *extra])  # fmt: skip


def _rows(db) -> list[dict]:
    with SQLiteResultStore(db, create=False) as store:
        rows = list(store.rows())
    return [
        {k: "nan" if isinstance(v, float) and math.isnan(v) else v for k, v in r.items()
         if k != "finished_utc"}
        for r in rows
    ]  # fmt: skip


def test_adaptive_study_resumes_without_duplicates_and_analyzes(tmp_path, box_stl):
    cut, clean = tmp_path / "cut.sqlite", tmp_path / "clean.sqlite"
    assert _run(cut, box_stl, "--max-experiments", "19") == 0  # stops inside round 1
    assert len(_rows(cut)) == 19
    assert _run(cut, box_stl) == 0
    assert _run(clean, box_stl) == 0
    resumed, reference = _rows(cut), _rows(clean)
    keys = [(r["object_id"], r["face"], r["conveyor"], r["theta_deg"], r["run"]) for r in resumed]
    assert len(keys) == len(set(keys))
    assert resumed == reference
    assert 8 * 2 < len(resumed) <= 8 * 6  # more than round 0, at most the exhaustive budget
    assert _run(cut, box_stl) == 0 and _rows(cut) == resumed  # finished: a rerun adds nothing

    with SQLiteResultStore(cut, create=False) as store:
        plan = StudyPlan.from_json(store.plan().plan_json)
    assert plan.sampling == "adaptive" and dict(plan.sampling_options)["batch_runs"] == 2
    out = tmp_path / "analysis"
    assert main(["analyze", str(cut), "--out", str(out)]) == 0
    selection = json.loads((out / "selection.json").read_text())
    assert set(selection["box"]) == {"best", "worst"}
