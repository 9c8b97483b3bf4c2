"""Start-up of a spawned study worker: what it imports, against the whole study surface.

A local worker (and a Ray worker) unpickles its entry point by module, so its start-up is
the import of that module: `transfertwin.study.experiment._worker`. The baseline, in the
same run, is what a worker imported while `transfertwin.study` was eager: the whole study
surface (calibration, statistics, analysis). Each is timed in fresh interpreters, best and
median of `--repeats`, interleaved.

    PYTHONPATH=src .venv/bin/python benchmarks/worker_startup.py [--repeats 7]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys

TARGETS = {
    "worker entry (_worker)": "import transfertwin.study.experiment._worker",
    "whole study surface": "import transfertwin.study as s; [getattr(s, n) for n in s.__all__]",
}
HEAVY = ("scipy.stats", "statsmodels", "pandas", "optuna")


def _once(statement: str) -> tuple[float, list[str]]:
    code = (
        "import sys, time\nt = time.perf_counter()\n"
        f"{statement}\n"
        "dt = time.perf_counter() - t\n"
        f"print(dt, *[m for m in {HEAVY!r} if m in sys.modules])\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()  # fmt: skip
    return float(out[0]), out[1:]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    times: dict[str, list[float]] = {name: [] for name in TARGETS}
    loaded: dict[str, list[str]] = {}
    for _ in range(args.repeats):
        for name, statement in TARGETS.items():
            dt, mods = _once(statement)
            times[name].append(dt)
            loaded[name] = mods
    for name, ts in times.items():
        heavy = ", ".join(loaded[name]) or "none"
        print(f"{name:<24} best {min(ts):.3f} s  median {statistics.median(ts):.3f} s  "
              f"heavy modules loaded: {heavy}")  # fmt: skip
    worker, whole = (statistics.median(times[n]) for n in TARGETS)
    print(f"\nworker start-up / whole surface (median): {worker / whole:.2f}")


if __name__ == "__main__":
    main()
