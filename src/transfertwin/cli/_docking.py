"""`transfertwin docking …`: fit, sample and plot the synthetic docking-error generator (Sec. 6.4).

Thin: one function per subcommand calling the public API. Bad input raises `InputError`
(exit code 2 in `transfertwin.cli.main`); every output is written to a temporary file and
moved into place, so a failed command leaves no partial file.

    docking fit CSV --out MODEL.json [--per-station]
    docking sample MODEL.json -n N [--seed S] --out SAMPLES.csv
    docking plot CSV MODEL.json --out DIR [-n N] [--seed S]
"""

from __future__ import annotations

import argparse
import csv
import io
import json

from transfertwin._atomic import write_atomic
from transfertwin.cli._common import positive_int
from transfertwin.cli._paths import out_dir, out_file

__all__ = ["register"]

HISTOGRAMS_PNG = "docking_histograms.png"
CORRELATIONS_PNG = "docking_correlations.png"


def cmd_docking_fit(args: argparse.Namespace) -> int:
    """Fit a Gaussian copula (or one per transfer unit) and save it as JSON."""
    from transfertwin.store import DOCKING_ERROR_COLUMNS
    from transfertwin.study.docking import GaussianCopula, PerStationCopula, read_docking_errors

    out = out_file(args.out, (".json",))
    errors, units = read_docking_errors(args.csv, args.per_station)
    if units is not None:
        model = PerStationCopula.fit(errors, units)
        models = dict(zip(model.units, model.copulas, strict=True))
    else:
        model = GaussianCopula.fit(errors)
        models = {"all": model}
    write_atomic(out, json.dumps(model.to_dict(), indent=1) + "\n")
    for name, cop in models.items():
        for col, m in zip(DOCKING_ERROR_COLUMNS, cop.marginals, strict=True):
            ks = m.score.ks_statistic
            print(f"{name} {col}: {m.marginal.family} (KS D = {ks:.3f})")
    print(out)
    return 0


def cmd_docking_sample(args: argparse.Namespace) -> int:
    """Draw N synthetic docking errors from a saved model into a CSV."""
    from transfertwin.store import DOCKING_ERROR_COLUMNS
    from transfertwin.study.docking import STATION_COLUMN, PerStationCopula, load_docking_model

    out = out_file(args.out, (".csv",))
    n = positive_int("-n", args.n)
    model = load_docking_model(args.model)
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    if isinstance(model, PerStationCopula):
        values, units = model.sample_with_units(n, args.seed)
        writer.writerow([*DOCKING_ERROR_COLUMNS, STATION_COLUMN])
        writer.writerows(
            [*(f"{v:.6f}" for v in row), u] for row, u in zip(values, units, strict=True)
        )
    else:
        writer.writerow(DOCKING_ERROR_COLUMNS)
        writer.writerows([f"{v:.6f}" for v in row] for row in model.sample_n(n, args.seed))
    write_atomic(out, buf.getvalue())
    print(out)
    return 0


def cmd_docking_plot(args: argparse.Namespace) -> int:
    """Histograms and correlation matrices of real vs synthetic errors (Fig. 6.9–6.11)."""
    from transfertwin.report import (
        docking_correlation_data,
        docking_hist_data,
        figure_png,
        plot_correlation_matrices,
        plot_docking_histograms,
    )
    from transfertwin.study.docking import load_docking_model, read_docking_errors

    out = out_dir(args.out)
    n = positive_int("-n", args.n)
    real, _ = read_docking_errors(args.csv, need_units=False)
    synthetic = load_docking_model(args.model).sample_n(n, args.seed)
    pngs = {
        HISTOGRAMS_PNG: figure_png(plot_docking_histograms(docking_hist_data(real, synthetic))),
        CORRELATIONS_PNG: figure_png(
            plot_correlation_matrices(docking_correlation_data(real, synthetic))
        ),
    }
    out.mkdir(parents=True, exist_ok=True)
    for name, data in pngs.items():
        write_atomic(out / name, data)
        print(out / name)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``docking fit|sample|plot`` to the subparsers of the `transfertwin` command."""
    docking = sub.add_parser(
        "docking",
        help="docking errors drawn from a model fitted to measured ones, a Gaussian copula "
        "(Sec. 6.4; compare: `dock` simulates how they arise)",
    )
    dsub = docking.add_subparsers(dest="docking_command", required=True, parser_class=type(docking))
    p = dsub.add_parser("fit", help="fit a Gaussian copula to measured docking errors")
    p.add_argument("csv", help="CSV with dock_err_x_mm, dock_err_y_mm, dock_err_theta_deg")
    p.add_argument("--out", required=True, help="model file MODEL.json")
    p.add_argument("--per-station", action="store_true",
                   help="one copula per transfer unit (needs a transfer_unit column)")  # fmt: skip
    p.set_defaults(func=cmd_docking_fit)
    p = dsub.add_parser("sample", help="draw synthetic docking errors from a model")
    p.add_argument("model", help="MODEL.json from `docking fit`")
    p.add_argument("-n", type=int, required=True, help="number of samples")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--out", required=True, help="SAMPLES.csv")
    p.set_defaults(func=cmd_docking_sample)
    p = dsub.add_parser("plot", help="histograms and correlations: real vs synthetic")
    p.add_argument("csv", help="measured docking errors (CSV)")
    p.add_argument("model", help="MODEL.json from `docking fit`")
    p.add_argument("--out", required=True, help="output directory (created if missing)")
    p.add_argument("-n", type=int, default=5000, help="synthetic samples (default 5000)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.set_defaults(func=cmd_docking_plot)
