"""`analyze` of a study db whose plan is not finished (issue 30.5): exit 0, a banner in the
report and a line on stderr that says done/planned; a finished plan gets neither."""

from __future__ import annotations

from pathlib import Path

from transfertwin.cli import main
from transfertwin.store import RESULT_COLUMNS, SQLiteResultStore
from transfertwin.study.docking import FixedDockingError
from transfertwin.study.experiment import StudyPlan


def _study(db: Path, keep: int | None) -> StudyPlan:
    """A θ-step 60 plan of o1 (16 states x 2 runs) with the first `keep` rows stored."""
    plan = StudyPlan(objects=("o1",), theta_step=60, runs=2, seed=0, docking=FixedDockingError())
    rows = []
    for st in plan.states():
        for run in range(plan.runs):
            row = dict.fromkeys(RESULT_COLUMNS, None)
            row.update(object_id="o1", face=st.face, conveyor=st.conveyor,
                       theta_deg=st.theta_deg, run=run, seed=run, success=int(run == 0),
                       y1=1, y2=int(run == 0), t_end_s=1.0, status="ok", message="")  # fmt: skip
            rows.append(row)
    with SQLiteResultStore(db) as store:
        store.init_plan(plan.plan_hash, plan.to_json())
        store.put(rows[:keep])
    return plan


def test_partial_study_is_analysed_with_a_banner_and_a_line(tmp_path, capsys):
    plan = _study(tmp_path / "s.sqlite", keep=6)
    assert main(["analyze", str(tmp_path / "s.sqlite"), "--out", str(tmp_path / "rep")]) == 0
    out, err = capsys.readouterr()
    assert out.strip().splitlines() == [str(tmp_path / "rep" / "report.html")]
    line = f"partial study: 6 of {plan.n_experiments} planned experiments done"
    assert line in err and f"3 of {len(plan.states())} planned states" in err
    assert "Partial study" in (tmp_path / "rep" / "report.html").read_text("utf-8")


def test_finished_study_has_no_banner(tmp_path, capsys):
    _study(tmp_path / "s.sqlite", keep=None)
    assert main(["analyze", str(tmp_path / "s.sqlite"), "--out", str(tmp_path / "rep")]) == 0
    assert "partial" not in capsys.readouterr().err
    assert "Partial study" not in (tmp_path / "rep" / "report.html").read_text("utf-8")
