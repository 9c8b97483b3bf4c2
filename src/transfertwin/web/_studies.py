"""What the console shows of a study store: progress (done/planned, rate, ETA), the
success map per core, face and pre-transfer state, and the per-state success shares with
their Clopper–Pearson intervals and each core's best and worst state (Sec. 6.6–6.7, Alg.
1–4, as `transfertwin analyze` computes them). Pure reads of the store's public API."""

from __future__ import annotations

import math
import tempfile
import threading
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

from transfertwin._errors import InputError
from transfertwin.ots import CONVEYORS, FACES
from transfertwin.report import RING_RADIUS
from transfertwin.store import SQLiteResultStore, export_results
from transfertwin.study.experiment import StudyPlan
from transfertwin.study.fullstate import AnalysisResult, SelectedState, analyze, object_sort_key

__all__ = [
    "RATE_WINDOW",
    "StudyView",
    "StudyViews",
    "analysis_view",
    "progress_of",
    "success_map",
]

#: The rate is measured over at most this many of the most recently finished rows.
RATE_WINDOW = 100


def _parse_utc(text: object) -> datetime | None:
    if not isinstance(text, str) or not text:
        return None
    try:
        t = datetime.fromisoformat(text)
    except ValueError:
        return None
    return t if t.tzinfo is not None else t.replace(tzinfo=UTC)


def progress_of(
    done: int,
    planned: int | None,
    finished: Iterable[datetime],
    by_status: Mapping[str, int],
    now: datetime | None = None,
) -> dict[str, object]:
    """Progress of a study from its row count, plan size and rows' finish times (pure).

    The rate is (k - 1) / (last - first) over the last `RATE_WINDOW` finish times; the
    ETA is the remaining experiments at that rate. Both are None when they cannot be
    measured (fewer than two timestamps, all at one instant, or nothing left to do).
    """
    now = now or datetime.now(UTC)
    times = sorted(finished)[-RATE_WINDOW:]
    rate = None
    if len(times) >= 2 and times[-1] > times[0]:
        rate = (len(times) - 1) / (times[-1] - times[0]).total_seconds()
    remaining = None if planned is None else max(planned - done, 0)
    eta = remaining / rate if rate and remaining else (0.0 if remaining == 0 else None)
    last = times[-1] if times else None
    return {
        "done": done,
        "planned": planned,
        "fraction": done / planned if planned else None,
        "rate_per_s": rate,
        "eta_s": eta,
        "last_finished_utc": last.isoformat() if last else None,
        "idle_s": (now - last).total_seconds() if last else None,
        "by_status": dict(sorted(by_status.items())),
    }


def success_map(rows: Iterable[Mapping[str, object]]) -> dict[str, object]:
    """Success share per (core, face, conveyor, θ) of the 'ok' rows (pure).

    Returns:
        ``{"faces": [...], "objects": {object_id: {face: [point, ...]}}}``, each point a
        dict with theta_deg, conveyor, r (ring radius as in Fig. 6.7), n, successes and
        share, ordered by conveyor then θ. Rows with another status are counted per
        object under ``excluded``.
    """
    cells: dict[tuple[str, str, str, int], list[int]] = {}
    excluded: dict[str, int] = {}
    for row in rows:
        oid = str(row["object_id"])
        success = row.get("success")
        if row.get("status") != "ok" or success is None:
            excluded[oid] = excluded.get(oid, 0) + 1
            continue
        key = (oid, str(row["face"]), str(row["conveyor"]), int(row["theta_deg"]))
        cell = cells.setdefault(key, [0, 0])
        cell[0] += 1
        cell[1] += int(success)
    objects: dict[str, dict[str, list[dict[str, object]]]] = {}
    order = {c: i for i, c in enumerate(CONVEYORS)}
    for (oid, face, conveyor, theta), (n, k) in sorted(
        cells.items(), key=lambda kv: (kv[0][0], kv[0][1], order.get(kv[0][2], 9), kv[0][3])
    ):
        objects.setdefault(oid, {f: [] for f in FACES}).setdefault(face, []).append(
            {
                "theta_deg": theta,
                "conveyor": conveyor,
                "r": RING_RADIUS.get(conveyor, 1.0),
                "n": n,
                "successes": k,
                "share": k / n,
            }
        )
    for oid in excluded:
        objects.setdefault(oid, {f: [] for f in FACES})
    return {"faces": list(FACES), "objects": objects, "excluded": excluded}


def _num(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _selected(st: SelectedState) -> dict[str, object]:
    return {"face": st.face, "conveyor": st.conveyor, "theta_deg": st.theta_deg,
            "series": st.series, "y_ma": _num(st.y_ma), "share": _num(st.p_hat), "n": st.n,
            "k": st.k, "low": _num(st.ci_low), "high": _num(st.ci_high)}  # fmt: skip


def _advice(result: AnalysisResult, object_id: str) -> str:
    """What to do with the core, decided face, conveyor, θ in turn as far as the data
    decide (`decide_placement`; the report's and `analyze`'s words)."""
    from transfertwin.study.fullstate import decide_placement, placement_headline

    return placement_headline(decide_placement(result.states, object_id))


def analysis_view(result: AnalysisResult | None, object_id: str | None) -> dict[str, object]:
    """Per-state shares of one core and every core's best/worst state (pure, JSON-ready).

    Args:
        result: `analyze` of the study's rows; None when no row is 'ok' yet.
        object_id: The core whose states are listed; None: the first core.

    Returns:
        ``{"objects": [...], "object": id, "states": [point, ...], "selection": [...]}``:
        a point has face, conveyor, theta_deg, n, k, share and the 95 % Clopper–Pearson
        low/high (states with n = 0 are left out); a selection entry has object_id, the
        advice (what to do, decided as far as the data decide) and best/worst with the
        state, its series, ȳ^MA (Eq. 6.27), share, n, k, low, high.
    """
    if result is None:
        return {"objects": [], "object": None, "states": [], "selection": [],
                "message": "no experiment with status 'ok' yet"}  # fmt: skip
    objects = sorted({s.object_id for s in result.states}, key=object_sort_key)
    if object_id is None:
        object_id = objects[0]
    if object_id not in objects:
        raise LookupError(f"no core {object_id[:40]!r} in this study; cores: {', '.join(objects)}")
    states = [
        {"face": s.face, "conveyor": s.conveyor, "theta_deg": s.theta_deg, "n": s.n, "k": s.k,
         "share": _num(s.y_mean), "low": _num(s.ci_low), "high": _num(s.ci_high)}
        for s in result.states if s.object_id == object_id and s.n > 0
    ]  # fmt: skip
    selection = [{"object_id": sel.object_id, "advice": _advice(result, sel.object_id),
                  "best": _selected(sel.best), "worst": _selected(sel.worst)}
                 for sel in result.selections]  # fmt: skip
    return {"objects": objects, "object": object_id, "states": states, "selection": selection,
            "skipped": list(result.skipped_objects)}  # fmt: skip


@dataclass
class StudyView:
    """One study store as the console reads it; results are cached until the store grows."""

    path: Path

    def __post_init__(self) -> None:
        self._lock = threading.Lock()
        self._cache_key: tuple[int, int, float] | None = None
        self._rows: list[dict[str, object]] = []
        self._plan: StudyPlan | None = None
        self._plan_hash: str | None = None
        self._analysis: tuple[tuple[int, int, float] | None, AnalysisResult | None] = (None, None)

    @property
    def name(self) -> str:
        """The store's file name (its id in the console's URLs)."""
        return self.path.name

    def _open(self) -> SQLiteResultStore:
        try:
            return SQLiteResultStore(self.path, create=False)
        except InputError:
            raise
        except Exception as exc:  # a file that is not a store
            raise InputError(f"{self.path.name}: not a result store ({exc})") from None

    def _refresh(self) -> None:
        wal = self.path.with_name(self.path.name + "-wal")
        mtime = self.path.stat().st_mtime + (wal.stat().st_mtime if wal.exists() else 0.0)
        with self._open() as store:
            count = store.count()
            key = (count, sum(store.count_by_status().values()), mtime)
            if key == self._cache_key:
                return
            stored = store.plan()
            if stored is not None and stored.plan_hash != self._plan_hash:
                try:
                    self._plan = StudyPlan.from_json(stored.plan_json)
                except Exception:  # a plan written by another version: no planned count
                    self._plan = None
                self._plan_hash = stored.plan_hash
            self._rows = list(store.rows())
            self._cache_key = key

    def rows(self) -> list[dict[str, object]]:
        """The store's rows (fresh when it has changed)."""
        with self._lock:
            self._refresh()
            return self._rows

    def progress(self) -> dict[str, object]:
        """`progress_of` the store, with its name and plan id."""
        with self._lock:
            self._refresh()
            rows, plan = self._rows, self._plan
        by_status: dict[str, int] = {}
        for r in rows:
            by_status[str(r["status"])] = by_status.get(str(r["status"]), 0) + 1
        times = [t for t in (_parse_utc(r.get("finished_utc")) for r in rows) if t is not None]
        out = progress_of(len(rows), plan.n_experiments if plan else None, times, by_status)
        out["name"] = self.name
        out["plan"] = self._plan_hash[:12] if self._plan_hash else None
        out["objects"] = sorted({str(r["object_id"]) for r in rows})
        return _finite(out)

    def success_map(self) -> dict[str, object]:
        """`success_map` of the store's rows."""
        return success_map(self.rows())

    def analysis(self, object_id: str | None = None) -> dict[str, object]:
        """`analysis_view` of the store's rows (analysed again only when the store grew)."""
        with self._lock:
            self._refresh()
            rows, key = self._rows, self._cache_key
            cached_key, result = self._analysis
        if cached_key != key:
            ok = any(r.get("status") == "ok" for r in rows)
            result = analyze(rows) if ok else None
            with self._lock:
                self._analysis = (key, result)
        return analysis_view(result, object_id)

    def export(self, fmt: str) -> bytes:
        """The results table as CSV or Parquet bytes."""
        if fmt not in ("csv", "parquet"):
            raise InputError(f"format must be csv or parquet, got {fmt!r}")
        rows = self.rows()
        with tempfile.TemporaryDirectory(prefix="tt-web-") as tmp:
            path = export_results(rows, Path(tmp) / f"results.{fmt}")
            return Path(path).read_bytes()


class StudyViews(Mapping[str, StudyView]):
    """The console's study stores by name: those it was given (``--db``) and, with a
    process floor (``--cps W``), the stores of the studies its Experiment Manager runs
    (``cps study start``), looked up again on every read so a study started after the
    console appears in it. A name given with ``--db`` wins over a floor's store of that
    name."""

    def __init__(self, dbs: Iterable[Path], cps: Path | None = None) -> None:
        self._views = {p.name: StudyView(p) for p in dbs}
        self._cps = cps
        self._lock = threading.Lock()

    def _scan(self) -> None:
        if self._cps is None:
            return
        from transfertwin.cps.apps import study_stores

        for path in study_stores(self._cps):
            with self._lock:
                if path.name not in self._views:
                    self._views[path.name] = StudyView(path)

    def __getitem__(self, name: str) -> StudyView:
        self._scan()
        return self._views[name]

    def __iter__(self) -> Iterator[str]:
        self._scan()
        return iter(list(self._views))

    def __len__(self) -> int:
        self._scan()
        return len(self._views)


def _finite(d: dict[str, object]) -> dict[str, object]:
    """JSON has no NaN or infinity: such floats become None."""
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in d.items()}
