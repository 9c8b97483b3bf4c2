"""Self-contained HTML report of an analysis (Sec. 6.3, 6.6, 6.7), written for an engineer.

One page, in this order:

1. **Summary**: what was analysed, then a "what to do" list decided as an engineer
   decides (`decide_placement`): the face first (k/n per face, Fisher's exact test),
   then the conveyor on the kept face, then θ, each level "decided" with its counts or
   "does not matter (as far as n shows)"; below it, the study's formal answer, one row
   per object with its exact best and worst pre-transfer state of Alg. 1–4 (k/n and the
   95 % Clopper–Pearson interval).
2. **Figures**: best/worst state per object with intervals, then per object the
   full-state plot (one panel per face and conveyor, each state's k/n with its interval)
   and the binary plot of single experiments, each with a caption in words and a
   footnote naming the figure of the source study it follows (Fig. 6.6/6.7, 6.20–6.23).
3. **Details**, folded away (``<details>``): the counts by status, the selection table
   and the parameters as tables grouped by section. Numbers use a general format
   (``1e-08``, ``0.01188``); a nested mapping such as the docking-error model is
   summarised in one line, its full JSON folded once more below it.

Figures are embedded as base64 PNG data URIs, so the page loads no external resource;
the same PNGs are also written to ``out_dir/figures/``.
"""

from __future__ import annotations

import base64
import html
import json
import math
import os
import re
from collections import Counter
from collections.abc import Mapping, Sequence
from pathlib import Path

from transfertwin.report._advice import YMA as _YMA
from transfertwin.report._advice import advice_item, formal_cell
from transfertwin.report._advice import ci_text as _ci
from transfertwin.report._advice import state_short as _state_short
from transfertwin.report._binary_polar import binary_polar_data, plot_binary_polar
from transfertwin.report._figure import figure_png, write_atomic
from transfertwin.report._interval_plot import interval_plot_data, plot_intervals
from transfertwin.report._mesh_convention import mesh_convention_html
from transfertwin.report._partial import StudyProgress, partial_banner_html
from transfertwin.report._polar_full_state import (
    SMOOTH_MIN_N,
    plot_polar_full_state,
    polar_full_state_data,
)
from transfertwin.study.fullstate import (
    AnalysisResult,
    ResultRecord,
    SelectedState,
    decide_placement,
    object_sort_key,
)

__all__ = ["REPORT_NAME", "format_value", "write_report"]

REPORT_NAME = "report.html"
_STYLE = (
    "body{font-family:system-ui,sans-serif;margin:2em auto;max-width:1100px;padding:0 1em;"
    "color:#222;line-height:1.45}"
    "h1{margin-bottom:0.1em}.lead{color:#555;margin-top:0.2em}"
    "table{border-collapse:collapse;margin:0.6em 0 1.2em}"
    "td,th{border:1px solid #ccc;padding:4px 8px;text-align:left;vertical-align:top}"
    "th{background:#f0f0f0}td.num{text-align:right;font-variant-numeric:tabular-nums}"
    ".todo li{margin:0.5em 0}.warn{color:#8a4b00}.ok{color:#1d6b1d}"
    ".banner{background:#fff6e5;border:1px solid #e0b070;border-radius:4px;padding:0.6em 0.9em}"
    "details{margin:0.8em 0;border:1px solid #ddd;border-radius:4px;padding:0.4em 0.8em}"
    "details details{border:none;padding:0;margin:0.2em 0}"
    "summary{cursor:pointer;font-weight:600}"
    "figure{margin:1.2em 0 2em}figcaption{color:#444;font-size:0.93em;max-width:60em}"
    "img{max-width:100%;display:block}"
    "code,pre{background:#f5f5f5;border-radius:3px;padding:1px 4px;font-size:0.92em}"
    "pre{white-space:pre-wrap;max-height:25em;overflow:auto;padding:0.5em}"
)
#: Parameter groups in page order; keys without a known ``group.`` prefix go under "source".
_GROUPS = (
    ("source", "Source"),
    ("plan", "Study plan"),
    ("scene", "Scene"),
    ("physics", "Physics (MuJoCo)"),
    ("layout", "Layout"),
    ("placement", "Placement and settling"),
)


# -- value formatting --------------------------------------------------------------------
def _num(value: float) -> str:
    """A float in a general format: ``1e-08``, ``0.01188``, ``30``; NaN as an en dash."""
    if math.isnan(value):
        return "–"
    return f"{value:.6g}"


def format_value(value: object) -> str:
    """One parameter value as HTML: numbers in a general format, sequences inline,
    mappings summarised (`_summarize_mapping`), everything else escaped text."""
    if value is None:
        return "–"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return _num(value)
    if isinstance(value, Mapping):
        return _summarize_mapping(value)
    if isinstance(value, (list, tuple)):
        if len(value) > 12 or any(isinstance(v, (Mapping, list, tuple)) for v in value):
            return _folded_json(f"{len(value)} entries", value)
        return ", ".join(format_value(v) for v in value)
    return html.escape(str(value))


def _folded_json(summary: str, value: object) -> str:
    text = html.escape(json.dumps(value, indent=1, default=str))
    return f"<details><summary>{html.escape(summary)}</summary><pre>{text}</pre></details>"


_DOCK_COLUMN = {"dock_err_x_mm": "x [mm]", "dock_err_y_mm": "y [mm]", "dock_err_theta_deg": "θ [°]"}


def _marginal_text(m: Mapping[str, object]) -> str:
    col = str(m.get("column", "?"))
    params = m.get("params", {})
    args = ""
    if isinstance(params, Mapping):
        args = ", ".join(f"{k} {_num(float(v))}" for k, v in params.items())  # type: ignore[arg-type]
    bounds = m.get("bounds")
    within = ""
    if isinstance(bounds, (list, tuple)) and len(bounds) == 2:
        within = f" in [{_num(float(bounds[0]))}, {_num(float(bounds[1]))}]"
    name = _DOCK_COLUMN.get(col, col)
    return f"{html.escape(name)}: {html.escape(str(m.get('family', '?')))}({args}){within}"


def _copula_text(d: Mapping[str, object]) -> str:
    marginals = d.get("marginals", [])
    parts = [f"Gaussian copula fitted to {d.get('n_fit', '?')} measured docking errors"]
    if isinstance(marginals, list) and marginals:
        parts.append("marginals " + "; ".join(_marginal_text(m) for m in marginals))
    rho = d.get("correlation")
    if isinstance(rho, list) and len(rho) == 3 and isinstance(marginals, list):
        names = [_DOCK_COLUMN.get(str(m.get("column")), "?").split(" ")[0] for m in marginals]
        pairs = [(0, 1), (0, 2), (1, 2)]
        if len(names) == 3:
            parts.append(
                "correlations "
                + ", ".join(f"ρ({names[i]},{names[j]}) = {rho[i][j]:.2f}" for i, j in pairs)
            )
    return "; ".join(parts)


def _summarize_mapping(d: Mapping[str, object]) -> str:
    """A nested mapping in one readable line, its full JSON folded below.

    Knows the docking-error models (kinds ``copula``, ``copula-per-station``, ``fixed``,
    ``resample``); any other mapping lists its first scalar entries.
    """
    kind = d.get("kind")
    if kind == "copula":
        text = _copula_text(d)
    elif kind == "copula-per-station":
        stations = d.get("stations", [])
        items = [
            f"{html.escape(str(s.get('unit')))} (n = {s.get('count')}): "
            + _copula_text(s.get("copula", {}))
            for s in stations
            if isinstance(s, Mapping)
        ]
        text = "one copula per station: " + " | ".join(items)
    elif kind == "fixed":
        text = (
            f"one fixed docking error: x = {format_value(d.get('x_mm'))} mm, "
            f"y = {format_value(d.get('y_mm'))} mm, θ = {format_value(d.get('theta_deg'))}°"
        )
    elif kind == "resample":
        text = (
            f"resampling {format_value(d.get('n'))} measured docking errors "
            f"from {format_value(d.get('source'))}"
        )
    else:
        scalars = [(k, v) for k, v in d.items() if not isinstance(v, (Mapping, list, tuple))]
        text = ", ".join(f"{html.escape(str(k))} = {format_value(v)}" for k, v in scalars[:6])
        if len(d) > len(scalars[:6]):
            text += f" (+{len(d) - len(scalars[:6])} more)"
    if len(json.dumps(d, default=str)) <= 80:
        return text
    return text + _folded_json("full model (JSON)", d)


# -- tables ------------------------------------------------------------------------------
def _table(head: Sequence[str], rows: Sequence[Sequence[str]], numeric: Sequence[int] = ()) -> str:
    th = "".join(f"<th>{h}</th>" for h in head)
    body = "".join(
        "<tr>"
        + "".join(
            f"<td class='num'>{c}</td>" if i in numeric else f"<td>{c}</td>"
            for i, c in enumerate(r)
        )
        + "</tr>"
        for r in rows
    )
    return f"<table><tr>{th}</tr>{body}</table>"


def _rate(st: SelectedState) -> str:
    return f"{st.k}/{st.n} = {st.p_hat:.2f}"


def _overview_rows(analysis: AnalysisResult) -> list[list[str]]:
    valid = Counter(r.object_id for r in analysis.records if r.status == "ok")
    wins = Counter(r.object_id for r in analysis.records if r.status == "ok" and r.success)
    rows = []
    for sel in analysis.selections:
        obj = sel.object_id
        share = f"{wins[obj] / valid[obj]:.1%}" if valid[obj] else "–"
        rows.append([
            f"<b>{html.escape(obj)}</b>", str(valid[obj]), share,
            _state_short(sel.best), _rate(sel.best), _ci(sel.best),
            _state_short(sel.worst), _rate(sel.worst), _ci(sel.worst),
            formal_cell(sel),
        ])  # fmt: skip
    return rows


_OVERVIEW_HEAD = (
    "object", "valid experiments", "success share",
    "best state", "best k/n", "best 95 % CI",
    "worst state", "worst k/n", "worst 95 % CI", "best and worst told apart?",
)  # fmt: skip


def _summary_section(analysis: AnalysisResult, params: Mapping[str, object]) -> str:
    status = Counter(r.status for r in analysis.records)
    n = len(analysis.records)
    source = params.get("results")
    objects = ", ".join(html.escape(o) for o in analysis.object_ids)
    lead = f"{n} experiments"
    if source is not None:
        lead += f" from <code>{html.escape(str(source))}</code>"
    lead += f"; {status['ok']} valid"
    excluded = [f"{status[s]} {s}" for s in ("invalid", "unstable", "error") if status[s]]
    if excluded:
        lead += " (not counted: " + ", ".join(excluded) + ")"
    run = sum(s.n > 0 for s in analysis.states)
    lead += f"; {run} pre-transfer states run; objects {objects}."
    parts = [
        "<section id='summary'><h2>Summary</h2>",
        f"<p>{lead}</p>",
        "<h3>What to do</h3><ul class='todo'>",
        *(
            advice_item(decide_placement(analysis.states, sel.object_id))
            for sel in analysis.selections
        ),
        "</ul>",
    ]
    if analysis.skipped_objects:
        skipped = ", ".join(html.escape(o) for o in analysis.skipped_objects)
        parts.append(f"<p class='warn'>No valid experiment, so no advice, for: {skipped}.</p>")
    parts.append(
        "<p class='lead'>How the advice is decided: first the face the object rests on, "
        "with the valid experiments of each face pooled; then the conveyor, over the states "
        "of the face kept; then the yaw θ, over the states of the face and conveyors kept. "
        "At each level the option with the highest share is compared with every other by "
        "Fisher's exact test (two-sided, Holm-adjusted over the level, 5 %): an option told "
        "apart below it is avoided, the others are kept. A level where none is told apart "
        "<i>does not matter (as far as n shows)</i>: more runs might still separate its "
        "options. The conveyor is the belt the object starts on (left and right as seen "
        "looking in the direction of travel from the transport module TM to the transfer "
        "unit TU; <i>both</i> = centred across the two belts); θ is the angle of the "
        "object's x axis (for the built-in cores: towards the pinion) from the direction "
        "of travel, counter-clockwise seen from above.</p>"
    )
    parts += [
        "<h3>The study's formal answer: best and worst state (Alg. 1–4)</h3>",
        "<p>The selection of the source study names one exact best and one exact worst "
        f"state per object, chosen on the success rate smoothed over neighbouring angles "
        f"({_YMA}, window {analysis.window}°); k/n and the Clopper–Pearson interval are "
        "those of the state itself. Where the advice above says a level does not matter, "
        "this exact state is one of several that did about as well.</p>",
        _table(_OVERVIEW_HEAD, _overview_rows(analysis), numeric=(1, 2, 4, 5, 7, 8)),
        "</section>",
    ]
    return "\n".join(parts)


def _counts(analysis: AnalysisResult) -> list[list[str]]:
    status = Counter(r.status for r in analysis.records)
    pairs: list[tuple[str, object]] = [("experiments", len(analysis.records))]
    pairs += [(f"status '{s}'", status[s]) for s in ("ok", "invalid", "unstable", "error")]
    pairs.append(("states run (n ≥ 1)", sum(s.n > 0 for s in analysis.states)))
    pairs.append(("objects with a selection", len(analysis.selections)))
    if analysis.skipped_objects:
        pairs.append(("objects without 'ok' results", ", ".join(analysis.skipped_objects)))
    pairs.append(("moving-average window (Eq. 6.27) [°]", analysis.window))
    return [[html.escape(k), format_value(v)] for k, v in pairs]


_SELECTION_HEAD = (
    "object", "state", "series", "face", "conveyor", "θ [°]", _YMA,
    "p̂", "n", "95 % CI", "half window [°]",
)  # fmt: skip


def _selection_row(obj: str, kind: str, st: SelectedState) -> list[str]:
    ci = f"[{st.ci_low:.3f}, {st.ci_high:.3f}]"
    return [
        html.escape(obj), kind, html.escape(st.series), html.escape(st.face),
        html.escape(st.conveyor), str(st.theta_deg), f"{st.y_ma:.3f}", f"{st.p_hat:.3f}",
        str(st.n), ci, str(st.half_window),
    ]  # fmt: skip


def _param_groups(params: Mapping[str, object]) -> list[tuple[str, list[list[str]]]]:
    known = {g for g, _ in _GROUPS}
    grouped: dict[str, list[list[str]]] = {g: [] for g, _ in _GROUPS}
    for key, value in params.items():
        group, _, name = str(key).partition(".")
        if not name or group not in known:
            group, name = "source", str(key)
        grouped[group].append([html.escape(name), format_value(value)])
    return [(title, grouped[g]) for g, title in _GROUPS if grouped[g]]


def _details_section(analysis: AnalysisResult, params: Mapping[str, object]) -> str:
    parts = [
        "<section id='details'><h2>Details</h2>",
        "<details><summary>Counts by status</summary>",
        _table(("quantity", "value"), _counts(analysis), numeric=(1,)),
        "</details>",
        "<details><summary>Selected pre-transfer states (Alg. 1–4)</summary>",
        _table(
            _SELECTION_HEAD,
            [
                _selection_row(sel.object_id, kind, getattr(sel, kind))
                for sel in analysis.selections
                for kind in ("best", "worst")
            ],
            numeric=(5, 6, 7, 8, 10),
        ),
        "</details>",
        "<details id='parameters'><summary>Parameters</summary>",
    ]
    for title, rows in _param_groups(params):
        parts.append(f"<h4>{html.escape(title)}</h4>")
        parts.append(_table(("parameter", "value"), rows))
    if not params:
        parts.append("<p>none given</p>")
    parts.append("</details></section>")
    return "\n".join(parts)


# -- figures -----------------------------------------------------------------------------
def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name)


_HOW_TO_READ = (
    "<p class='lead'>Polar plots: the angle is the yaw θ (0° at the top: the object's x axis "
    "points in the direction of travel TM → TU; counter-clockwise positive, as seen from "
    "above). Angles are signed, θ = -179…180° as in the tables: -150° is 150° clockwise, "
    "never written 210°.</p>"
)


def _sigma_text(sigmas: list[float]) -> str:
    if not sigmas:
        return ""
    lo, hi = min(sigmas), max(sigmas)
    return f"{lo:.3g}°" if math.isclose(lo, hi) else f"{lo:.3g}–{hi:.3g}°"


def _smooth_text(data) -> str:
    sigmas = [p.bandwidth_deg for p in data.panels if p.smoothed]
    if not sigmas:
        return (
            "No smoothed line: no panel has enough runs near any angle "
            f"(at least {SMOOTH_MIN_N:g} under the kernel) for one to say more than its dots."
        )
    return (
        "A dashed grey line, where drawn, smooths the shares over neighbouring angles "
        f"(Gaussian kernel, σ = {_sigma_text(sigmas)}); it is drawn only where at least "
        f"{SMOOTH_MIN_N:g} runs lie under the kernel, and is a guide, not data."
    )


#: (file stem, caption HTML, PNG, the source figure it follows)
FigureItem = tuple[str, str, bytes, str]


def _figures(analysis: AnalysisResult) -> list[FigureItem]:
    """Every figure in page order, with the source figure its caption's footnote cites."""
    out = []
    for which, fig_no in (("best", "Fig. 6.22"), ("worst", "Fig. 6.23")):
        fig = plot_intervals(interval_plot_data(analysis.selections, which))
        caption = (
            f"The <b>{which}</b> state of each object: its success share k/n with the 95 % "
            "Clopper–Pearson interval. A long bar means few experiments."
        )
        out.append((f"intervals_{which}", caption, figure_png(fig), fig_no))
    by_object: dict[str, list[ResultRecord]] = {}
    for rec in analysis.records:
        by_object.setdefault(rec.object_id, []).append(rec)
    selections = {sel.object_id: sel for sel in analysis.selections}
    states = {}
    for st in analysis.states:
        states.setdefault(st.object_id, []).append(st)
    for obj in sorted(by_object, key=object_sort_key):
        name = html.escape(obj)
        if obj in selections:
            data = polar_full_state_data(states[obj], selections[obj], window=analysis.window)
            png = figure_png(plot_polar_full_state(data))
            caption = (
                f"<b>{name}</b>: how often each pre-transfer state succeeded, over the yaw θ. "
                "One panel per face (rows: the face the object rests on) and conveyor "
                "(columns: started on the left belt, centred across both, on the right "
                "belt). Radius: success share, 0 at the centre, 1 on the rim. Each dot is "
                "one state's own k/n, the bar through it its 95 % Clopper–Pearson interval: "
                "a long bar means few runs. The panel title gives the runs it holds; an "
                f"empty panel was not run. {_smooth_text(data)} Star and cross: the exact "
                "best and worst state of the study's selection, at their own k/n; a dotted "
                "spoke marks their angle θ, labelled at the rim."
            )
            out.append((f"full_state_{_safe(obj)}", caption, png, "Fig. 6.20/6.21"))
        png = figure_png(plot_binary_polar(binary_polar_data(by_object[obj], obj)))
        caption = (
            f"<b>{name}</b>: the valid experiments of each state at its yaw θ, "
            "one marker per state coloured by its success share k/n: red = all failed, "
            "yellow = half, green = all succeeded (with few states, k/n is written beside "
            "it). The ring is the conveyor the object started on: outer ring left, middle "
            "ring both, inner ring right."
        )
        out.append((f"binary_{_safe(obj)}", caption, png, "Fig. 6.6/6.7"))
    return out


def _figures_section(out: Path, analysis: AnalysisResult) -> str:
    """The figures, each caption with a footnote naming the source figure it follows."""
    parts = ["<section id='figures'><h2>Figures</h2>", _HOW_TO_READ]
    notes: dict[str, int] = {}
    for stem, caption, png, source in _figures(analysis):
        write_atomic(out / "figures" / f"{stem}.png", png)
        uri = "data:image/png;base64," + base64.b64encode(png).decode("ascii")
        no = notes.setdefault(source, len(notes) + 1)
        ref = f"<sup><a href='#note-{no}'>{no}</a></sup>"
        parts.append(f'<figure><img src="{uri}" alt="{html.escape(stem)}">')
        parts.append(f"<figcaption>{caption}{ref}</figcaption></figure>")
    parts.append("<ol class='notes'>")
    parts += [
        f"<li id='note-{no}'>After {html.escape(src)} of the source study (see the "
        "documentation's Background page for the work and its notation).</li>"
        for src, no in notes.items()
    ]
    parts.append("</ol></section>")
    return "\n".join(parts)


def write_report(
    out_dir: str | os.PathLike[str],
    analysis: AnalysisResult,
    params: Mapping[str, object],
    *,
    progress: StudyProgress | None = None,
) -> Path:
    """Write ``out_dir/report.html`` (and ``out_dir/figures/*.png``) atomically.

    Args:
        out_dir: Output folder, created if needed.
        analysis: From `transfertwin.study.analyze`.
        params: Study parameters to list (e.g. runs, seed, profile), any values; keys
            ``group.name`` (plan, scene, physics, layout, placement) are grouped, the key
            ``results`` names the source in the summary.
        progress: Done/planned of the study the rows come from; a partial study gets a
            banner at the top (`partial_banner_html`).

    Returns:
        Path of the HTML file.
    """
    out = Path(out_dir)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    parts = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
        f"<title>transfertwin report</title><style>{_STYLE}</style></head><body>",
        "<h1>Transfer study report</h1>",
        "<p class='lead'>Will the object make it from the transport module (TM) to the "
        "transfer unit (TU) and back, and how should it be put on the belt?</p>",
        partial_banner_html(progress) if progress is not None else "",
        _summary_section(analysis, params),
        mesh_convention_html(params),
        _figures_section(out, analysis),
    ]
    parts.append(_details_section(analysis, params))
    parts.append("</body></html>\n")
    path = out / REPORT_NAME
    write_atomic(path, "\n".join(parts))
    return path
