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
    # Summary: what to do, decided level by level, then Alg. 1-4's exact states.
    head = text[summary:figures]
    assert "<h3>What to do</h3>" in head
    assert head.index("<h3>What to do</h3>") < head.index("formal answer")
    # The face is decided (front 11/31 against back 0/30); one run per θ tells no θ apart.
    assert (
        "<b>o1: Put it on its front face, centred across both belts (the only one run), "
        "at any θ.</b>" in head
    )
    assert "Face: decided: front 11/31 against back 0/30" in head
    assert "Yaw θ: does not matter (as far as n shows)" in head
    best = analysis.selection_of("o1").best
    assert "front, both, θ = 105°" in head  # the formal answer, in its table
    assert f"{best.k}/{best.n} = {best.p_hat:.2f}" in head
    assert f"{best.ci_low:.2f}–{best.ci_high:.2f}" in head
    # Captions and headers as HTML, never a literal TeX-like superscript.
    assert "^MA" not in text and "ȳ<sup>MA</sup>" in text


def test_object_without_a_difference_says_nothing_matters(tmp_path: Path) -> None:
    flat = [
        dict(object_id="o7", face=f, conveyor="both", theta_deg=t, success=1)
        for f in ("front", "back")
        for t in range(30, 60)
    ]
    text = write_report(tmp_path, analyze(flat), {}).read_text(encoding="utf-8")
    advice = _advice_of(text, "o7")
    assert "Put it on either face, centred across both belts (the only one run)" in advice
    assert "Avoid" not in text and "warn" not in advice


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
    start = text.index(f"<li><b>{obj}: ")
    return text[start : text.index("</li>\n", start)]


ALL_FRONT = {-120: 8, -60: 8, 0: 8, 60: 8, 120: 8, 180: 8}


def test_a_face_decided_by_the_data_is_advised_without_an_exact_state(tmp_path) -> None:
    """o18: front 64/64, back 14/64: the face is decided, conveyor and θ do not matter."""
    rows = _face_rows("o18", "front", ALL_FRONT)
    rows += _face_rows("o18", "back", {-120: 4, -60: 3, 0: 0, 60: 1, 120: 6, 180: 0})
    text = write_report(tmp_path, analyze(rows), {}).read_text(encoding="utf-8")
    advice = _advice_of(text, "o18")
    assert "<b>o18: Put it on its front face, on any conveyor, at any θ.</b>" in advice
    assert "Face: decided: front 64/64 against back 14/64" in advice
    assert "Conveyor: does not matter (as far as n shows)" in advice
    assert "Yaw θ: does not matter (as far as n shows)" in advice
    assert "turned" not in advice and "not yet" not in text
    summary = text[text.index("id='summary'") : text.index("<figure")]
    assert "Fisher&#x27;s exact test" in summary or "Fisher's exact test" in summary


def test_a_theta_told_apart_on_the_face_is_named(tmp_path) -> None:
    rows = _face_rows("o32", "front", {-120: 0, -60: 0, 0: 0, 60: 8, 120: 1, 180: 0})
    rows += _face_rows("o32", "back", {-120: 0, -60: 0, 0: 0, 60: 1, 120: 0, 180: 0})
    text = write_report(tmp_path, analyze(rows), {}).read_text(encoding="utf-8")
    advice = _advice_of(text, "o32")
    assert "at θ = 60°" in advice
    assert "Yaw θ: decided: 60° 8/8 against" in advice


def test_a_poor_best_placement_is_flagged(tmp_path) -> None:
    rows = _face_rows("o5", "front", {-120: 1, -60: 2, 0: 1, 60: 2, 120: 1, 180: 2})
    rows += _face_rows("o5", "back", {-120: 1, -60: 1, 0: 2, 60: 1, 120: 2, 180: 1})
    text = write_report(tmp_path, analyze(rows), {}).read_text(encoding="utf-8")
    assert "this object needs another way of handling" in _advice_of(text, "o5")


def test_captions_are_in_words_and_the_source_figures_in_footnotes(tmp_path) -> None:
    text = write_report(tmp_path, analyze(rows()), {}).read_text(encoding="utf-8")
    captions = re.findall(r"<figcaption>(.*?)</figcaption>", text, flags=re.S)
    assert len(captions) == 6
    for cap in captions:
        assert "Fig." not in cap and "Alg." not in cap and "<sup>MA" not in cap
        assert re.search(r"<sup><a href='#note-\d'>\d</a></sup>$", cap)
    notes = re.findall(r"<li id='note-(\d)'>After (Fig\. [\d./]+) of the source study", text)
    assert [src for _, src in notes] == ["Fig. 6.22", "Fig. 6.23", "Fig. 6.20/6.21", "Fig. 6.6/6.7"]


def test_real_data_advice_for_o1_is_the_face_not_an_exact_state(tmp_path) -> None:
    """The 191 real experiments: o1 went 25/31 front and 3/23 back, one run a state; the
    advice is the face, and Alg. 1-4's exact pick (front, left, θ = -156°, 1/1) is only in
    the formal table below it."""
    import csv
    from importlib import resources

    with (
        resources.files("transfertwin.data")
        .joinpath("calibration_experiments.csv")
        .open(encoding="utf-8") as fh
    ):
        real = [r for r in csv.DictReader(fh) if r["object_id"] == "o1"]
    analysis = analyze(real)
    text = write_report(tmp_path, analysis, {}).read_text(encoding="utf-8")
    advice = _advice_of(text, "o1")
    assert "<b>o1: Put it on its front face, on any conveyor, at any θ.</b>" in advice
    assert "Face: decided: front 25/31 against back 3/23" in advice
    best = analysis.selection_of("o1").best
    assert (best.face, best.conveyor, best.theta_deg) == ("front", "left", -156)
    assert "-156" not in advice
    formal = text[text.index("formal answer") : text.index("<figure")]
    assert "front, left, θ = -156°" in formal
