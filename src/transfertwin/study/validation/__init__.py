"""Validation of virtual against physical results (Sec. 6.7)."""

from transfertwin.study.validation._agreement import (
    Agreement,
    SideOutcome,
    compare_scenes,
    run_side,
)
from transfertwin.study.validation._comparison import (
    NEWCOMBE_HYBRID_SCORE,
    DifferenceInterval,
    StateComparison,
    VirtualPhysicalShares,
    newcombe_difference,
)
from transfertwin.study.validation._power import (
    DETECTABLE_DIFFERENCE,
    PowerSummary,
    n_to_exclude_zero,
    power_note,
    power_summary,
)
from transfertwin.study.validation._validation import (
    VALIDATION_COLUMNS,
    ValidationResult,
    compare,
    summary_json_text,
    validate,
    validation_csv_text,
    write_validation,
)

__all__ = [
    "DETECTABLE_DIFFERENCE",
    "NEWCOMBE_HYBRID_SCORE",
    "VALIDATION_COLUMNS",
    "Agreement",
    "DifferenceInterval",
    "PowerSummary",
    "SideOutcome",
    "StateComparison",
    "ValidationResult",
    "VirtualPhysicalShares",
    "compare",
    "compare_scenes",
    "n_to_exclude_zero",
    "newcombe_difference",
    "power_note",
    "power_summary",
    "run_side",
    "summary_json_text",
    "validate",
    "validation_csv_text",
    "write_validation",
]
