"""What the `transfertwin calibrate` commands print and write beside their results: the
one-line summaries (object mapping, metrics with why one is undefined, trials and the best
one against the untuned baseline), the sensitivity table, and the CSV/JSON/PNG files'
formatting. `_calibrate` parses the options and runs the calibration; it calls these."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

from rich.console import Console
from rich.table import Table

from transfertwin._atomic import write_atomic

__all__ = [
    "best_line",
    "builtin_real",
    "csv_text",
    "json_safe",
    "mapping_line",
    "metric_line",
    "prediction_rows",
    "print_sensitivity",
    "trial_line",
    "undefined_reason",
    "write_trials",
]


def _mapping_note(mapping: dict[str, str]) -> str:
    return ", ".join(f"{k}->{v}" for k, v in sorted(mapping.items()))


_ROW_KEY = ("object_id", "face", "conveyor", "theta_deg", "success", "dock_err_x_mm",
            "dock_err_y_mm", "dock_err_theta_deg")  # fmt: skip


def _row_key(row: dict[str, object]) -> tuple[str, ...]:
    return tuple(str(row.get(k)) for k in _ROW_KEY)


def builtin_real(rows: list[dict[str, object]]) -> bool:
    """Whether the rows are (a part of) the study's real experiments shipped with the
    package: only then are the objects the real cores whose scans are not public."""
    from transfertwin.data import calibration_csv_path
    from transfertwin.store import read_results

    shipped = {_row_key(r) for r in read_results(calibration_csv_path())}
    return bool(rows) and all(_row_key(r) in shipped for r in rows)


def mapping_line(mapping: dict[str, str], shipped: bool) -> str:
    """Which mesh replays which object; the scans remark only for the built-in real cores
    (`shipped`: the rows are those of `builtin_real`)."""
    if shipped:
        return (f"real objects mapped to meshes: {_mapping_note(mapping)} "
                "(the real cores' scans are not public)")  # fmt: skip
    return f"objects replayed with the meshes: {_mapping_note(mapping)}"


#: Why a metric of a confusion matrix is undefined (Eq. A.1-A.4), by the empty denominator.
_NO_PREDICTED = "no predicted successes"
_NO_REAL = "no real successes"


def undefined_reason(confusion, key: str) -> str:
    """Why ``key`` is undefined for one run's confusion matrix ('' when it is defined):
    precision needs predicted successes, recall real ones, F0.5 both."""
    reasons = []
    if key in ("precision", "f05") and confusion.tp + confusion.fp == 0:
        reasons.append((_NO_PREDICTED, "precision"))
    if key in ("recall", "f05") and confusion.tp + confusion.fn == 0:
        reasons.append((_NO_REAL, "recall"))
    if key == "accuracy" and confusion.total == 0:
        reasons.append(("no rows", "accuracy"))
    if not reasons:
        return ""
    why = " and ".join(r for r, _ in reasons)
    what = " and ".join(m for _, m in reasons)
    return f"{why}: {what} undefined"


def metric_line(key: str, summary: dict[str, object], confusions) -> str:
    """One metric's mean ± std over runs, or n/a with the reason when no run defines it."""
    reasons = [undefined_reason(c, key) for c in confusions]
    n_undefined = sum(bool(r) for r in reasons)
    if n_undefined == len(confusions):
        return f"{key:9s} n/a ({reasons[0]})"
    std = summary[key]["std"]
    spread = f" ± {std:.3f}" if math.isfinite(std) else " (one run: no spread)"
    line = f"{key:9s} {summary[key]['mean']:.3f}{spread}"
    if n_undefined:
        first = next(r for r in reasons if r)
        line += f" ({n_undefined} of {len(confusions)} runs n/a, counted as 0: {first})"
    return line


def prediction_rows(rows, result) -> list[dict[str, object]]:
    """predictions.csv: per real row its state, real outcome and each run's virtual one
    (``pred_run<r>``: 1 success, 0 failure or a result that was not 'ok')."""
    keys = ("object_id", "face", "conveyor", "theta_deg", "success")
    return [
        {"row": i, **{k: row[k] for k in keys},
         **{f"pred_run{r.run}": r.predicted[i] for r in result.runs}}
        for i, row in enumerate(rows)
    ]  # fmt: skip


def write_trials(out: Path, records, keys, metric: str, title: str) -> None:
    """trials.csv (one row per `(label, TunedTrial)`: parameters, objective, metrics) and
    scores.png (the objective metric per run)."""
    from transfertwin.report import (
        figure_png,
        plot_score_distribution,
        score_distribution_data,
    )

    buf = io.StringIO()
    metrics = ("f05", "f05_std", "precision", "recall", "accuracy", "brier", "not_ok")
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(["label", *keys, "objective", *metrics, "penalty", "runs"])
    for label, t in records:
        writer.writerow([label, *(t.params.get(k, "") for k in keys), _fmt(t.objective),
                         *(_fmt(t.metrics[m]) for m in metrics), _fmt(t.penalty),
                         len(t.scores)])  # fmt: skip
    write_atomic(out / "trials.csv", buf.getvalue())
    labels = [f"{label} " + ",".join(f"{k}={v}" for k, v in t.params.items())
              for label, t in records]  # fmt: skip
    data = score_distribution_data(labels, [list(t.scores) for _, t in records], metric)
    fig = plot_score_distribution(data)
    fig.suptitle(title)
    write_atomic(out / "scores.png", figure_png(fig))


#: How the CLI names a metric in its lines (the --metric names are file/JSON names).
_METRIC_NAMES = {"f05": "F0.5", "brier": "Brier"}


def _metric_name(metric: str) -> str:
    return _METRIC_NAMES.get(metric, metric)


def _params_text(params: dict[str, object]) -> str:
    """``physics.solver=Newton mu=0.5``; ``(base settings)`` for none."""
    parts = [f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in params.items()]
    return " ".join(parts) or "(base settings)"


def trial_line(label: str, params: dict[str, object], metric: str, score: float) -> str:
    """``S0 physics.solver=Newton: F0.5 0.860``: a trial, its settings and its named score."""
    return f"{label} {_params_text(params)}: {_metric_name(metric)} {score:.3f}"


def best_line(label: str, params: dict[str, object], metric: str, score: float,
              baseline: float) -> str:  # fmt: skip
    """The best trial beside the untuned baseline (the starting profile, unmodified cores)."""
    sign = 1.0 if metric != "brier" else -1.0
    better = "better" if sign * (score - baseline) > 0 else "not better"
    return (
        f"best: {trial_line(label, params, metric, score)}; untuned baseline "
        f"{_metric_name(metric)} {baseline:.3f} ({better})"
    )


def csv_text(rows: list[dict[str, object]]) -> str:
    """CSV of dict rows (the first row's keys), floats to 6 significant digits, NaN empty."""
    buf = io.StringIO()
    keys = list(rows[0]) if rows else []
    writer = csv.DictWriter(buf, fieldnames=keys, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: "" if v is None or (isinstance(v, float) and math.isnan(v))
                         else (f"{v:.6g}" if isinstance(v, float) else v)
                         for k, v in row.items()})  # fmt: skip
    return buf.getvalue()


def _signature_line(label: str, sig: dict[str, dict[str, object]]) -> str:
    parts = [" ".join(f"{k} {_fmt(v)}" for k, v in groups.items()) for groups in sig.values()]
    # object/face pairs are in the JSON; the line keeps face, conveyor and yaw
    parts = parts[:3]
    return f"{label}: " + " | ".join(parts)


def json_safe(value: object) -> object:
    """NaN and infinities become null (strict JSON)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    return value


def _fmt(value: object, spec: str = ".2f") -> str:
    """``format(value, spec)``; "-" for None or a non-finite float (the table cells, the
    signature lines and trials.csv's figures)."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    return format(value, spec)


def print_sensitivity(result, method: str, title: str, console: Console) -> None:
    """`calibrate sensitivity`'s table (Morris indices, or each factor's levels and effects),
    then the real success share and signature and, one at a time, the base profile's."""
    table = Table(title=title)
    if method == "morris":
        for col in ("factor", "range", "mu* share", "± conf", "sigma", "mu* stuck", "mu* F0.5"):
            table.add_column(col, justify="left" if col == "factor" else "right")
        idx = result.indices
        for r in result.ranking("share"):
            f = next(x for x in result.factors if x.name == r["factor"])
            extra = [idx.get(k, {}).get(f.name, {}).get("mu_star") for k in ("stuck_rate", "f05")]
            table.add_row(f.name, f"{f.low:g}..{f.high:g}", _fmt(r["mu_star"], ".3f"),
                          _fmt(r["mu_star_conf"], ".3f"), _fmt(r["sigma"], ".3f"),
                          *(_fmt(v, ".3f") for v in extra))  # fmt: skip
    else:
        for col in ("factor", "levels", "success share by level", "Δ share", "stuck/fail max",
                    "F0.5 best", "Δ F0.5", "AUC best"):  # fmt: skip
            table.add_column(col, justify="left" if col == "factor" else "right")
        for e in result.effects():
            lv = result.of(str(e["factor"]))
            table.add_row(
                str(e["factor"]), " ".join(f"{x.value:g}" for x in lv),
                " ".join(f"{x.share:.2f}" for x in lv), _fmt(e["share_range"]),
                _fmt(e["stuck_share_max"]), _fmt(e["f05_best"], ".3f"),
                _fmt(e["f05_range"], ".3f"), _fmt(e["auc_best"]),
            )  # fmt: skip
    console.print(table)
    real = result.real
    print(f"real success share {real['share']:.2f} [{real['ci_low']:.2f}, {real['ci_high']:.2f}]"
          f" (n {real['n']})")  # fmt: skip
    print(_signature_line("real signature", real["signature"]))
    if method != "morris":
        b = result.base
        print(f"base profile: share {b.share:.2f} [{b.ci_low:.2f}, {b.ci_high:.2f}], "
              f"stuck/fail {_fmt(b.stuck_share)}, F0.5 {b.f05:.3f}, AUC {_fmt(b.auc)}")  # fmt: skip
        print(_signature_line("base signature", b.signature))
