"""Self-contained HTML page of a rehearsal (`transfertwin rehearse`, issue 12)."""

from __future__ import annotations

import html
from collections.abc import Mapping
from pathlib import Path

from transfertwin._atomic import write_atomic

__all__ = ["REHEARSAL_REPORT_NAME", "write_rehearsal_report"]

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
        + f"<h2>Configuration</h2><pre>{html.escape(str(doc.get('config', '')))}</pre>"
        "</body></html>\n"
    )
    path = Path(out_dir) / REHEARSAL_REPORT_NAME
    write_atomic(path, page)
    return path
