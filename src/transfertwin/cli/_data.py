"""`transfertwin data calibration --out FILE.csv`: the shipped real experiments as a file."""

from __future__ import annotations

import argparse
import csv
import io

from transfertwin._atomic import write_atomic
from transfertwin.cli._paths import out_file

__all__ = ["register"]


def _grid(step_deg: int) -> dict[tuple[str, str], list[int]]:
    """The θ of the experiment states (Eq. 6.7) on the `step_deg` grid, per (face, conveyor):
    one belt holds the object only near 0° and 180°, both belts between."""
    from transfertwin.ots import experiment_states, filter_theta_step

    grid: dict[tuple[str, str], list[int]] = {}
    for st in filter_theta_step(experiment_states(), step_deg):
        grid.setdefault((st.face, st.conveyor), []).append(st.theta_deg)
    return grid


def snap_theta(theta_deg: int, choices: list[int]) -> int:
    """The θ of `choices` nearest to `theta_deg` around the circle (the smaller on a tie);
    `theta_deg` itself when there are none."""
    if not choices:
        return theta_deg
    return min(choices, key=lambda c: (abs((c - theta_deg + 180) % 360 - 180), c))


def snapped_csv(text: str, step_deg: int) -> tuple[str, int]:
    """The real experiments' CSV with each θ moved to the nearest state of the `step_deg`
    grid with the row's face and conveyor; (CSV, rows moved)."""
    grid = _grid(step_deg)
    rows = list(csv.DictReader(io.StringIO(text)))
    moved = 0
    for row in rows:
        theta = int(row["theta_deg"])
        row["theta_deg"] = str(snap_theta(theta, grid.get((row["face"], row["conveyor"]), [])))
        moved += row["theta_deg"] != str(theta)
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return buf.getvalue(), moved


def cmd_calibration(args: argparse.Namespace) -> int:
    """Write the 191 real calibration experiments (the study's Table A.1) as CSV, with
    ``--theta-step`` each real θ rounded onto a study's θ grid."""
    from transfertwin.data import calibration_csv_path
    from transfertwin.study.experiment import check_theta_step

    if args.theta_step is not None:
        check_theta_step(args.theta_step)
    out = out_file(args.out, (".csv",))
    text = calibration_csv_path().read_text()
    if args.theta_step is None:
        write_atomic(out, text)
        print(out)
        return 0
    snapped, moved = snapped_csv(text, args.theta_step)
    write_atomic(out, snapped)
    total = len(snapped.splitlines()) - 1
    print(f"{out}: θ of {moved} of {total} real experiments moved to the nearest state on a "
          f"{args.theta_step}° grid (a study's): validate lines their states up")  # fmt: skip
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add `data calibration`."""
    data = sub.add_parser("data", help="data shipped with transfertwin")
    dsub = data.add_subparsers(dest="data_command", required=True, parser_class=type(data))
    p = dsub.add_parser("calibration", help="the 191 real calibration experiments as CSV")
    p.add_argument("--out", required=True, help="FILE.csv")
    p.add_argument("--theta-step", type=int, metavar="DEG",
                   help="move each real θ to the nearest pre-transfer state on a DEG grid (a "
                   "study's --theta-step, dividing 360) with the row's face and conveyor, so "
                   "that `validate` lines the real states up with the study's (the real "
                   "angles are measured, e.g. -11°)")  # fmt: skip
    p.set_defaults(func=cmd_calibration)
