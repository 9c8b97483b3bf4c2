"""The fidelity report: one honest headline of the twin against the real rows.

`fidelity_report` puts together, on the same rows:

- nested CV over many seeds (`held_out`): F0.5 and Brier of the twin and each baseline
  (mean over seeds, their spread, and a row-bootstrap 95 % interval of the seed mean);
- the paired differences twin − (object, face) table, twin − (object, face, conveyor)
  table and twin − logistic, each with a paired row-bootstrap 95 % interval;
- the noise ceiling from near-repeats (`noise_ceiling`);
- leave-one-cell-out figures for (object, face, conveyor) and (object, face) cells, the
  paired difference there resampling whole cells;
- each core's raw simulated share (unshrunk) against the real Clopper–Pearson interval:
  held out (candidates chosen in the row's training fold) and chosen on all rows;
- the choices still made on all rows.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np

from transfertwin._errors import InputError
from transfertwin.study.calibration._ceiling import noise_ceiling
from transfertwin.study.calibration._evaluate import HYBRID_CS, JointCandidates, _assemble
from transfertwin.study.calibration._evaluate import choose_candidates as _choose
from transfertwin.study.calibration._nested import (
    PREDICTORS,
    HeldOut,
    Variant,
    held_out,
    leave_cell_out,
    select_variant,
)
from transfertwin.study.calibration._paired import paired_interval, score_interval

__all__ = ["fidelity_report", "report_lines"]

_PAIRS = ("table_object_face", "table_object_face_conveyor", "logistic", "always_success")


def _scores(ho: HeldOut, y: np.ndarray, clusters: np.ndarray | None, n_resamples: int,
            seed: int) -> dict[str, dict[str, object]]:  # fmt: skip
    ones = np.ones((1, len(y)))
    from transfertwin.study.calibration._paired import brier_of, f05_of

    out: dict[str, dict[str, object]] = {}
    for name in PREDICTORS:
        bits, p = ho.bits[name], ho.p[name]
        per_seed_f = [float(f05_of(b[None], y, ones)[0]) for b in bits]
        per_seed_b = [float(brier_of(q[None], y, ones)[0]) for q in p]
        out[name] = {
            "f05": float(np.mean(per_seed_f)),
            "f05_sd_over_seeds": float(np.std(per_seed_f, ddof=1)) if len(bits) > 1 else 0.0,
            "f05_ci": score_interval("f05", bits, y, clusters=clusters,
                                     n_resamples=n_resamples, seed=seed),
            "brier": float(np.mean(per_seed_b)),
            "brier_sd_over_seeds": float(np.std(per_seed_b, ddof=1)) if len(p) > 1 else 0.0,
            "brier_ci": score_interval("brier", p, y, clusters=clusters,
                                       n_resamples=n_resamples, seed=seed),
        }  # fmt: skip
    return out


def _paired(ho: HeldOut, y: np.ndarray, clusters: np.ndarray | None, n_resamples: int,
            seed: int) -> dict[str, dict[str, object]]:  # fmt: skip
    out = {}
    for other in _PAIRS:
        f, f_ci = paired_interval(
            "f05",
            ho.bits["twin"],
            ho.bits[other],
            y,
            clusters=clusters,
            n_resamples=n_resamples,
            seed=seed,
        )
        b, b_ci = paired_interval(
            "brier",
            ho.p["twin"],
            ho.p[other],
            y,
            clusters=clusters,
            n_resamples=n_resamples,
            seed=seed,
        )
        out[f"twin - {other}"] = {"f05": f, "f05_ci": f_ci, "brier": b, "brier_ci": b_ci}
    return out  # fmt: skip


def _clopper_pearson(k: int, n: int) -> tuple[float, float]:
    from scipy.stats import binomtest

    ci = binomtest(k, n).proportion_ci(confidence_level=0.95, method="exact")
    return float(ci.low), float(ci.high)


def _raw_shares(rows, variants, ho: HeldOut, y: np.ndarray, settings) -> dict[str, object]:
    objects = np.array([str(r["object_id"]) for r in rows])
    every = np.arange(len(y))
    v, pen = select_variant(variants, y, every, settings["penalties"],
                            inner_folds=settings["inner_folds"], seed=0,
                            shift_penalty=settings["shift_penalty"],
                            position_penalty=settings["position_penalty"])  # fmt: skip
    var = variants[v]
    chosen = _choose(var.candidates, var.groups, y, every, pen, settings["shift_penalty"],
                     settings["position_penalty"])  # fmt: skip
    p_all = _assemble(var.candidates, var.groups, chosen)
    shares = {}
    for obj in sorted(set(objects), key=lambda o: (len(o), o)):
        m = objects == obj
        lo, hi = _clopper_pearson(int(y[m].sum()), int(m.sum()))
        held = float(np.mean(ho.twin_raw[:, m]))
        every_rows = float(p_all[m].mean())
        shares[obj] = {"n": int(m.sum()), "real": float(y[m].mean()), "real_ci": (lo, hi),
                       "held_out_raw": held, "held_out_inside": bool(lo <= held <= hi),
                       "all_rows_raw": every_rows,
                       "all_rows_inside": bool(lo <= every_rows <= hi)}  # fmt: skip
    return {"all_rows_choice": {"variant": var.label, "penalty": float(pen)}, "cores": shares}


def _on_all_rows(variants: Sequence[Variant], settings: Mapping[str, object]) -> list[str]:
    notes = [
        "the scene variants themselves: each candidate folder's (or the simulated "
        "profile's) scene — pulley shape and radius, runs per row R, contact settings — and "
        "its depth/shift/position grids were made before this evaluation, looking at these "
        f"rows; the folds choose among the {len(variants)} scene variant(s) given, not among "
        "variants that could have been made",
        f"the grids searched inside the folds: depth penalty {list(settings['penalties'])}, "
        "shrinkage weight 0..0.6, logistic L2 strength C "
        f"{list(HYBRID_CS)}, {settings['inner_folds']} inner folds, selection by inner Brier",
        "the baselines' form: logistic features (one-hot state, sin/cos of theta and 2 theta "
        "per object and face, docking error); rate-table cells (object, face) and (object, "
        "face, conveyor)",
    ]
    joint = [c for v in variants for c in v.candidates.values()
             if isinstance(c, JointCandidates)]  # fmt: skip
    if any(len(c.shifts_m) > 1 for c in joint):
        notes.append(f"the centre-of-mass shift penalty ({settings['shift_penalty']}), fixed")
    if any(c.positions is not None for c in joint):
        notes.append(f"the position penalty ({settings['position_penalty']}), fixed")
    return notes


def fidelity_report(
    rows: Sequence[Mapping[str, object]],
    variants: Sequence[Variant],
    *,
    folds: int = 5,
    seeds: int = 20,
    seed: int = 0,
    inner_folds: int = 3,
    penalties: Sequence[float] = (0.0, 0.02, 0.05),
    shift_penalty: float = 0.0,
    position_penalty: float = 0.0,
    n_resamples: int = 2000,
    on_progress: Callable[[int, int], None] | None = None,
) -> dict[str, object]:
    """Everything of the module doc as plain JSON-ready values."""
    y = np.array([int(r["success"]) for r in rows])
    settings = {"penalties": tuple(float(v) for v in penalties), "inner_folds": inner_folds,
                "shift_penalty": shift_penalty, "position_penalty": position_penalty}  # fmt: skip
    cells3 = len({(r["object_id"], r["face"], r["conveyor"]) for r in rows})
    cells2 = len({(r["object_id"], r["face"]) for r in rows})
    total = seeds * folds + cells3 + cells2
    offset = [0]

    def progress(done: int, _total: int) -> None:
        if on_progress is not None:
            on_progress(offset[0] + done, total)

    ho = held_out(rows, variants, folds=folds, seeds=seeds, seed=seed, inner_folds=inner_folds,
                  penalties=penalties, shift_penalty=shift_penalty,
                  position_penalty=position_penalty, on_progress=progress)  # fmt: skip
    offset[0] = seeds * folds
    loco = {}
    for label, columns in (("object_face_conveyor", ("object_id", "face", "conveyor")),
                           ("object_face", ("object_id", "face"))):  # fmt: skip
        cell_ho, clusters = leave_cell_out(
            rows,
            variants,
            columns,
            seed=seed,
            inner_folds=inner_folds,
            penalties=penalties,
            shift_penalty=shift_penalty,
            position_penalty=position_penalty,
            on_progress=progress,
        )
        offset[0] += cell_ho.folds
        loco[label] = {
            "cells": cell_ho.folds,
            "scores": _scores(cell_ho, y, clusters, n_resamples, seed),
            "paired": _paired(cell_ho, y, clusters, n_resamples, seed),
            "chosen": {f"{k[0]} penalty {k[1]:g}": c for k, c in cell_ho.chosen.items()},
        }
    try:
        ceiling = noise_ceiling(rows, n_resamples=n_resamples, seed=seed).to_dict()
    except InputError as err:  # too few near-repeats on a small row set
        ceiling = {"error": str(err)}
    return {
        "n": len(y), "successes": int(y.sum()), "folds": folds, "seeds": seeds, "seed": seed,
        "inner_folds": inner_folds, "penalties": list(settings["penalties"]),
        "variants": [v.label for v in variants],
        "scores": _scores(ho, y, None, n_resamples, seed),
        "paired": _paired(ho, y, None, n_resamples, seed),
        "ceiling": ceiling,
        "leave_cell_out": loco,
        "chosen_in_folds": {f"{k[0]} penalty {k[1]:g}": c for k, c in ho.chosen.items()},
        "raw_shares": _raw_shares(rows, variants, ho, y, settings),
        "made_on_all_rows": _on_all_rows(variants, settings),
    }  # fmt: skip


def _ci(pair: Sequence[float]) -> str:
    return f"[{pair[0]:.3f}, {pair[1]:.3f}]"


def report_lines(report: Mapping[str, object]) -> list[str]:
    """The report as printed lines (headline table first)."""
    lines = [f"nested CV: {report['n']} real rows, {report['seeds']} CV seeds x "
             f"{report['folds']} folds, every choice inside the training folds "
             f"({report['inner_folds']} inner folds); variants: "
             f"{', '.join(report['variants'])}",
             f"{'predictor':28s} {'F0.5':>6s} {'sd':>6s} {'95% (rows)':>16s} "
             f"{'Brier':>6s} {'95% (rows)':>16s}"]  # fmt: skip
    for name, s in report["scores"].items():
        lines.append(
            f"{name:28s} {s['f05']:6.3f} {s['f05_sd_over_seeds']:6.3f} "
            f"{_ci(s['f05_ci']):>16s} {s['brier']:6.3f} {_ci(s['brier_ci']):>16s}"
        )
    for name, d in report["paired"].items():
        lines.append(f"{name:40s} F0.5 {d['f05']:+.3f} {_ci(d['f05_ci'])}  "
                     f"Brier {d['brier']:+.3f} {_ci(d['brier_ci'])}")  # fmt: skip
    c = report["ceiling"]
    if "error" in c:
        lines.append(f"noise ceiling: not estimated ({c['error']})")
    else:
        lines.append(
            f"noise ceiling: {c['pairs']} near-repeat pairs (same object, face, conveyor, "
            f"|dtheta| <= {c['max_dtheta_deg']:g} deg) over {c['cells']} cells disagree "
            f"{c['disagreement']:.3f} {_ci(c['disagreement_ci'])}; oracle F0.5 "
            f"{c['f05']:.3f} {_ci(c['f05_ci'])}, Brier {c['brier']:.3f} "
            f"{_ci(c['brier_ci'])} (cell bootstrap)"
        )
    for label, block in report["leave_cell_out"].items():
        parts = ", ".join(f"{k} {v['f05']:.3f}/{v['brier']:.3f}"
                          for k, v in block["scores"].items())  # fmt: skip
        d = block["paired"]["twin - table_object_face"]
        a = block["paired"]["twin - always_success"]
        lines.append(f"leave one {label} cell out ({block['cells']} cells), F0.5/Brier: "
                     f"{parts}; twin - (object, face) table F0.5 {d['f05']:+.3f} "
                     f"{_ci(d['f05_ci'])}, twin - always-success {a['f05']:+.3f} "
                     f"{_ci(a['f05_ci'])} (cell bootstrap)")  # fmt: skip
    lines.append(f"chosen in the outer folds: {report['chosen_in_folds']}")
    raw = report["raw_shares"]
    choice = raw["all_rows_choice"]
    for obj, s in raw["cores"].items():
        lines.append(f"{obj}: real {s['real']:.2f} {_ci(s['real_ci'])}; raw simulated share "
                     f"held out {s['held_out_raw']:.3f} "
                     f"({'inside' if s['held_out_inside'] else 'OUTSIDE'}), chosen on all "
                     f"rows ({choice['variant']}) {s['all_rows_raw']:.3f} "
                     f"({'inside' if s['all_rows_inside'] else 'OUTSIDE'})")  # fmt: skip
    lines.append("made on all rows (not repeated inside the folds):")
    lines += [f"  - {note}" for note in report["made_on_all_rows"]]
    return lines
