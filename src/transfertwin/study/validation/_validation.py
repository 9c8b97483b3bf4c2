"""Virtual against physical success probabilities per pre-transfer state (Sec. 6.7).

For every state (object_id, face, conveyor, θ) run on both sides (at least one
``'ok'`` experiment each) the comparison (`StateComparison`, in `_comparison`) holds n, k
and p̂ = k/n of the virtual (E^V) and the physical (E^P) experiments with Clopper–Pearson
intervals, and the Newcombe hybrid score interval of the difference p_V − p_P. A state is
*significant* when that interval excludes 0 (a bound exactly at 0 does not).
An object *differs* when any of its compared states is significant.

States run on one side only are never silently dropped: they are counted per
object in `ValidationResult` and ``summary.json``. Rows with a status other than
``'ok'`` never count (see `transfertwin.study.fullstate._analysis.state_table`).
"""

from __future__ import annotations

import csv
import io
import json
import logging
import os
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from transfertwin._atomic import write_atomic
from transfertwin._errors import InputError
from transfertwin.store import read_results
from transfertwin.study.fullstate import (
    ResultRecord,
    StateStat,
    clopper_pearson,
    object_sort_key,
    state_order,
    state_table,
)
from transfertwin.study.validation._comparison import (
    NEWCOMBE_HYBRID_SCORE,
    StateComparison,
    StateKey,
    newcombe_difference,
)
from transfertwin.study.validation._power import power_note, power_summary

__all__ = [
    "VALIDATION_COLUMNS",
    "ValidationResult",
    "compare",
    "summary_json_text",
    "validate",
    "validation_csv_text",
    "write_validation",
]

_log = logging.getLogger(__name__)

#: Header of ``validation.csv``.
VALIDATION_COLUMNS: tuple[str, ...] = (
    "object_id", "face", "conveyor", "theta_deg", "n_v", "k_v", "p_v",
    "n_p", "k_p", "p_p", "diff_low", "diff_high", "significant",
)  # fmt: skip

Rows = Iterable[Mapping[str, object] | ResultRecord]
_OBJECT_COUNTS = (
    "states_compared", "states_significant", "states_virtual_only", "states_physical_only",
)  # fmt: skip


def _compare_stats(
    virtual: Sequence[StateStat], physical: Sequence[StateStat], alpha: float
) -> list[StateComparison]:
    run_p = {s.key: s for s in physical if s.n > 0}
    out = []
    for v in virtual:
        p = run_p.get(v.key)
        if v.n == 0 or p is None:
            continue
        ci_v, ci_p = clopper_pearson(v.k, v.n, alpha), clopper_pearson(p.k, p.n, alpha)
        diff = newcombe_difference(v.k, v.n, p.k, p.n, alpha)
        out.append(StateComparison(
            *v.key, v.n, v.k, ci_v.low, ci_v.high, p.n, p.k, ci_p.low, ci_p.high,
            diff.low, diff.high, float(alpha),
        ))  # fmt: skip
    return out


def compare(virtual_rows: Rows, physical_rows: Rows, alpha: float = 0.05) -> list[StateComparison]:
    """Compare every state run on both sides (Sec. 6.7).

    Args:
        virtual_rows: Results table of E^V (rows as in `state_table`).
        physical_rows: Results table of E^P.
        alpha: 1 − confidence level of all intervals.

    Returns:
        Comparisons ordered by object (natural), face, conveyor and θ; empty
        when no state is run on both sides.

    Raises:
        InputError: On a bad row or alpha.
    """
    clopper_pearson(0, 1, alpha)  # validate alpha even when nothing is compared
    return _compare_stats(state_table(virtual_rows), state_table(physical_rows), alpha)


def _fmt(value: float) -> str:
    return repr(float(value))


def validation_csv_text(comparisons: Iterable[StateComparison]) -> str:
    """``validation.csv``: one row per compared state, `VALIDATION_COLUMNS`; significant 0/1."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(VALIDATION_COLUMNS)
    for c in comparisons:
        writer.writerow([
            c.object_id, c.face, c.conveyor, c.theta_deg, c.n_v, c.k_v, _fmt(c.p_v),
            c.n_p, c.k_p, _fmt(c.p_p), _fmt(c.diff_low), _fmt(c.diff_high), int(c.significant),
        ])  # fmt: skip
    return buf.getvalue()


@dataclass(frozen=True)
class ValidationResult:
    """All comparisons of a validation (Sec. 6.7) and the states left uncompared.

    Attributes:
        comparisons: States run on both sides, in state order.
        virtual_only: States run (n ≥ 1) only in E^V, in state order.
        physical_only: States run only in E^P, in state order.
        alpha: 1 − confidence level of all intervals.
    """

    comparisons: tuple[StateComparison, ...]
    virtual_only: tuple[StateKey, ...] = ()
    physical_only: tuple[StateKey, ...] = ()
    alpha: float = 0.05

    @property
    def object_ids(self) -> tuple[str, ...]:
        """Objects with at least one compared state, natural order."""
        return tuple(sorted({c.object_id for c in self.comparisons}, key=object_sort_key))

    @property
    def differing_objects(self) -> tuple[str, ...]:
        """Objects with at least one significant state, natural order."""
        diff = {c.object_id for c in self.comparisons if c.significant}
        return tuple(o for o in self.object_ids if o in diff)

    @property
    def summary_line(self) -> str:
        """E.g. ``"12/37 objects differ"``."""
        return f"{len(self.differing_objects)}/{len(self.object_ids)} objects differ"

    @property
    def power_note(self) -> str:
        """Whether the compared n can show a difference and which n would (`power_note`);
        empty when every compared state has enough runs."""
        return power_note(power_summary(self.comparisons)) if self.comparisons else ""

    def _objects(self) -> dict[str, dict[str, Any]]:
        counts: dict[str, Counter[str]] = {}
        for name, keys in (
            ("states_compared", [c.key for c in self.comparisons]),
            ("states_significant", [c.key for c in self.comparisons if c.significant]),
            ("states_virtual_only", self.virtual_only),
            ("states_physical_only", self.physical_only),
        ):
            for key in keys:
                counts.setdefault(key[0], Counter())[name] += 1
        out = {}
        for obj in sorted(counts, key=object_sort_key):
            c = counts[obj]
            entry: dict[str, Any] = {name: c[name] for name in _OBJECT_COUNTS}
            entry["differs"] = c["states_significant"] > 0 if c["states_compared"] else None
            out[obj] = entry
        return out

    def to_dict(self) -> dict[str, Any]:
        """The content of ``summary.json``: method, counts, per-object counts, and what the
        compared n can show (``power``, ``power_note``; see `power_summary`).

        Per object ``differs`` is ``None`` when none of its states was compared.
        """
        return {
            "summary": self.summary_line,
            "alpha": self.alpha,
            "state_interval": "clopper-pearson",
            "difference_interval": NEWCOMBE_HYBRID_SCORE,
            "difference": "p_v - p_p",
            "objects_compared": len(self.object_ids),
            "objects_differing": len(self.differing_objects),
            "differing_objects": list(self.differing_objects),
            "states_compared": len(self.comparisons),
            "states_significant": sum(c.significant for c in self.comparisons),
            "states_virtual_only": len(self.virtual_only),
            "states_physical_only": len(self.physical_only),
            "objects": self._objects(),
            "power": power_summary(self.comparisons).to_dict() if self.comparisons else None,
            "power_note": self.power_note,
        }


def summary_json_text(result: ValidationResult) -> str:
    """``summary.json``: `ValidationResult.to_dict` as indented JSON."""
    return json.dumps(result.to_dict(), indent=2) + "\n"


def _side_stats(source: str | os.PathLike[str] | Rows, side: str) -> list[StateStat]:
    """`state_table` of one side; errors name the side (paths name themselves)."""
    if isinstance(source, (str, os.PathLike)):
        source = read_results(source)
    try:
        return state_table(source)
    except InputError as exc:
        raise InputError(f"{side} results: {exc}") from None


def validate(
    virtual: str | os.PathLike[str] | Rows,
    physical: str | os.PathLike[str] | Rows,
    out_dir: str | os.PathLike[str] | None = None,
    *,
    alpha: float = 0.05,
) -> ValidationResult:
    """Validate E^V against E^P state by state (Sec. 6.7).

    Everything is read and computed (and bad input rejected) before anything is
    written. With ``out_dir`` the folder is created if needed and
    ``validation.csv`` and ``summary.json`` are written atomically; the plots
    are drawn by `transfertwin.report` (a higher layer).

    Args:
        virtual: Results of E^V: a SQLite db, CSV or Parquet path, or rows.
        physical: Results of E^P, likewise (e.g. a real-experiment CSV).
        out_dir: Output folder, or ``None`` to write nothing.
        alpha: 1 − confidence level of all intervals.

    Raises:
        InputError: On an unreadable table, a bad row or alpha, or when no
            state is run on both sides.
    """
    clopper_pearson(0, 1, alpha)
    v_stats, p_stats = _side_stats(virtual, "virtual"), _side_stats(physical, "physical")
    v_run = {s.key for s in v_stats if s.n > 0}
    p_run = {s.key for s in p_stats if s.n > 0}
    comparisons = _compare_stats(v_stats, p_stats, alpha)
    if not comparisons:
        raise InputError(
            f"no pre-transfer state was run on both sides ({len(v_run)} virtual, "
            f"{len(p_run)} physical states; Sec. 6.7)"
        )
    result = ValidationResult(
        tuple(comparisons),
        tuple(sorted(v_run - p_run, key=state_order)),
        tuple(sorted(p_run - v_run, key=state_order)),
        float(alpha),
    )
    _log.info("%d virtual-only states not compared", len(result.virtual_only))
    if result.physical_only:  # physical experiments without a virtual twin: worth a warning
        _log.warning("%d physical-only states not compared", len(result.physical_only))
    if out_dir is not None:
        write_validation(result, out_dir)
    return result


def write_validation(result: ValidationResult, out_dir: str | os.PathLike[str]) -> Path:
    """Write ``validation.csv`` and ``summary.json`` atomically into ``out_dir`` (created).

    Returns:
        The output folder.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_atomic(out / "validation.csv", validation_csv_text(result.comparisons))
    write_atomic(out / "summary.json", summary_json_text(result))
    return out
