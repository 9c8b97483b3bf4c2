"""The HTML report is one self-contained page with tables and embedded PNGs."""

from __future__ import annotations

import re
from pathlib import Path

from transfertwin.report import REPORT_NAME, write_report
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
        "<tr><td>o1</td><td>best</td><td>front-left</td><td>front</td><td>both</td><td>105</td>"
        in text
    )
    assert "<tr><td>o2</td><td>worst</td>" in text
    assert "<td>status &#x27;unstable&#x27;</td><td>1</td>" in text
    assert sorted(p.name for p in (tmp_path / "rep" / "figures").iterdir()) == [
        "binary_o1.png",
        "binary_o2.png",
        "full_state_o1.png",
        "full_state_o2.png",
        "intervals_best.png",
        "intervals_worst.png",
    ]
    assert not list((tmp_path / "rep").rglob("*.tmp"))
