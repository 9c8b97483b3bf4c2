"""What a rehearsal (`transfertwin rehearse`) found, as data, words and one figure.

`rehearsal_plot_data` reads a ``rehearsal.json`` document into `RehearsalPlot`: the held-out
F0.5 of the always-success predictor and of the twin before and after calibration, each
with its 95 % bootstrap interval, and every object's best and worst state as the twin
(p̂_V) and the plant (p̂_P) ran it, with Clopper–Pearson intervals (Eq. 6.27) and whether
the Newcombe interval of p_V − p_P excludes 0 (Sec. 6.7). `f05_change_text` says in words
whether calibration changed F0.5 by more than the held-out rows can resolve; the CLI and
the HTML page both use it. `plot_rehearsal` draws the data (left: F0.5, right: the
validation), nothing more.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib.figure import Figure

from transfertwin._errors import InputError
from transfertwin.report._figure import FAILURE_COLOR, new_figure
from transfertwin.study.fullstate import clopper_pearson
from transfertwin.study.validation import VirtualPhysicalShares

__all__ = [
    "SMALL_HELD_OUT",
    "F05Point",
    "RehearsalPlot",
    "ValidatedState",
    "f05_change_text",
    "plot_rehearsal",
    "rehearsal_plot_data",
]

#: Below this many held-out rows the page and the CLI call the F0.5 figures small-n.
SMALL_HELD_OUT = 30
_F05 = (
    ("f05_base_rate", "always 'success'"),
    ("f05_before", "twin before calibration"),
    ("f05_after", "twin after calibration"),
)
_VIRTUAL_COLOR = "#1f77b4"
_PLANT_COLOR = "#ff7f0e"


@dataclass(frozen=True)
class F05Point:
    """One predictor's held-out F0.5 and its 95 % percentile-bootstrap interval (or None)."""

    label: str
    f05: float
    ci: tuple[float, float] | None


@dataclass(frozen=True)
class ValidatedState(VirtualPhysicalShares):
    """An object's best or worst state run by twin and plant (Sec. 6.7); its shares p̂_V
    and p̂_P as a `StateComparison` has them (`VirtualPhysicalShares`).

    Attributes:
        object_id, kind: The object and ``'best'`` or ``'worst'``.
        state: ``'front both -90°'``.
        k_v, n_v, k_p, n_p: Successes and runs of twin (V) and plant (P).
        ci_v, ci_p: Clopper–Pearson 95 % intervals of p_V and p_P (Eq. 6.27).
        diff: Newcombe hybrid score interval of p_V − p_P.
        significant: Whether ``diff`` excludes 0.
    """

    object_id: str
    kind: str
    state: str
    k_v: int
    n_v: int
    k_p: int
    n_p: int
    ci_v: tuple[float, float]
    ci_p: tuple[float, float]
    diff: tuple[float, float]
    significant: bool


@dataclass(frozen=True)
class RehearsalPlot:
    """Plot data of a rehearsal: held-out F0.5 (`F05Point`) and the validated states."""

    f05: tuple[F05Point, ...]
    held_out: int
    delta_ci: tuple[float, float] | None
    states: tuple[ValidatedState, ...]


def _pair(value: object) -> tuple[float, float] | None:
    if not value:
        return None
    low, high = value  # type: ignore[misc]
    return float(low), float(high)


def _state(oid: str, kind: str, st: Mapping[str, object]) -> ValidatedState:
    k_v, n_v, k_p, n_p = (int(st[k]) for k in ("k_v", "n_v", "k_p", "n_p"))  # type: ignore[call-overload]
    cv, cp = clopper_pearson(k_v, n_v), clopper_pearson(k_p, n_p)
    return ValidatedState(
        oid, kind, f"{st['face']} {st['conveyor']} {st['theta_deg']}°", k_v, n_v, k_p, n_p,
        (cv.low, cv.high), (cp.low, cp.high),
        (float(st["diff_low"]), float(st["diff_high"])), bool(st["significant"]),  # type: ignore[arg-type]
    )  # fmt: skip


def rehearsal_plot_data(doc: Mapping[str, object]) -> RehearsalPlot:
    """Collect the figures of one ``rehearsal.json`` document (pure).

    Raises:
        InputError: If the document lacks the F0.5 figures.
    """
    missing = [k for k, _ in _F05 if k not in doc]
    if missing:
        raise InputError(f"rehearsal document without {', '.join(missing)}")
    f05 = tuple(F05Point(label, float(doc[k]), _pair(doc.get(f"{k}_ci"))) for k, label in _F05)  # type: ignore[arg-type]
    objects: Mapping[str, Mapping[str, object]] = doc.get("objects") or {}  # type: ignore[assignment]
    states = tuple(
        _state(oid, kind, entry[kind])  # type: ignore[arg-type]
        for oid, entry in objects.items()
        for kind in ("best", "worst")
        if entry.get(kind)
    )
    return RehearsalPlot(f05, int(doc.get("held_out", 0)), _pair(doc.get("f05_delta_ci")), states)  # type: ignore[call-overload]


def f05_change_text(data: RehearsalPlot) -> str:
    """Whether calibration changed held-out F0.5 by more than the rows resolve, in words.

    E.g. ``"after − before −0.091, 95 % CI [−0.30, 0.07]: not significant (the interval
    holds 0); 12 held-out rows are few, every F0.5 here is uncertain by about ±0.2"``.
    """
    before, after = data.f05[1].f05, data.f05[2].f05
    text = f"after − before {after - before:+.3f}"
    if data.delta_ci is None:
        verdict = "no interval recorded"
    else:
        low, high = data.delta_ci
        holds_zero = low <= 0.0 <= high
        verdict = f"95 % CI [{low:.2f}, {high:.2f}]: " + (
            "not significant (the interval holds 0)" if holds_zero else "significant"
        )
    text += f", {verdict}"
    if data.held_out < SMALL_HELD_OUT:
        widths = [p.ci[1] - p.ci[0] for p in data.f05 if p.ci]
        spread = (
            f", every F0.5 here is uncertain by about ±{np.mean(widths) / 2:.1f}" if widths else ""
        )
        text += f"; {data.held_out} held-out rows are few{spread}"
    return text


def _errorbar(value: float, ci: tuple[float, float] | None) -> np.ndarray:
    low, high = ci if ci else (value, value)
    return np.array([[value - low], [high - value]])


def _draw_f05(ax, data: RehearsalPlot) -> None:
    for i, p in enumerate(data.f05):
        color = "grey" if i == 0 else (_VIRTUAL_COLOR if i == 2 else "#9ecae1")
        ax.errorbar([i], [p.f05], yerr=_errorbar(p.f05, p.ci), fmt="o", color=color,
                    capsize=4, elinewidth=1.5, markersize=7)  # fmt: skip
        ax.annotate(f"{p.f05:.2f}", (i, p.f05), textcoords="offset points", xytext=(8, -3),
                    fontsize="small")  # fmt: skip
    ax.set_xticks(range(len(data.f05)), [p.label.replace(" calibration", "\ncalibration")
                                         for p in data.f05], fontsize="small")  # fmt: skip
    ax.set_xlim(-0.5, len(data.f05) - 0.5)
    ax.set_ylim(0, 1.05)
    ax.set_ylabel("F0.5 on held-out plant experiments")
    ax.set_title(f"held-out F0.5, 95 % bootstrap CI ({data.held_out} rows)", fontsize="medium")
    ax.grid(axis="y", alpha=0.3)


def _draw_states(ax, states: Sequence[ValidatedState]) -> None:
    x = np.arange(len(states))
    for i, s in enumerate(states):
        if s.significant:
            ax.axvspan(i - 0.5, i + 0.5, color=FAILURE_COLOR, alpha=0.15, lw=0)
    for shift, name, color, attr in ((-0.15, "twin p̂_V", _VIRTUAL_COLOR, "v"),
                                     (0.15, "plant p̂_P", _PLANT_COLOR, "p")):  # fmt: skip
        p = [getattr(s, f"p_{attr}") for s in states]
        err = np.hstack(
            [_errorbar(v, getattr(s, f"ci_{attr}")) for v, s in zip(p, states, strict=True)]
        )
        ax.errorbar(x + shift, p, yerr=err, fmt="o", color=color, capsize=3, label=name)
    ax.set_xticks(x, [f"{s.object_id} {s.kind}\n{s.state}" for s in states], fontsize="small",
                  rotation=90 if len(states) > 8 else 0)  # fmt: skip
    ax.set_xlim(-0.5, len(states) - 0.5)
    ax.set_ylim(-0.05, 1.05)
    ax.set_ylabel("success share, 95 % Clopper–Pearson CI")
    ax.set_title("best/worst states: twin vs plant (red: differ)", fontsize="medium")
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize="small", loc="best")


def plot_rehearsal(data: RehearsalPlot, fig: Figure | None = None) -> Figure:
    """Draw held-out F0.5 (left) and, when there are any, the validated best/worst states
    (right; a red background where twin and plant differ significantly)."""
    width = 5.0 + (max(4.0, 1.1 * len(data.states)) if data.states else 0.0)
    fig = fig or new_figure(width, 4.2)
    if data.states:
        left, right = fig.subplots(1, 2, gridspec_kw={"width_ratios": [5.0, width - 5.0]})
        _draw_states(right, data.states)
    else:
        left = fig.add_subplot(1, 1, 1)
    _draw_f05(left, data)
    return fig
