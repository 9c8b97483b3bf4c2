"""The rehearsal page's words on its scores and on what calibration recovered.

- `metrics_html`: what F0.5 and the Brier score measure, a sentence each.
- `verdict_html`: a plain verdict when calibration made the twin worse on the held-out
  rows (lower F0.5 or higher Brier score), and why that can happen with a few dozen
  calibration experiments.
- `thresholded_html`: the thresholded block of ``rehearsal.json`` (one decision per row at
  a threshold chosen on the training rows; F0.5 and Brier with intervals and the paired
  after − before differences).
- `truth_html`: the plant's hidden truth (`transfertwin.plant.reveal_truth`, from the seed
  in ``plant.secret``) beside the fitted proxy per core and face, the scene's μ and gap
  beside the twin's, with what calibration recovered and what it missed.
"""

from __future__ import annotations

import html
from collections.abc import Mapping, Sequence

from transfertwin.plant import PlantTruth
from transfertwin.sim import SceneConfig

__all__ = [
    "COUNTER_MEASURE_TEXT",
    "metrics_html",
    "thresholded_html",
    "truth_html",
    "verdict_html",
]

#: What each of the twin's counter-measures does, in words.
COUNTER_MEASURE_TEXT = {
    "mass": "each core is weighed and balanced, and its proxy takes the measured mass and "
    "centre of mass instead of a uniform density",
    "stability": "a run with an implausible event (a launch, an energy jump, deep "
    "penetration) is marked unstable and run again at half the time step",
    "compliance": "the proxy's features yield a little under load, as cable housings and "
    "clips do, instead of being as rigid as the body",
}
#: A fitted depth this close to the hidden one (mm) counts as recovered.
DEPTH_TOLERANCE_MM = 4.0


def metrics_html() -> str:
    """A sentence each on F0.5 and the Brier score."""
    return (
        "<p><b>F0.5</b> scores the twin's yes/no predictions of success against what the "
        "plant did; it weighs precision twice as much as recall, because a predicted "
        "success that then fails costs more than a missed one (1 is perfect). The "
        "<b>Brier score</b> scores the twin's probabilities instead: the mean squared "
        "difference between the predicted chance of success and the outcome, 0 or 1 "
        "(0 is perfect, 0.25 is what always saying 50 % scores; lower is better).</p>"
    )


def _brier(doc: Mapping[str, object], which: str) -> float | None:
    scores = doc.get(f"scores_{which}")
    if isinstance(scores, Mapping) and "brier" in scores:
        return float(scores["brier"])  # type: ignore[arg-type]
    return None


def _split_text(doc: Mapping[str, object]) -> str:
    cfg: Mapping[str, object] = doc.get("config") or {}  # type: ignore[assignment]
    k, train, held = cfg.get("calibration_experiments"), doc.get("training"), doc.get("held_out")
    if cfg.get("test_experiments") or k is None:
        return f"With {train} calibration experiments"
    return f"With {k} calibration experiments ({train} to calibrate, {held} held out to score)"


def verdict_html(doc: Mapping[str, object]) -> str:
    """'Calibration made the twin worse …' with the reasons, or '' when it did not."""
    f_b, f_a = float(doc["f05_before"]), float(doc["f05_after"])  # type: ignore[arg-type]
    b_b, b_a = _brier(doc, "before"), _brier(doc, "after")
    worse = []
    if f_a < f_b:
        worse.append(f"F0.5 fell from {f_b:.3f} to {f_a:.3f}")
    if b_b is not None and b_a is not None and b_a > b_b:
        worse.append(f"the Brier score rose from {b_b:.3f} to {b_a:.3f}")
    if not worse:
        return ""
    cfg: Mapping[str, object] = doc.get("config") or {}  # type: ignore[assignment]
    n_obj = max(1, len(cfg.get("objects", ()) or ()))  # type: ignore[arg-type]
    per_face = int(doc.get("training", 0)) / (2 * n_obj)  # type: ignore[call-overload]
    return (
        "<p class='warn'><b>Calibration made the twin worse on these rows</b>: "
        + " and ".join(worse)
        + f". {_split_text(doc)} for {n_obj} object{'s' if n_obj > 1 else ''}: each "
        "face's protrusion depth was chosen on "
        f"about {per_face:.0f} yes/no outcomes at random states. So few outcomes are "
        "matched about as well by a wrong depth as by the right one: the plant's own "
        "noise (placement scatter, outcomes that flip by chance) can pick the wrong one, "
        "and a proxy tuned to those rows can then predict the held-out rows worse than "
        "the untouched twin did. The held-out rows are few too, so read the change "
        "beside its interval: a change whose interval includes 0 may be chance. More "
        "calibration experiments per object (or fewer candidate depths) make the fit "
        "steadier; the table of hidden truth below shows which faces it got wrong.</p>"
    )


def _ci(ci: object) -> str:
    if isinstance(ci, Sequence) and len(ci) == 2:
        return f" [{float(ci[0]):.2f}, {float(ci[1]):.2f}]"
    return ""


def thresholded_html(doc: Mapping[str, object]) -> str:
    """The ``thresholded`` block: decisions at a threshold, F0.5 and Brier, with intervals."""
    t: Mapping[str, object] | None = doc.get("thresholded")  # type: ignore[assignment]
    if not t:
        return ""
    rows = []
    for which in ("before", "after"):
        rows.append(
            f"<tr><td>twin {which} calibration</td><td>{float(t[f'threshold_{which}']):.2f}</td>"  # type: ignore[arg-type]
            f"<td>{float(t[f'f05_{which}']):.3f}{_ci(t.get(f'f05_{which}_ci'))}</td>"  # type: ignore[arg-type]
            f"<td>{float(t[f'brier_{which}']):.3f}{_ci(t.get(f'brier_{which}_ci'))}</td></tr>"  # type: ignore[arg-type]
        )
    rows.append(
        f"<tr><td>after − before</td><td></td><td>{float(t['f05_delta']):+.3f}"  # type: ignore[arg-type]
        f"{_ci(t.get('f05_delta_ci'))}</td><td>{float(t['brier_delta']):+.3f}"  # type: ignore[arg-type]
        f"{_ci(t.get('brier_delta_ci'))}</td></tr>"
    )
    head = "<tr><th>twin</th><th>threshold</th><th>F0.5 [95 %]</th><th>Brier [95 %]</th></tr>"
    return (
        "<h2>Decisions at a threshold</h2><p>Each held-out row gets the twin's probability "
        "P (the share of its runs that succeeded) and one decision, success if P reaches "
        f"the threshold ({html.escape(str(t.get('threshold_source', '')))}), as "
        "<code>calibrate evaluate</code> does. F0.5 of those decisions and the Brier score "
        "of P, with row-bootstrap 95 % intervals; the last row is the paired difference "
        f"on the same resamples.</p><table>{head}{''.join(rows)}</table>"
    )


def _fitted_depth(entry: Mapping[str, object], face: str) -> float | None:
    fit = entry.get("calibration")
    depth = fit.get("depth_mm") if isinstance(fit, Mapping) else None
    if isinstance(depth, Mapping) and face in depth:
        return float(depth[face])  # type: ignore[arg-type]
    return None


def _depth_verdict(hidden: float, fitted: float | None, candidates: Sequence[float]) -> str:
    if fitted is None:
        return "not calibrated"
    if abs(fitted - hidden) <= DEPTH_TOLERANCE_MM:
        return "<span class='ok'>recovered</span>"
    near = min(candidates, key=lambda c: abs(c - hidden))
    miss = f"missed by {abs(fitted - hidden):.0f} mm"
    if abs(near - hidden) > DEPTH_TOLERANCE_MM:
        tol = f"{DEPTH_TOLERANCE_MM:g} mm"
        return f"<span class='warn'>{miss}</span> (no candidate depth within {tol})"
    return f"<span class='warn'>{miss}</span> (the candidate {near:g} mm was closer)"


def _object_rows(doc: Mapping[str, object], truth: PlantTruth) -> list[str]:
    objects: Mapping[str, Mapping[str, object]] = doc.get("objects") or {}  # type: ignore[assignment]
    cfg: Mapping[str, object] = doc.get("config") or {}  # type: ignore[assignment]
    cands = sorted({0.0, *(float(d) for d in cfg.get("depths_mm", ()) or ())})  # type: ignore[union-attr]
    rows = []
    for oid, entry in objects.items():
        hidden = truth.object(oid)
        for face, depth in hidden.depth_mm:
            fitted = _fitted_depth(entry, face)
            fx, fy = dict(hidden.feature_at)[face]
            where = "plain face" if depth == 0 else f"at x {fx:.2f}, y {fy:.2f} of the face"
            rows.append(
                f"<tr><td>{html.escape(oid)}</td><td>{face}</td><td>{depth:.1f} mm "
                f"({where})</td><td>{'–' if fitted is None else f'{fitted:g} mm'}</td>"
                f"<td>{_depth_verdict(depth, fitted, cands)}</td></tr>"
            )
    return rows


def _mass_rows(doc: Mapping[str, object], truth: PlantTruth) -> list[str]:
    objects: Mapping[str, Mapping[str, object]] = doc.get("objects") or {}  # type: ignore[assignment]
    rows = []
    for oid in objects:
        hidden = truth.object(oid)
        fit = objects[oid].get("calibration") or {}
        mass, com = fit.get("measured_mass_kg"), fit.get("measured_com_mm")  # type: ignore[union-attr]
        shown = "not weighed" if mass is None else f"{float(mass):.3f} kg"
        com_text = "" if com is None else ", ".join(f"{float(v):.1f}" for v in com)
        rows.append(
            f"<tr><td>{html.escape(oid)}</td><td>{hidden.mass_kg:.3f} kg</td><td>{shown}</td>"
            f"<td>{', '.join(f'{v:.1f}' for v in hidden.com_mm)}</td><td>{com_text}</td></tr>"
        )
    return rows


def _scene_rows(doc: Mapping[str, object], truth: PlantTruth) -> list[str]:
    tuned: Mapping[str, object] | None = doc.get("tuned_scene")  # type: ignore[assignment]
    default = SceneConfig()
    s = truth.scene
    rows = []
    for name, hidden, key, unit, twin_default in (
        ("friction μ", s.mu, "mu", "", default.mu),
        ("gap", s.gap_mm, "gap_mm", " mm", default.gap_m * 1000.0),
    ):
        if tuned and key in tuned:
            twin = f"{float(tuned[key]):.3g}{unit} (tuned)"  # type: ignore[arg-type]
        else:
            twin = f"not tuned (the default scene has {twin_default:.3g}{unit})"
        rows.append(f"<tr><td>{name}</td><td>{hidden:.3g}{unit}</td><td>{twin}</td></tr>")
    rows += [
        f"<tr><td>belt speed error</td><td>{s.belt_speed_error_pct:+.1f} %</td>"
        "<td>not modelled (the twin's belts run at the commanded speed)</td></tr>",
        f"<tr><td>outcomes flipped by chance</td><td>{s.flip_share:.1%}</td>"
        "<td>not modelled: noise no twin can predict</td></tr>",
    ]
    return rows


def truth_html(doc: Mapping[str, object], truth: PlantTruth | None) -> str:
    """The hidden truth beside the fitted proxy (empty note when the seed is unknown)."""
    if truth is None:
        return (
            "<section id='truth'><h2>Hidden truth and fitted proxy</h2><p>The plant's seed "
            "(<code>plant.secret</code>) is not beside this record, so its hidden truth "
            "cannot be shown.</p></section>"
        )
    struct = ""
    if truth.structural_parts:
        struct = (
            "<p class='warn'>This plant is of kind 'mismatch': besides the values below it "
            "holds structural parts no proxy of the twin's class can represent ("
            + html.escape(", ".join(truth.structural_parts))
            + "); part of the gap is out of calibration's reach.</p>"
        )
    return (
        "<section id='truth'><h2>Hidden truth and fitted proxy</h2><p>The plant's seed, kept in "
        "<code>plant.secret</code> beside this record, draws every hidden value; here they "
        "stand beside what calibration fitted. A proxy holds one box feature under each "
        "face's centre with a depth from the candidate list; the plant's feature may sit "
        "anywhere under the face. A depth within "
        f"{DEPTH_TOLERANCE_MM:g} mm of the hidden one counts as recovered.</p>"
        + struct
        + "<table><tr><th>object</th><th>face</th><th>hidden feature depth</th>"
        "<th>fitted proxy depth</th><th>calibration</th></tr>"
        + "".join(_object_rows(doc, truth))
        + "</table><table><tr><th>object</th><th>true mass</th><th>measured mass</th>"
        "<th>true centre of mass [mm]</th><th>measured [mm]</th></tr>"
        + "".join(_mass_rows(doc, truth))
        + "</table><table><tr><th>scene</th><th>hidden</th><th>twin</th></tr>"
        + "".join(_scene_rows(doc, truth))
        + "</table></section>"
    )
