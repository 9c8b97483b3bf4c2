"""Per-state statistics, the four series and the best/worst selection (Sec. 6.6–6.7).

Input is a results table as an iterable of mappings (one experiment each) with
at least ``object_id, face, conveyor, theta_deg, success`` and optionally
``status``. A missing or empty status counts as ``'ok'`` (real-experiment CSVs
have none). Only ``'ok'`` rows enter n and k; ``'invalid'``, ``'unstable'`` and
``'error'`` rows are counted per state but never as success or failure.

Per state: n, k, ȳ = k/n (Eq. 6.26), Clopper–Pearson 95 % interval (Sec. 6.7).
Per object: the four series (Eq. 6.21–6.24) over the states with n ≥ 1, smoothed
by Eq. 6.27 (window means over the angles present, see `study._selection`), and
the best/worst state by Alg. 1–4. A series with no run state is skipped.
"""

from __future__ import annotations

import csv
import io
import json
import logging
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import numpy as np

from transfertwin._atomic import write_atomic
from transfertwin._errors import InputError
from transfertwin.ots import (
    SERIES_ORDER,
)
from transfertwin.study.fullstate._decision import decide_placement
from transfertwin.study.fullstate._decision_text import placement_headline
from transfertwin.study.fullstate._selection import (
    CircularSeries,
    GlobalChoice,
    best_global,
    moving_average,
    worst_global,
)
from transfertwin.study.fullstate._states import (
    STATES_COLUMNS,
    ResultRecord,
    StateStat,
    iter_records,
    object_sort_key,
    state_table,
)

__all__ = [
    "AnalysisResult",
    "SelectedState",
    "Selection",
    "SeriesStats",
    "analyze",
    "placement_json_text",
    "select",
    "select_from_series",
    "selection_json_text",
    "series_table",
    "states_csv_text",
]

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SeriesStats:
    """One series (Eq. 6.21–6.24) of one object over its run states, θ ascending.

    Attributes:
        object_id: Object label.
        face: ``'front'`` or ``'back'``.
        side: ``'left'`` or ``'right'``: conveyor ∈ {both, side}.
        states: Run states (n ≥ 1) of the series, θ ascending.
        y_ma: Exact ȳ^MA (Eq. 6.27) per state.
    """

    object_id: str
    face: str
    side: str
    states: tuple[StateStat, ...]
    y_ma: tuple[Fraction, ...]

    @property
    def name(self) -> str:
        """Series label such as ``'front-left'``."""
        return f"{self.face}-{self.side}"

    @property
    def theta_deg(self) -> np.ndarray:
        """Angles ``(m,)``, degrees."""
        return np.array([s.theta_deg for s in self.states], dtype=int)

    @property
    def y_mean(self) -> np.ndarray:
        """ȳ per state ``(m,)`` (Eq. 6.26)."""
        return np.array([s.y_mean for s in self.states])

    @property
    def y_ma_array(self) -> np.ndarray:
        """ȳ^MA per state ``(m,)`` as floats (Eq. 6.27)."""
        return np.array([float(v) for v in self.y_ma])

    def smoothed(self) -> CircularSeries:
        """ȳ^MA as a `CircularSeries` for Alg. 1–4."""
        return CircularSeries(tuple(s.theta_deg for s in self.states), self.y_ma)


def series_table(
    state_stats: Iterable[StateStat], object_id: str, *, window: int = 21
) -> tuple[SeriesStats, ...]:
    """The series of ``object_id`` in the order of `SERIES_ORDER` (Eq. 6.28).

    States with n = 0 are left out; a series with no run state is skipped, so
    the result may hold fewer than four series (none for an unknown object).
    """
    mine = [s for s in state_stats if s.object_id == object_id and s.n > 0]
    out = []
    for face, side in SERIES_ORDER:
        chosen = sorted(
            (s for s in mine if s.face == face and s.conveyor in ("both", side)),
            key=lambda s: s.theta_deg,
        )
        if not chosen:
            continue
        thetas = tuple(s.theta_deg for s in chosen)
        y = CircularSeries(thetas, tuple(Fraction(s.k, s.n) for s in chosen))
        y_ma = moving_average(y, window).values
        out.append(SeriesStats(object_id, face, side, tuple(chosen), y_ma))
    return tuple(out)


@dataclass(frozen=True)
class SelectedState:
    """The best or worst pre-transfer state of one object (Alg. 1–4, Sec. 6.7).

    Attributes:
        face, conveyor, theta_deg: The state.
        series: Name of the series it was chosen from, e.g. ``'front-left'``.
        y_ma: Its smoothed value ȳ^MA (Eq. 6.27).
        p_hat: Its own mean ȳ = k/n (Eq. 6.26).
        n, k: Its ``'ok'`` experiments and successes.
        ci_low, ci_high: Clopper–Pearson 95 % bounds of p.
        half_window: Applied half window of Alg. 1/4, degrees.
    """

    face: str
    conveyor: str
    theta_deg: int
    series: str
    y_ma: float
    p_hat: float
    n: int
    k: int
    ci_low: float
    ci_high: float
    half_window: int

    def to_dict(self) -> dict[str, object]:
        """The ``selection.json`` entry: face … half_window (no series, k)."""
        keys = ("face", "conveyor", "theta_deg", "y_ma", "p_hat", "n", "ci_low", "ci_high")
        return {**{key: getattr(self, key) for key in keys}, "half_window": self.half_window}


@dataclass(frozen=True)
class Selection:
    """Best (Alg. 1–2) and worst (Alg. 3–4) state of one object."""

    object_id: str
    best: SelectedState
    worst: SelectedState

    def to_dict(self) -> dict[str, dict[str, object]]:
        """``{"best": {...}, "worst": {...}}`` as in ``selection.json``."""
        return {"best": self.best.to_dict(), "worst": self.worst.to_dict()}


def _selected(series: Sequence[SeriesStats], choice: GlobalChoice) -> SelectedState:
    s = series[choice.series_index]
    st = s.states[choice.local.index]
    return SelectedState(
        st.face, st.conveyor, st.theta_deg, s.name, float(choice.local.value), st.y_mean,
        st.n, st.k, st.ci_low, st.ci_high, choice.local.half_window,
    )  # fmt: skip


def select_from_series(series: Sequence[SeriesStats]) -> Selection:
    """Alg. 1–4 over an object's series given in `SERIES_ORDER` (ties to the earlier).

    Raises:
        InputError: If no series is given.
    """
    if not series:
        raise InputError("no series with run states to select from (Alg. 2)")
    smoothed = [s.smoothed() for s in series]
    best, worst = best_global(smoothed), worst_global(smoothed)
    return Selection(series[0].object_id, _selected(series, best), _selected(series, worst))


def select(state_stats: Iterable[StateStat], object_id: str, *, window: int = 21) -> Selection:
    """Best and worst pre-transfer state of one object (Eq. 6.27, Alg. 1–4).

    Raises:
        InputError: If the object has no state with an ``'ok'`` experiment.
    """
    series = series_table(state_stats, object_id, window=window)
    if not series:
        raise InputError(f"object {object_id!r} has no state with an 'ok' experiment (Alg. 2)")
    return select_from_series(series)


@dataclass(frozen=True)
class AnalysisResult:
    """Everything `analyze` computed, in natural object order.

    Attributes:
        records: The validated input rows.
        states: Per-state statistics (`state_table`).
        series: All objects' series (`series_table`), object by object.
        selections: One per object with at least one run state.
        skipped_objects: Objects without any ``'ok'`` experiment.
        window: Moving-average window of Eq. 6.27, degrees.
    """

    records: tuple[ResultRecord, ...]
    states: tuple[StateStat, ...]
    series: tuple[SeriesStats, ...]
    selections: tuple[Selection, ...]
    skipped_objects: tuple[str, ...] = ()
    window: int = 21

    @property
    def object_ids(self) -> tuple[str, ...]:
        """Objects with a selection."""
        return tuple(s.object_id for s in self.selections)

    def series_of(self, object_id: str) -> tuple[SeriesStats, ...]:
        """The series of one object."""
        return tuple(s for s in self.series if s.object_id == object_id)

    def selection_of(self, object_id: str) -> Selection:
        """The selection of one object; InputError if it has none."""
        for sel in self.selections:
            if sel.object_id == object_id:
                return sel
        raise InputError(f"no selection for object {object_id!r}")


def _fmt(value: float | Fraction | None) -> str:
    return "" if value is None or value != value else repr(float(value))


def states_csv_text(result: AnalysisResult) -> str:
    """``states.csv``: one row per state (`STATES_COLUMNS`), in `state_table` order.

    A 'both' state lies in the left and the right series of its face; its ȳ^MA in each
    goes to ``y_ma_left`` and ``y_ma_right``. The column of a series the state is not in
    is empty, and so are y_mean, y_ma and the interval of a state with n = 0.
    """
    y_ma = {
        (s.object_id, s.face, s.side, st.conveyor, st.theta_deg): v
        for s in result.series
        for st, v in zip(s.states, s.y_ma, strict=True)
    }
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(STATES_COLUMNS)
    for st in result.states:
        key = (st.object_id, st.face)
        ma_left, ma_right = (
            y_ma.get((*key, side, st.conveyor, st.theta_deg)) for side in ("left", "right")
        )
        writer.writerow([
            st.object_id, st.face, st.conveyor, st.theta_deg, st.n, st.k,
            _fmt(st.y_mean), _fmt(ma_left), _fmt(ma_right), _fmt(st.ci_low), _fmt(st.ci_high),
        ])  # fmt: skip
    return buf.getvalue()


def selection_json_text(result: AnalysisResult) -> str:
    """``selection.json``: ``{object_id: {"best": {...}, "worst": {...}}}``."""
    return json.dumps({s.object_id: s.to_dict() for s in result.selections}, indent=2) + "\n"


def placement_json_text(result: AnalysisResult) -> str:
    """``placement.json``: per object the advice decided face → conveyor → θ
    (`decide_placement`): ``{"advice": headline, "alpha": …, "face": {…}, "conveyor": {…},
    "theta": {…}}``, each level with its verdict, kept and avoided options and pooled counts."""
    out = {}
    for sel in result.selections:
        d = decide_placement(result.states, sel.object_id)
        body = d.to_dict()
        body.pop("object_id")
        out[sel.object_id] = {"advice": placement_headline(d), **body}
    return json.dumps(out, indent=2, ensure_ascii=False) + "\n"


def analyze(
    rows: Iterable[Mapping[str, object] | ResultRecord],
    out_dir: str | os.PathLike[str] | None = None,
    *,
    window: int = 21,
) -> AnalysisResult:
    """Statistics, series and selection of a results table (Sec. 6.6–6.7).

    Everything is computed (and bad input rejected) before anything is
    written. With ``out_dir`` the folder is created if needed and
    ``states.csv``, ``selection.json`` and ``placement.json`` are written atomically. Plots and the
    HTML report are made by `transfertwin.report` (a higher layer).

    Raises:
        InputError: On a bad row or window, or if no row has status ``'ok'``.
    """
    records = tuple(iter_records(rows))
    states = state_table(records)
    objects = sorted({s.object_id for s in states}, key=object_sort_key)
    all_series: list[SeriesStats] = []
    selections, skipped = [], []
    for obj in objects:
        series = series_table(states, obj, window=window)
        if not series:
            _log.warning("object %s has no 'ok' experiment; no selection", obj)
            skipped.append(obj)
            continue
        all_series.extend(series)
        selections.append(select_from_series(series))
    if not selections:
        raise InputError("results contain no experiment with status 'ok'")
    result = AnalysisResult(
        records, tuple(states), tuple(all_series), tuple(selections), tuple(skipped), window
    )
    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        write_atomic(out / "states.csv", states_csv_text(result))
        write_atomic(out / "selection.json", selection_json_text(result))
        write_atomic(out / "placement.json", placement_json_text(result))
    return result
