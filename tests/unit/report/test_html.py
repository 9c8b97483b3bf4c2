"""The HTML report is one self-contained page with tables and embedded PNGs."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from transfertwin.report import REPORT_NAME, format_value, write_report
from transfertwin.study.fullstate import analyze


def rows() -> list[dict]:
    out = []
    for obj, good in (("o1", range(100, 111)), ("o2", range(-60, -49))):
        for t in range(90, 121):
            out.append(
                dict(
                    object_id=obj,
                    face="front",
                    conveyor="both",
                    theta_deg=t,
                    success=int(t in good),
                )
            )
        for t in range(-70, -40):
            out.append(
                dict(
                    object_id=obj, face="back", conveyor="both", theta_deg=t, success=int(t in good)
                )
            )
    out.append(
        dict(
            object_id="o2",
            face="back",
            conveyor="both",
            theta_deg=-45,
            success=None,
            status="unstable",
        )
    )
    return out


def test_write_report_is_self_contained(tmp_path: Path) -> None:
    analysis = analyze(rows())
    path = write_report(tmp_path / "rep", analysis, {"runs": 50, "seed": 7, "profile": "fast<&>"})
    assert path == tmp_path / "rep" / REPORT_NAME
    text = path.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>")
    # 2 interval plots + per object a full-state and a binary plot.
    assert text.count('<img src="data:image/png;base64,') == 6
    assert not re.search(r"(src|href)=[\"']?(https?:|//)", text)
    assert "<link" not in text and "<script" not in text
    # Parameters table, HTML-escaped.
    assert "<td>runs</td><td>50</td>" in text and "fast&lt;&amp;&gt;" in text
    # Selection rows: o1 best is the centre of its plateau 100..110 -> θ = 105.
    best_o1 = analysis.selection_of("o1").best
    assert best_o1.theta_deg == 105
    assert (
        "<tr><td>o1</td><td>best</td><td>front-left</td><td>front</td><td>both</td>"
        "<td class='num'>105</td>" in text
    )
    assert "<tr><td>o2</td><td>worst</td>" in text
    assert "<td>status &#x27;unstable&#x27;</td><td class='num'>1</td>" in text
    assert sorted(p.name for p in (tmp_path / "rep" / "figures").iterdir()) == [
        "binary_o1.png",
        "binary_o2.png",
        "full_state_o1.png",
        "full_state_o2.png",
        "intervals_best.png",
        "intervals_worst.png",
    ]
    assert not list((tmp_path / "rep").rglob("*.tmp"))


def docking_model() -> dict:
    """A copula docking model as a study plan stores it (long: candidates per marginal)."""
    cands = [
        {"family": f, "status": "fitted", "bic": 1000.0 + i, "ks_statistic": 0.05,
         "ks_pvalue": 0.5, "reason": ""}
        for i, f in enumerate(("normal", "truncnorm", "beta", "student_t", "gamma", "kde"))
    ]  # fmt: skip
    marginals = [
        {"column": c, "family": "normal", "params": {"loc": loc, "scale": 1.5},
         "bounds": [-20.0, 20.0], "score": {"bic": 1000.0}, "candidates": cands,
         "criterion": {"name": "bic-ks-gate", "ks_alpha": 0.05}}
        for c, loc in (("dock_err_x_mm", -7.3), ("dock_err_y_mm", 2.1), ("dock_err_theta_deg", 1.2))
    ]  # fmt: skip
    rho = [[1.0, -0.62, 0.15], [-0.62, 1.0, 0.3], [0.15, 0.3, 1.0]]
    return {
        "kind": "copula",
        "version": 1,
        "n_fit": 191,
        "correlation": rho,
        "marginals": marginals,
    }


def test_report_opens_with_a_summary_and_folds_readable_parameters(tmp_path: Path) -> None:
    analysis = analyze(rows())
    params = {
        "results": "s.sqlite",
        "plan.docking": docking_model(),
        "plan.runs": 8,
        "physics.tolerance": 1e-8,
        "physics.solimp": [0.9, 0.95, 0.001, 0.5, 2.0],
        "physics.multiccd": True,
        "scene.gap_m": 0.01188,
    }
    text = write_report(tmp_path, analysis, params).read_text(encoding="utf-8")
    summary, figures = text.index("id='summary'"), text.index("<figure")
    details = text.index("<details id='parameters'>")
    assert summary < figures < details
    # No JSON dump before the folded parameters: the long model is summarised in one line.
    assert '{"' not in text[:details] and "correlation" not in text[:details]
    assert '"correlation"' not in text[details:].split("<pre>")[0]
    assert "Gaussian copula fitted to 191 measured docking errors" in text
    assert "x [mm]: normal(loc -7.3, scale 1.5) in [-20, 20]" in text
    assert "ρ(x,y) = -0.62" in text
    # Numbers in a general format, grouped tables.
    assert "<td>tolerance</td><td>1e-08</td>" in text
    assert "<td>gap_m</td><td>0.01188</td>" in text
    assert "<td>solimp</td><td>0.9, 0.95, 0.001, 0.5, 2</td>" in text
    assert "<td>multiccd</td><td>true</td>" in text
    assert "<h4>Physics (MuJoCo)</h4>" in text and "<h4>Study plan</h4>" in text
    # Summary: per object best/worst with k/n and interval, and what to do.
    head = text[summary:figures]
    assert "<h3>What to do</h3>" in head
    assert "<b>o1</b>: put it on its <b>front</b> face" in head
    # One run per state: no front state is told apart from the best at 95 %, so θ = 105°
    # is named as Alg. 1-4's pick, not advised (issue 30.3).
    assert "any front placement does about as well as another" in head
    assert "front, both, θ = 105°" in head and "turned" not in head
    best = analysis.selection_of("o1").best
    assert f"{best.k}/{best.n} = {best.p_hat:.2f}" in head
    assert f"{best.ci_low:.2f}–{best.ci_high:.2f}" in head
    # Captions and headers as HTML, never a literal TeX-like superscript.
    assert "^MA" not in text and "ȳ<sup>MA</sup>" in text


def test_object_without_a_difference_gets_no_best_worst_advice(tmp_path: Path) -> None:
    flat = [
        dict(object_id="o7", face=f, conveyor="both", theta_deg=t, success=1)
        for f in ("front", "back")
        for t in range(30, 60)
    ]
    text = write_report(tmp_path, analyze(flat), {}).read_text(encoding="utf-8")
    assert "<b>o7</b>: no state stands out" in text and "Avoid" not in text


@pytest.mark.parametrize(
    ("value", "shown"),
    [
        (1e-8, "1e-08"),
        (0.01188, "0.01188"),
        (30.0, "30"),
        (0.1 + 0.2, "0.3"),
        (float("nan"), "–"),
        (7, "7"),
        (False, "false"),
        (None, "–"),
        ([0.004, 1.0], "0.004, 1"),
        ("a<b", "a&lt;b"),
        ({"kind": "fixed", "x_mm": -8.5, "y_mm": 2.0, "theta_deg": 1.0},
         "one fixed docking error: x = -8.5 mm, y = 2 mm, θ = 1°"),
    ],
)  # fmt: skip
def test_format_value(value: object, shown: str) -> None:
    assert format_value(value) == shown


def _face_rows(obj: str, face: str, wins: dict[int, int], runs: int = 8) -> list[dict]:
    """θ-step 60 states of one face (left and right at 0 and 180, both elsewhere)."""
    out = []
    for t, k in wins.items():
        for conv in ("left", "right") if t in (0, 180) else ("both",):
            out += [dict(object_id=obj, face=face, conveyor=conv, theta_deg=t,
                         success=int(r < k)) for r in range(runs)]  # fmt: skip
    return out


def _advice_of(text: str, obj: str) -> str:
    start = text.index(f"<li><b>{obj}</b>")
    return text[start : text.index("</li>", start)]


ALL_FRONT = {-120: 8, -60: 8, 0: 8, 60: 8, 120: 8, 180: 8}


def test_issue_30_3_a_tie_on_the_best_face_is_not_presented_as_a_placement(tmp_path) -> None:
    """o18: front 8/8 at every θ, so Alg. 1-4's pick of an angle there is a tie."""
    rows = _face_rows("o18", "front", ALL_FRONT)
    rows += _face_rows("o18", "back", {-120: 4, -60: 3, 0: 0, 60: 1, 120: 6, 180: 0})
    text = write_report(tmp_path, analyze(rows), {}).read_text(encoding="utf-8")
    advice = _advice_of(text, "o18")
    assert "any front placement works" in advice
    assert "only when the best state is separated on its face" in text  # the rule, stated
    assert "turned" not in advice and "clockwise" not in advice
    assert "Avoid the <b>back</b> face" in advice


def test_issue_30_3_a_separated_best_state_gets_its_angle(tmp_path) -> None:
    rows = _face_rows("o32", "front", {-120: 0, -60: 0, 0: 0, 60: 8, 120: 1, 180: 0})
    rows += _face_rows("o32", "back", {-120: 2, -60: 3, 0: 0, 60: 1, 120: 2, 180: 0})
    text = write_report(tmp_path, analyze(rows), {}).read_text(encoding="utf-8")
    advice = _advice_of(text, "o32")
    assert "turned <b>60° counter-clockwise</b> (θ = 60°)" in advice
    assert "any front placement" not in advice


def test_issue_30_3_overlapping_intervals_on_the_face_name_the_pick_as_a_tie(tmp_path) -> None:
    rows = _face_rows("o5", "front", {-120: 5, -60: 6, 0: 7, 60: 8, 120: 6, 180: 5})
    rows += _face_rows("o5", "back", {-120: 0, -60: 0, 0: 0, 60: 0, 120: 0, 180: 0})
    text = write_report(tmp_path, analyze(rows), {}).read_text(encoding="utf-8")
    advice = _advice_of(text, "o5")
    assert "any front placement does about as well as another" in advice
    assert "turned" not in advice and "θ = 60°" in advice  # named as the pick, not advised


def test_separation_rule_compares_clopper_pearson_bounds() -> None:
    """Separated iff some state's upper bound lies below the best's lower bound (8 runs:
    8/8 -> [0.631, 1]; 1/8 -> upper 0.527; 2/8 -> upper 0.651, Clopper-Pearson tables)."""
    from transfertwin.report._advice import best_is_separated
    from transfertwin.study.fullstate import state_table

    def stats(wins: dict[int, int]):
        return state_table(_face_rows("o1", "front", wins))

    best = next(s for s in stats(ALL_FRONT) if s.theta_deg == 60)
    assert not best_is_separated(best, stats(ALL_FRONT))
    assert best_is_separated(best, stats({**ALL_FRONT, 120: 1}))
    assert not best_is_separated(best, stats({**ALL_FRONT, 120: 2}))
