"""`transfertwin data calibration --out FILE.csv`: the shipped real experiments as a file."""

from __future__ import annotations

import argparse

from transfertwin._atomic import write_atomic
from transfertwin.cli._paths import out_file

__all__ = ["register"]


def cmd_calibration(args: argparse.Namespace) -> int:
    """Write the 191 real calibration experiments (the study's Table A.1) as CSV."""
    from transfertwin.data import calibration_csv_path

    out = out_file(args.out, (".csv",))
    write_atomic(out, calibration_csv_path().read_bytes())
    print(out)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add `data calibration`."""
    data = sub.add_parser("data", help="data shipped with transfertwin")
    dsub = data.add_subparsers(dest="data_command", required=True, parser_class=type(data))
    p = dsub.add_parser("calibration", help="the 191 real calibration experiments as CSV")
    p.add_argument("--out", required=True, help="FILE.csv")
    p.set_defaults(func=cmd_calibration)
