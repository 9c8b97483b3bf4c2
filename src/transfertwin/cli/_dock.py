"""`transfertwin dock`: emergent docking errors from simulated navigation and laser docking,
measured by the simulated ChArUco rig (Sec. 5.4.1, 6.1.2).

    dock --station A|B|C|D[,...] --runs N --seed S --out FILE.csv [--image PNG] [--real CSV]

The CSV has the real experiments' columns (transfer_unit, dock_err_x_mm, dock_err_y_mm,
dock_err_theta_deg) plus run, seed, status and the simulation's true error. A per-station
summary is printed next to the measured errors of the real table. Same seed, same bytes.
"""

from __future__ import annotations

import argparse

from rich.console import Console
from rich.table import Table

from transfertwin._atomic import write_atomic, write_bytes_atomic
from transfertwin._errors import InputError
from transfertwin.cli._common import positive_int
from transfertwin.cli._paths import out_file
from transfertwin.cli._progress import progress_bar

__all__ = ["register"]


def _stations(text: str) -> list[str]:
    from transfertwin.navigation import STATION_NAMES

    names = [s.strip().upper() for s in text.split(",") if s.strip()]
    bad = [s for s in names if s not in STATION_NAMES]
    if not names or bad:
        raise InputError(f"--station expects some of {','.join(STATION_NAMES)}, got {text!r}")
    return list(dict.fromkeys(names))


def _summary(records, real_path) -> Table:
    """Per station and component: emergent (measured by the rig) vs real mean ± SD and KS."""
    import numpy as np

    from transfertwin.navigation import compare_with_real, real_errors_by_unit

    ok = [r for r in records if r.status == "ok"]
    sim = np.array([r.measured for r in ok]).reshape(-1, 3)
    rows = compare_with_real(sim, [r.transfer_unit for r in ok], real_errors_by_unit(real_path))
    table = Table(title="docking error: emergent (simulated, ChArUco-measured) vs real")
    for col in ("unit", "component", "n sim", "sim mean ± SD", "n real", "real mean ± SD",
                "KS D", "KS p"):  # fmt: skip
        table.add_column(col)
    for c in rows:
        sim_stats = f"{c.mean_sim:.2f} ± {c.sd_sim:.2f}"
        real_stats = f"{c.mean_real:.2f} ± {c.sd_real:.2f}"
        name = c.column.removeprefix("dock_err_")
        table.add_row(c.transfer_unit, name, str(c.n_sim), sim_stats, str(c.n_real), real_stats,
                      f"{c.ks_statistic:.2f}", f"{c.ks_pvalue:.3g}")  # fmt: skip
    return table


def cmd_dock(args: argparse.Namespace) -> int:
    """Simulate navigation and docking, measure, write the table, print the comparison."""
    from transfertwin.navigation import default_floor, emergent_docking_errors, records_csv
    from transfertwin.study.docking import read_docking_errors

    stations = _stations(args.station)
    runs = positive_int("--runs", args.runs)
    if args.seed < 0:
        raise InputError(f"--seed must be >= 0, got {args.seed}")
    out = out_file(args.out, (".csv",))
    image = out_file(args.image, (".png",)) if args.image else None
    read_docking_errors(args.real, need_units=True)  # refuse a bad table before the work
    floor = default_floor()
    first = []
    console = Console(stderr=True)
    with progress_bar("docking", console, unit="run") as on_progress:
        records = emergent_docking_errors(
            floor, stations, runs, args.seed, on_progress=on_progress,
            keep=lambda run: first.append(run) if not first else None,
        )  # fmt: skip
    png = None
    if image is not None:
        from transfertwin.report import figure_png, plot_docking_run

        png = figure_png(plot_docking_run(floor, first[0]), dpi=110)
    write_atomic(out, records_csv(records))
    if png is not None:
        write_bytes_atomic(image, png)
    Console().print(_summary(records, args.real))
    failed = sum(r.status != "ok" for r in records)
    if failed:
        print(f"{failed} of {len(records)} runs did not dock (status column)")
    print(out)
    if image is not None:
        print(image)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``dock`` to the subparsers of the `transfertwin` command."""
    p = sub.add_parser(
        "dock",
        help="docking errors that emerge from simulated navigation, laser docking and "
        "ChArUco (compare: `docking` fits and samples a model of measured ones)",
    )
    p.add_argument("--station", default="A,B,C,D",
                   help="station(s) A|B|C|D, comma-separated (default A,B,C,D)")  # fmt: skip
    p.add_argument("--runs", type=int, default=20, help="runs per station (default 20)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--out", required=True, help="FILE.csv with the emergent errors")
    p.add_argument("--image", help="PNG of the first run: grid, path and laser scan")
    p.add_argument("--real", help="real experiments CSV to compare with (default: shipped)")
    p.set_defaults(func=cmd_dock)
