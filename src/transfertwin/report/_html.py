"""Self-contained HTML report of an analysis (Sec. 6.3, 6.6, 6.7).

One page: a parameters table (whatever the caller passes), a summary of the
results table, the best/worst selection per object (Alg. 1–4) with 95 %
Clopper–Pearson intervals, Fig. 6.22/6.23 and per object the full-state plot
(Fig. 6.20/6.21) and the binary plot of single experiments (Fig. 6.6/6.7).
Figures are embedded as base64 PNG data URIs, so the page loads no external
resource; the same PNGs are also written to ``out_dir/figures/``.
"""

from __future__ import annotations

import base64
import html
import json
import os
import re
from collections import Counter
from collections.abc import Mapping
from pathlib import Path

from transfertwin.report._binary_polar import binary_polar_data, plot_binary_polar
from transfertwin.report._figure import figure_png, write_atomic
from transfertwin.report._interval_plot import interval_plot_data, plot_intervals
from transfertwin.report._polar_full_state import plot_polar_full_state, polar_full_state_data
from transfertwin.study.fullstate import (
    AnalysisResult,
    ResultRecord,
    SelectedState,
    object_sort_key,
)

__all__ = ["REPORT_NAME", "write_report"]

REPORT_NAME = "report.html"
_STYLE = (
    "body{font-family:sans-serif;margin:2em;max-width:1100px}"
    "table{border-collapse:collapse;margin:1em 0}"
    "td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}"
    "th{background:#eee}td:first-child,th:first-child{text-align:left}"
    "img{max-width:100%;display:block;margin:0.5em 0}"
)
_SELECTION_HEAD = (
    "object", "state", "series", "face", "conveyor", "θ [°]", "ȳ<sup>MA</sup>",
    "p̂", "n", "95 % CI", "half window [°]",
)  # fmt: skip


def _cell(value: object) -> str:
    if isinstance(value, float):
        return f"{value:.3f}"
    if isinstance(value, (dict, list, tuple)):
        return html.escape(json.dumps(value, default=str))
    return html.escape(str(value))


def _table(head: tuple[str, ...], rows: list[list[str]]) -> str:
    th = "".join(f"<th>{h}</th>" for h in head)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><tr>{th}</tr>{body}</table>"


def _selection_row(obj: str, kind: str, st: SelectedState) -> list[str]:
    ci = f"[{st.ci_low:.3f}, {st.ci_high:.3f}]"
    values = (obj, kind, st.series, st.face, st.conveyor, st.theta_deg, st.y_ma, st.p_hat, st.n)
    return [_cell(v) for v in values] + [ci, _cell(st.half_window)]


def _summary(analysis: AnalysisResult) -> list[list[str]]:
    status = Counter(r.status for r in analysis.records)
    pairs: list[tuple[str, object]] = [("experiments", len(analysis.records))]
    pairs += [(f"status '{s}'", status[s]) for s in ("ok", "invalid", "unstable", "error")]
    pairs.append(("states run (n ≥ 1)", sum(s.n > 0 for s in analysis.states)))
    pairs.append(("objects with a selection", len(analysis.selections)))
    if analysis.skipped_objects:
        pairs.append(("objects without 'ok' results", ", ".join(analysis.skipped_objects)))
    pairs.append(("moving-average window (Eq. 6.27) [°]", analysis.window))
    return [[_cell(k), _cell(v)] for k, v in pairs]


def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name)


def _figures(analysis: AnalysisResult) -> list[tuple[str, str, bytes]]:
    """(file stem, caption, PNG) of every figure, in page order."""
    out = []
    for which, fig_no in (("best", "6.22"), ("worst", "6.23")):
        fig = plot_intervals(interval_plot_data(analysis.selections, which))
        caption = (
            f"p̂ and 95 % Clopper–Pearson interval of each object's {which} state (Fig. {fig_no})"
        )
        out.append((f"intervals_{which}", caption, figure_png(fig)))
    by_object: dict[str, list[ResultRecord]] = {}
    for rec in analysis.records:
        by_object.setdefault(rec.object_id, []).append(rec)
    selections = {sel.object_id: sel for sel in analysis.selections}
    for obj in sorted(by_object, key=object_sort_key):
        if obj in selections:
            data = polar_full_state_data(analysis.series_of(obj), selections[obj])
            png = figure_png(plot_polar_full_state(data))
            out.append(
                (f"full_state_{_safe(obj)}", f"{obj}: smoothed series ȳ^MA (Fig. 6.20)", png)
            )
        png = figure_png(plot_binary_polar(binary_polar_data(by_object[obj], obj)))
        out.append((f"binary_{_safe(obj)}", f"{obj}: single experiments (Fig. 6.7)", png))
    return out


def write_report(
    out_dir: str | os.PathLike[str], analysis: AnalysisResult, params: Mapping[str, object]
) -> Path:
    """Write ``out_dir/report.html`` (and ``out_dir/figures/*.png``) atomically.

    Args:
        out_dir: Output folder, created if needed.
        analysis: From `transfertwin.study.analyze`.
        params: Study parameters to list (e.g. runs, seed, profile), any values.

    Returns:
        Path of the HTML file.
    """
    out = Path(out_dir)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    parts = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
        f"<title>transfertwin report</title><style>{_STYLE}</style></head><body>",
        "<h1>Transfer study report</h1><h2>Parameters</h2>",
        _table(("parameter", "value"), [[_cell(k), _cell(v)] for k, v in params.items()]),
        "<h2>Results table</h2>",
        _table(("quantity", "value"), _summary(analysis)),
        "<h2>Selected pre-transfer states (Alg. 1–4)</h2>",
        _table(
            _SELECTION_HEAD,
            [
                _selection_row(sel.object_id, kind, getattr(sel, kind))
                for sel in analysis.selections
                for kind in ("best", "worst")
            ],
        ),
        "<h2>Figures</h2>",
    ]
    for stem, caption, png in _figures(analysis):
        write_atomic(out / "figures" / f"{stem}.png", png)
        uri = "data:image/png;base64," + base64.b64encode(png).decode("ascii")
        parts.append(f'<figure><img src="{uri}" alt="{html.escape(stem)}">')
        parts.append(f"<figcaption>{html.escape(caption)}</figcaption></figure>")
    parts.append("</body></html>\n")
    path = out / REPORT_NAME
    write_atomic(path, "\n".join(parts))
    return path
