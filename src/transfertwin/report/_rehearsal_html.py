"""Self-contained HTML page of a rehearsal (`transfertwin rehearse`, issue 12)."""

from __future__ import annotations

import base64
import html
from collections.abc import Mapping, Sequence
from pathlib import Path

from transfertwin._atomic import write_atomic
from transfertwin.report._figure import figure_png, new_figure

__all__ = [
    "REHEARSAL_REPORT_NAME",
    "plot_rehearsal_curve",
    "write_rehearsal_curve_report",
    "write_rehearsal_report",
]

REHEARSAL_REPORT_NAME = "report.html"
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
    measures = ", ".join(doc.get("counter_measures", [])) or "none"  # type: ignore[arg-type]
    out = f"<h2>Counter-measures</h2><p>The twin runs with: {html.escape(measures)}.</p>"
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


def write_rehearsal_report(doc: Mapping[str, object], out_dir: str | Path) -> Path:
    """Write ``report.html`` for a ``rehearsal.json`` document into `out_dir`."""
    scores = [
        ["always 'success'", doc["f05_base_rate"], "", "", ""],
        *[
            [label, s["f05"], s["precision"], s["recall"], s["brier"]]
            for label, s in (("twin before calibration", doc["scores_before"]),
                             ("twin after calibration", doc["scores_after"]))
        ],
    ]  # fmt: skip
    objects: Mapping[str, Mapping[str, object]] = doc["objects"]  # type: ignore[assignment]
    states, calib = [], []
    for oid, entry in objects.items():
        fit = entry["calibration"]
        calib.append([oid, fit.get("depth_mm", fit.get("reason", "")),
                      entry.get("plant_calibration_share", "")])  # fmt: skip
        for kind in ("best", "worst"):
            st = entry.get(kind)
            if st:
                states.append([
                    oid, kind, f"{st['face']} {st['conveyor']} {st['theta_deg']}°",
                    f"{st['k_v']}/{st['n_v']}", f"{st['k_p']}/{st['n_p']}",
                    f"[{st['diff_low']:.2f}, {st['diff_high']:.2f}]",
                    "yes" if st["significant"] else "no",
                ])  # fmt: skip
    n = len(objects)
    page = (
        f"<!doctype html><html><head><meta charset='utf-8'><title>Rehearsal</title>"
        f"<style>{_STYLE}</style></head><body><h1>Rehearsal on an emulated plant</h1>"
        f"<p>{html.escape(str(doc.get('note', '')))}</p>"
        f"<p>Plant experiments: {doc['plant_experiments']}; virtual experiments: "
        f"{doc['virtual_experiments']}; training rows {doc['training']}, held-out rows "
        f"{doc['held_out']}; {doc['seconds']} s.</p>"
        "<h2>Held-out plant experiments</h2>"
        + _table(("predictor", "F0.5", "precision", "recall", "Brier"), scores)
        + "<h2>Object calibration (proxies, not scans)</h2>"
        + _table(("object", "protrusion depth [mm]", "plant success share (calibration)"), calib)
        + f"<h2>Validation: best/worst states</h2><p>Significant: best "
        f"{doc['significant_best']}/{n}, worst {doc['significant_worst']}/{n} "
        "(Newcombe hybrid score interval of p<sub>V</sub> − p<sub>P</sub>, α = 0.05).</p>"
        + _table(
            (
                "object",
                "state",
                "pre-transfer state",
                "virtual k/n",
                "plant k/n",
                "p_V − p_P 95 % CI",
                "significant",
            ),
            states,
        )
        + _ablation_section(doc)
        + _operations_section(doc)
        + f"<h2>Configuration</h2><pre>{html.escape(str(doc.get('config', '')))}</pre>"
        "</body></html>\n"
    )
    path = Path(out_dir) / REHEARSAL_REPORT_NAME
    write_atomic(path, page)
    return path
