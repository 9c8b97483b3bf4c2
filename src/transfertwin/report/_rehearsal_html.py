"""Self-contained HTML pages of a rehearsal (`transfertwin rehearse`).

One rehearsal's page reads like the study's report: what was done, what the two scores
mean, what it found in words (held-out F0.5 and Brier score with intervals; with few rows,
that a change is not significant; a plain verdict when calibration made the twin worse),
the figure (`plot_rehearsal`), the tables (the thresholded decisions of ``rehearsal.json``
among them), the plant's hidden truth beside the fitted proxy (`_rehearsal_truth`), and
the configuration folded away. Several K get a curve page (`write_rehearsal_curve_report`).
"""

from __future__ import annotations

import base64
import html
from collections.abc import Mapping, Sequence
from pathlib import Path

from transfertwin._atomic import write_atomic
from transfertwin._errors import InputError
from transfertwin.plant import PLANT_SEED_FILE, PlantTruth, read_plant_seed, reveal_truth
from transfertwin.report._figure import figure_png, new_figure
from transfertwin.report._rehearsal_plots import (
    SMALL_HELD_OUT,
    RehearsalPlot,
    f05_change_text,
    plot_rehearsal,
    rehearsal_plot_data,
)
from transfertwin.report._rehearsal_truth import (
    COUNTER_MEASURE_TEXT,
    metrics_html,
    thresholded_html,
    truth_html,
    verdict_html,
)

__all__ = [
    "REHEARSAL_FIGURE",
    "REHEARSAL_REPORT_NAME",
    "plot_rehearsal_curve",
    "write_rehearsal_curve_report",
    "write_rehearsal_report",
]

REHEARSAL_REPORT_NAME = "report.html"
#: The figure `write_rehearsal_report` writes beside the page.
REHEARSAL_FIGURE = "rehearsal.png"
_STYLE = (
    "body{font-family:sans-serif;margin:2em;max-width:1100px}"
    "table{border-collapse:collapse;margin:1em 0}"
    "td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}"
    "th{background:#eee}td:first-child,th:first-child{text-align:left}"
)


def _cell(value: object) -> str:
    if isinstance(value, float):
        return f"{value:.3f}"
    return html.escape(str(value))


def _table(head: tuple[str, ...], rows: list[list[object]]) -> str:
    th = "".join(f"<th>{html.escape(h)}</th>" for h in head)
    body = "".join("<tr>" + "".join(f"<td>{_cell(c)}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><tr>{th}</tr>{body}</table>"


def _ablation_section(doc: Mapping[str, object]) -> str:
    ablations: Mapping[str, Mapping[str, object]] = doc.get("ablations") or {}  # type: ignore[assignment]
    names: list[str] = list(doc.get("counter_measures", []))  # type: ignore[call-overload]
    items = "".join(
        f"<li><b>{html.escape(m)}</b>: {COUNTER_MEASURE_TEXT.get(m, '')}</li>" for m in names
    )
    out = (
        "<h2>Counter-measures</h2><p>Steps the twin takes against the known causes of "
        "its gap to the plant; this twin runs with "
        + (f"these:</p><ul>{items}</ul>" if names else "none.</p>")
    )
    if not ablations:
        return out
    rows: list[list[object]] = [
        ["all on", doc["f05_after"], "", doc["significant_best"], "", doc["significant_worst"],
         "", doc.get("virtual_unstable", ""), doc.get("virtual_rerun", "")],
    ]  # fmt: skip
    for m, ab in ablations.items():
        rows.append([
            f"without {m}", ab["f05_after"], f"{ab['delta_f05_after']:+.3f}",
            ab["significant_best"], f"{ab['delta_significant_best']:+d}",
            ab["significant_worst"], f"{ab['delta_significant_worst']:+d}",
            ab["virtual_unstable"], ab["virtual_rerun"],
        ])  # fmt: skip
    head = ("twin", "F0.5 after", "Δ", "significant best", "Δ", "significant worst", "Δ",
            "unstable runs", "re-run runs")  # fmt: skip
    return (
        out + "<p>Each ablation repeats calibration, prediction and validation with one "
        "counter-measure switched off (Δ = without − with).</p>" + _table(head, rows)
    )


def _operations_section(doc: Mapping[str, object]) -> str:
    ops: Mapping[str, object] | None = doc.get("operations")  # type: ignore[assignment]
    if not ops:
        return ""
    rows = []
    for policy, label in (("twin", "twin's recommendation"), ("random", "random placement")):
        p: Mapping[str, float] = ops[policy]  # type: ignore[assignment]
        rows.append([
            label, f"{p['k']}/{p['n']}",
            f"{p['success_rate']:.2f} [{p['success_low']:.2f}, {p['success_high']:.2f}]",
            f"{p['ops_per_hour']:.1f} [{p['ops_per_hour_low']:.1f}, {p['ops_per_hour_high']:.1f}]",
        ])  # fmt: skip
    return (
        "<h2>Predictions in operation (Sec. 7.2)</h2>"
        f"<p>{ops['orders']} orders per policy; the twin docks at "
        f"{html.escape(str(ops['station']))}"
        " (smallest mean gap area in the plant's log). Success-rate difference "
        f"{ops['success_diff']:+.2f}, Newcombe 95 % CI [{ops['success_diff_low']:.2f}, "
        f"{ops['success_diff_high']:.2f}]; operations/h ratio {ops['ops_per_hour_ratio']:.2f}. "
        f"An operation takes {ops['handling_s']:g} s handling + the transfer time "
        f"(+ {ops['recovery_s']:g} s recovery after a failure).</p>"
        + _table(
            (
                "policy",
                "successes",
                "success rate [Wilson 95 %]",
                "completed operations/h [bootstrap 95 %]",
            ),
            rows,
        )
    )


def plot_rehearsal_curve(curve: Sequence[Mapping[str, object]]):
    """F0.5 (before/after, always-success) and significant differences against K."""
    fig = new_figure(9, 3.6)
    ax1, ax2 = fig.subplots(1, 2)
    ks = [int(p["calibration_experiments"]) for p in curve]  # type: ignore[call-overload]
    for key, label, style in (("f05_after", "after calibration", "o-"),
                              ("f05_before", "before calibration", "s--"),
                              ("f05_base_rate", "always 'success'", ":")):  # fmt: skip
        (line,) = ax1.plot(ks, [p[key] for p in curve], style, label=label)
        cis = [p.get(f"{key}_ci") for p in curve]
        if all(cis):  # 95 % bootstrap band over the held-out rows
            ax1.fill_between(ks, [c[0] for c in cis], [c[1] for c in cis],  # type: ignore[index]
                             color=line.get_color(), alpha=0.12, lw=0)  # fmt: skip
    ax1.axhline(0.9, color="grey", lw=0.8)
    ax1.set_xlabel("plant calibration experiments K")
    ax1.set_ylabel("F0.5 (held-out plant experiments)")
    ax1.set_ylim(0, 1.02)
    ax1.legend(fontsize=8)
    for key, label, style in (("significant_best", "best state", "o-"),
                              ("significant_worst", "worst state", "s--")):  # fmt: skip
        ax2.plot(ks, [p[key] for p in curve], style, label=label)
    ax2.set_xlabel("plant calibration experiments K")
    ax2.set_ylabel("objects with a significant difference")
    ax2.yaxis.get_major_locator().set_params(integer=True)
    ax2.legend(fontsize=8)
    for ax in (ax1, ax2):
        ax.set_xscale("log")
        ax.set_xticks(ks, labels=[str(k) for k in ks])
        ax.minorticks_off()
    return fig


def _ci_text(ci: object) -> str:
    return f"[{ci[0]:.2f}, {ci[1]:.2f}]" if ci else ""  # type: ignore[index]


def _with_ci(point: Mapping[str, object], key: str) -> str:
    """'0.833 [0.58, 0.99]': a figure and its bootstrap interval (where the doc has one)."""
    return f"{point[key]:.3f} {_ci_text(point.get(f'{key}_ci'))}".strip()


def write_rehearsal_curve_report(doc: Mapping[str, object], out_dir: str | Path) -> Path:
    """``report.html`` (with ``curve.png``) for the ``rehearsal.json`` of several K."""
    curve: Sequence[Mapping[str, object]] = doc["curve"]  # type: ignore[assignment]
    png = figure_png(plot_rehearsal_curve(curve))
    out = Path(out_dir)
    write_atomic(out / "curve.png", png)
    n = len(doc.get("objects", []))  # type: ignore[arg-type]
    rows = [[p["calibration_experiments"], _with_ci(p, "f05_before"), _with_ci(p, "f05_after"),
             _with_ci(p, "f05_base_rate"), _ci_text(p.get("f05_delta_ci")),
             p.get("held_out", ""), f"{p['significant_best']}/{n}", f"{p['significant_worst']}/{n}",
             f"<a href='K{p['calibration_experiments']}/{REHEARSAL_REPORT_NAME}'>K"
             f"{p['calibration_experiments']}</a>"] for p in curve]  # fmt: skip
    head = ("K", "F0.5 before [95 %]", "F0.5 after [95 %]", "always 'success' [95 %]",
            "after - before [95 %]", "held-out rows", "significant best", "significant worst",
            "report")  # fmt: skip
    table = _table(head, [r[:-1] for r in rows])
    links = " ".join(str(r[-1]) for r in rows)
    page = (
        f"<!doctype html><html><head><meta charset='utf-8'><title>Rehearsal curve</title>"
        f"<style>{_STYLE}</style></head><body><h1>How many plant experiments are enough?</h1>"
        f"<p>{html.escape(str(doc.get('note', '')))}</p>"
        f"<img alt='F0.5 and significant differences against K' "
        f"src='data:image/png;base64,{base64.b64encode(png).decode()}'>"
        + table
        + f"<p>Per K: {links}</p></body></html>\n"
    )
    path = out / REHEARSAL_REPORT_NAME
    write_atomic(path, page)
    return path


_PAGE_STYLE = (
    "body{font-family:system-ui,sans-serif;margin:2em auto;max-width:1100px;padding:0 1em;"
    "color:#222;line-height:1.45}h1{margin-bottom:0.1em}.lead{color:#555;margin-top:0.2em}"
    "table{border-collapse:collapse;margin:0.6em 0 1.2em}"
    "td,th{border:1px solid #ccc;padding:4px 8px;text-align:left;vertical-align:top}"
    "th{background:#f0f0f0}.warn{color:#8a4b00}.ok{color:#1d6b1d}"
    "details{margin:0.8em 0;border:1px solid #ddd;border-radius:4px;padding:0.4em 0.8em}"
    "summary{cursor:pointer;font-weight:600}"
    "figure{margin:1.2em 0 2em}figcaption{color:#444;font-size:0.93em;max-width:60em}"
    "img{max-width:100%;display:block}"
)
#: What the fields of ``rehearsal.json`` hold, for the folded glossary.
_FIELDS = (
    ("f05_before, f05_after, f05_base_rate", "held-out F0.5 of the twin before and after "
     "calibration and of the always-success predictor (mean over runs)"),
    ("*_ci", "their 95 % percentile-bootstrap intervals over the held-out rows"),
    ("f05_delta_ci", "after − before on the same resamples (paired)"),
    ("significant_best, significant_worst", "objects whose best/worst state differs "
     "between twin and plant (Newcombe interval of p_V − p_P excludes 0)"),
    ("ablations, delta_*", "twin variants with one counter-measure off; without − with"),
)  # fmt: skip


_CALIBRATION_HEAD = (
    "object", "protrusion depth", "measured mass [kg]", "plant success share (calibration)",
)  # fmt: skip
_STATES_HEAD = (
    "object", "state", "pre-transfer state", "twin k/n", "plant k/n", "p_V − p_P 95 % CI",
    "differ",
)  # fmt: skip


def _what_was_done(doc: Mapping[str, object]) -> str:
    cfg: Mapping[str, object] = doc.get("config") or {}  # type: ignore[assignment]
    objects = ", ".join(map(str, cfg.get("objects", ()))) or "?"  # type: ignore[call-overload]
    runs = html.escape(str(cfg.get("validation_runs", "?")))
    if cfg.get("test_experiments"):
        split = (f"all {doc['training']} calibrated the twin and {doc['held_out']} further "
                 "plant experiments were kept only for scoring")  # fmt: skip
    else:
        split = (f"{doc['training']} of them calibrated the twin and {doc['held_out']} were "
                 "held out, never used in calibration")  # fmt: skip
    return (
        "<p>An emulated plant (its physical parameters hidden from the twin, its seed kept "
        "in plant.secret beside the record) stood in for the real one. It ran "
        f"{html.escape(str(cfg.get('calibration_experiments', '?')))} calibration experiments "
        f"on random pre-transfer states of {html.escape(objects)}; {split}. Calibration fitted "
        "each object's proxy (a protrusion depth per face, with the measured mass) to the "
        "plant's outcomes. The twin predicted the held-out experiments before and after "
        "calibration. Then its full-state prediction chose each object's best and worst "
        f"state, and plant and twin each ran those {runs} times. In all "
        f"{doc['plant_experiments']} plant and {doc['virtual_experiments']} virtual "
        f"experiments, {doc['seconds']} s.</p>"
    )


def _findings(doc: Mapping[str, object], data: RehearsalPlot) -> str:
    base, before, after = data.f05
    n = len(doc.get("objects") or {})  # type: ignore[arg-type]
    best = ", ".join(doc.get("significant_best_objects") or []) or "none"  # type: ignore[arg-type]
    worst = ", ".join(doc.get("significant_worst_objects") or []) or "none"  # type: ignore[arg-type]
    small = data.held_out < SMALL_HELD_OUT
    brier = [doc.get(f"scores_{w}", {}).get("brier") for w in ("before", "after")]  # type: ignore[union-attr]
    brier_text = ""
    if None not in brier:
        brier_text = (f" Brier score: before {float(brier[0]):.3f}, after "
                      f"{float(brier[1]):.3f} (lower is better).")  # fmt: skip
    items = [
        f"Held-out F0.5: before calibration {before.f05:.3f} {_ci_text(before.ci)}, after "
        f"{after.f05:.3f} {_ci_text(after.ci)}; {f05_change_text(data)}.{brier_text}"
        + (" <span class='warn'>Score on more rows (<code>--test-experiments H</code>) "
           "before reading a change into these numbers.</span>" if small else ""),
        f"Always predicting success scores F0.5 {base.f05:.3f} {_ci_text(base.ci)} on these "
        "rows, so the twin is useful only above that.",
        f"Validation of the best/worst states: twin and plant differ significantly for the "
        f"best state of {doc['significant_best']}/{n} objects ({html.escape(best)}) and the "
        f"worst of {doc['significant_worst']}/{n} ({html.escape(worst)}).",
    ]  # fmt: skip
    note = _power_note(data)
    if note:
        items.append(f"<span class='warn'>{html.escape(note)}</span>")
    return (
        "<section id='findings'><h2>What it found</h2>"
        + metrics_html()
        + verdict_html(doc)
        + "<ul>"
        + "".join(f"<li>{t}</li>" for t in items)
        + "</ul></section>"
    )


def _power_note(data: RehearsalPlot) -> str:
    """The validation's power note (study.validation) over the best/worst states."""
    from transfertwin.study.validation import StateComparison, power_note, power_summary

    comps = [
        StateComparison(s.object_id, *s.state.split(" ")[:2], 0, s.n_v, s.k_v, *s.ci_v,
                        s.n_p, s.k_p, *s.ci_p, *s.diff)
        for s in data.states
    ]  # fmt: skip
    return power_note(power_summary(comps)) if comps else ""


def _depth_text(fit: Mapping[str, object]) -> str:
    depth = fit.get("depth_mm")
    if isinstance(depth, Mapping):
        return ", ".join(f"{face} {float(d):g} mm" for face, d in sorted(depth.items()))
    if depth is not None:
        return f"{float(depth):g} mm"  # type: ignore[arg-type]
    return html.escape(str(fit.get("reason", "not calibrated")))


def _calibration_rows(objects: Mapping[str, Mapping[str, object]]) -> list[list[object]]:
    rows: list[list[object]] = []
    for oid, entry in objects.items():
        fit: Mapping[str, object] = entry.get("calibration") or {}  # type: ignore[assignment]
        mass = fit.get("measured_mass_kg")
        share = entry.get("plant_calibration_share")
        rows.append([oid, _depth_text(fit), "" if mass is None else f"{float(mass):.3f}",  # type: ignore[arg-type]
                     "" if share is None else f"{float(share):.2f}"])  # type: ignore[arg-type]  # fmt: skip
    return rows


def _state_rows(data: RehearsalPlot) -> list[list[object]]:
    return [
        [s.object_id, s.kind, s.state, f"{s.k_v}/{s.n_v}", f"{s.k_p}/{s.n_p}",
         f"[{s.diff[0]:.2f}, {s.diff[1]:.2f}]", "yes" if s.significant else "no"]
        for s in data.states
    ]  # fmt: skip


def _config_details(doc: Mapping[str, object]) -> str:
    cfg: Mapping[str, object] = doc.get("config") or {}  # type: ignore[assignment]
    rows = [[k, ", ".join(map(str, v)) if isinstance(v, (list, tuple)) else v]
            for k, v in cfg.items()]  # fmt: skip
    fields = _table(("rehearsal.json field", "holds"), [list(f) for f in _FIELDS])
    return (
        "<details><summary>Configuration</summary>"
        + _table(("setting", "value"), rows)
        + "</details><details><summary>Fields of rehearsal.json</summary>"
        + fields
        + "</details>"
    )


def _truth_beside(doc: Mapping[str, object], out_dir: Path) -> PlantTruth | None:
    """The hidden truth of the plant whose seed lies in ``out_dir/plant.secret`` (None
    without that file or when it cannot be read)."""
    secret = out_dir / PLANT_SEED_FILE
    if not secret.is_file():
        return None
    cfg: Mapping[str, object] = doc.get("config") or {}  # type: ignore[assignment]
    try:
        return reveal_truth(
            read_plant_seed(secret), list(doc.get("objects") or ()),  # type: ignore[call-overload]
            kind=str(cfg.get("plant_kind", "in-class")),
            mismatch_off=tuple(cfg.get("mismatch_off", ()) or ()),  # type: ignore[call-overload]
        )  # fmt: skip
    except InputError:
        return None


def write_rehearsal_report(
    doc: Mapping[str, object], out_dir: str | Path, *, truth: PlantTruth | None = None
) -> Path:
    """Write ``report.html`` (and ``rehearsal.png``) for a ``rehearsal.json`` document:
    what was done, the two scores explained, what it found in words (with the small-n
    caveats and a verdict when calibration made things worse), the figure, the tables,
    the hidden truth beside the fitted proxy, and the configuration folded away.

    Args:
        doc: The ``rehearsal.json`` document.
        out_dir: Where the page goes (the rehearsal's folder).
        truth: The plant's hidden truth; by default revealed from the seed in
            ``out_dir/plant.secret`` when that file is there.
    """
    truth = truth if truth is not None else _truth_beside(doc, Path(out_dir))
    data = rehearsal_plot_data(doc)
    png = figure_png(plot_rehearsal(data))
    scores = [
        ["always 'success'", _with_ci(doc, "f05_base_rate"), "", "", ""],
        *[
            [label, _with_ci(doc, key), s["precision"], s["recall"], s["brier"]]
            for label, key, s in (("twin before calibration", "f05_before", doc["scores_before"]),
                                  ("twin after calibration", "f05_after", doc["scores_after"]))
        ],
    ]  # fmt: skip
    objects: Mapping[str, Mapping[str, object]] = doc["objects"]  # type: ignore[assignment]
    page = (
        f"<!doctype html><html><head><meta charset='utf-8'><title>Rehearsal</title>"
        f"<style>{_PAGE_STYLE}</style></head><body><h1>Rehearsal on an emulated plant</h1>"
        "<p class='lead'>The study's procedure — calibrate, predict, validate — tried "
        "against a plant whose truth is known.</p>"
        + _what_was_done(doc)
        + _findings(doc, data)
        + "<figure><img alt='held-out F0.5 before/after calibration; best/worst states, "
        f"twin vs plant' src='data:image/png;base64,{base64.b64encode(png).decode()}'>"
        "<figcaption>Left: F0.5 on the held-out plant experiments with 95 % bootstrap "
        "intervals. Right: each object's best and worst state as the twin chose them, the "
        "twin's and the plant's success share with 95 % Clopper–Pearson intervals; a red "
        "background where the Newcombe interval of p<sub>V</sub> − p<sub>P</sub> excludes "
        "0.</figcaption></figure>"
        "<h2>Held-out plant experiments</h2>"
        + _table(("predictor", "F0.5 [95 %]", "precision", "recall", "Brier"), scores)
        + thresholded_html(doc)
        + "<h2>Object calibration (proxies, not scans)</h2>"
        + _table(_CALIBRATION_HEAD, _calibration_rows(objects))
        + truth_html(doc, truth)
        + "<h2>Validation: best/worst states</h2>"
        + _table(_STATES_HEAD, _state_rows(data))
        + _ablation_section(doc)
        + _operations_section(doc)
        + _config_details(doc)
        + "</body></html>\n"
    )
    out = Path(out_dir)
    write_atomic(out / REHEARSAL_FIGURE, png)
    path = out / REHEARSAL_REPORT_NAME
    write_atomic(path, page)
    return path
