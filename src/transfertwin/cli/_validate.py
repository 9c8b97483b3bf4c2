"""`transfertwin validate`: virtual against physical results per state (Sec. 6.7).

Writes ``validation.csv``, ``summary.json`` and ``validation.png`` into ``--out``
and prints one summary line such as ``12/37 objects differ (…)``; when the compared
states have too few runs to see a difference it says so, and which n per side would.
"""

from __future__ import annotations

import argparse
import logging

from transfertwin.cli._paths import out_dir

__all__ = ["cmd_validate", "register"]


def cmd_validate(args: argparse.Namespace) -> int:
    """Compare E^V with E^P state by state; Newcombe hybrid score intervals."""
    from transfertwin.report import validate_and_report

    out = out_dir(args.out)
    quiet = logging.getLogger("transfertwin.study.validation")
    level = quiet.level
    if not logging.getLogger().isEnabledFor(logging.INFO):
        quiet.setLevel(logging.ERROR)  # its warning is said below in a sentence
    try:
        result = validate_and_report(args.virtual, args.physical, out, alpha=args.alpha)
    finally:
        quiet.setLevel(level)
    n_sig = sum(c.significant for c in result.comparisons)
    print(
        f"{result.summary_line} ({len(result.comparisons)} states compared, {n_sig} significant "
        f"at alpha={result.alpha:g}; not compared: {len(result.virtual_only)} virtual-only, "
        f"{len(result.physical_only)} physical-only states)"
    )
    if result.physical_only:
        print(f"{len(result.physical_only)} physical states have no virtual results (objects "
              "or angles the virtual study did not run) and were not compared; a real θ lines "
              "up only with the same θ (`data calibration --theta-step` moves them onto a "
              "study's grid)")  # fmt: skip
    if result.power_note:
        print(result.power_note)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add `validate` to the CLI (``sub`` from ``add_subparsers(parser_class=_Parser)``)."""
    p = sub.add_parser("validate", help="virtual vs physical success per state (Sec. 6.7)")
    p.add_argument("--virtual", required=True, metavar="RESULTS",
                   help="virtual results: SQLite db, CSV or Parquet")  # fmt: skip
    p.add_argument("--physical", required=True, metavar="RESULTS",
                   help="physical (real) results: SQLite db, CSV or Parquet")  # fmt: skip
    p.add_argument("--out", required=True, metavar="DIR", help="output directory")
    p.add_argument("--alpha", type=float, default=0.05,
                   help="1 - confidence level of all intervals (default 0.05)")  # fmt: skip
    p.set_defaults(func=cmd_validate)
