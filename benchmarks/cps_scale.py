"""How a process floor grows: floors of 10, 50 and 200 asset processes (objects included),
one process per asset on its own loopback address.

    PYTHONPATH=src .venv/bin/python benchmarks/cps_scale.py --sizes 10,50,200

For each size it prints the start-up time (launch until the knowledge graph lists every
asset online: discovery convergence through the leases), the memory of one asset process
(RSS and PSS, median and largest, by class), the CPU the processes spend while the floor
idles, `--settle` seconds after it converged (median asset process, by class, the knowledge
graph, the whole floor, in % of one core), the
traffic on the loopback interface per asset per minute while the floor idles (heartbeats,
gossip), the latency of a status query (the graph's `Status`, median and 95th percentile of
20) and the time the graph takes to see an object process killed with -9 offline (its lease
lapsing). A floor that does not converge within `--converge-timeout` is reported with how
many assets the graph had by then (and measured as it is). A size whose processes would not
fit in the memory available is skipped with the reason (its figures are then a projection,
docs/scaling.md). Ratios against the smallest floor are printed in the same run.

`--lease` left out, each floor runs with the launcher's default lease for its size
(`default_lease`); the load average is printed with every size (the host may be shared).

Asset processes are forked from one prepared process, as `cps up` starts them (they share
the imports and the OPC UA standard address space copy-on-write); the smallest size is
also run with one interpreter per asset (`--baseline`, how a restart by hand starts one),
and the memory ratio of the two is printed.

Then the credentials of the largest size are prepared both ways in the same run
(`--credentials N`, 0: not): the floor CA's (what ``cps up`` does) and the pinned lists of
before (`cps_certificates.compare`), wall clock and CPU seconds each.

Objects beyond the 37 built-in cores are ids only here: nothing is transported.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
import statistics
import sys
import tempfile
import time
from pathlib import Path


def floor_of(n: int):
    """A floor of `n` asset processes: KG, TMS, one module per 25 assets, one station per
    10, the rest objects."""
    from transfertwin.cps import FloorSpec, ModuleSpec, StationSpec

    modules = max(1, n // 25)
    stations = max(2, n // 10)
    objects = n - 2 - modules - stations
    if objects < 1:
        raise SystemExit(f"--sizes: {n} is too small for a floor (at least 5)")
    width = 4.0 + 4.5 * ((stations + 1) // 2)
    st = tuple(StationSpec(f"S{i}", 3.0 + 4.5 * (i // 2), 10.6 if i % 2 == 0 else 1.4,
                           90.0 if i % 2 == 0 else -90.0, "left")
               for i in range(stations))  # fmt: skip
    mods = tuple(ModuleSpec(f"TM_{i + 1}", 3.0 + 2.0 * i, 6.0) for i in range(modules))
    objs = tuple((f"o{i + 1}", st[i % stations].unit) for i in range(objects))
    return FloorSpec(f"scale{n}", (width, 12.0), st, mods, objs, ("KG", "TMS"))


def projected_mb(n: int, pss_by_class: dict[str, float]) -> float:
    """The PSS a floor of `n` would take, MB: each class's median PSS (measured on a smaller
    floor) times how many of that class `floor_of(n)` holds (a larger floor is mostly
    objects, the lightest processes; a mean over the small floor would overstate it)."""
    spec = floor_of(n)
    counts = {"KG": 1, "TMS": 1, "TM": len(spec.modules), "TU": len(spec.stations),
              "object": len(spec.objects)}
    heaviest = max(pss_by_class.values())
    return sum(c * pss_by_class.get(k, heaviest) for k, c in counts.items())


def memory(pid: int) -> tuple[float, float]:
    """(RSS, PSS) of a process, MB."""
    rss = pss = 0.0
    try:
        for line in Path(f"/proc/{pid}/smaps_rollup").read_text().splitlines():
            if line.startswith("Rss:"):
                rss = float(line.split()[1]) / 1024
            elif line.startswith("Pss:"):
                pss = float(line.split()[1]) / 1024
    except OSError:
        pass
    return rss, pss


def cpu_s(pid: int) -> float:
    """User + system CPU seconds a process has used so far (0 once it is gone)."""
    import os

    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def load_average() -> float:
    return float(Path("/proc/loadavg").read_text().split()[0])


def lo_bytes() -> int:
    base = Path("/sys/class/net/lo/statistics")
    return int((base / "rx_bytes").read_text())


def available_mb() -> float:
    for line in Path("/proc/meminfo").read_text().splitlines():
        if line.startswith("MemAvailable:"):
            return float(line.split()[1]) / 1024
    return 0.0


async def status_latency(wd: Path, repeats: int = 20) -> list[float]:
    from transfertwin.cps.opcua import connect, load_credentials

    info = json.loads((wd / "cps.json").read_text())
    kg = next(a["endpoint"] for a in info["assets"] if a["id"] == "KG")
    creds = load_credentials(Path(info["credentials_file"]))
    out = []
    async with connect(kg, "KG", credentials=creds, cert_dir=Path(info["cert_dir"]),
                       timeout_s=30) as s:  # fmt: skip
        for _ in range(repeats):
            t0 = time.perf_counter()
            await s.call("Status")
            out.append(time.perf_counter() - t0)
    return out


def run_size(n: int, base: Path, lease: float | None, idle_s: float,
             pss_by_class: dict[str, float] | None, fork: bool = True,
             converge_s: float | None = None, settle_s: float = 0.0):  # fmt: skip
    from transfertwin._errors import InputError
    from transfertwin.cli._cps_floor import _wait_online, floor_status
    from transfertwin.cps import asset_pids, launch, prepare_floor, stop_floor, write_floor_info

    need = None if pss_by_class is None else projected_mb(n, pss_by_class) * 1.5
    if need is not None and need > available_mb():
        return {"n": n, "skipped": f"needs about {need / 1024:.1f} GB, "
                                   f"{available_mb() / 1024:.1f} GB available"}  # fmt: skip
    floor = floor_of(n)
    wd = base / f"floor{n}{'' if fork else '-exec'}"
    t0 = time.monotonic()
    configs = prepare_floor(floor, wd, time_scale=0.0,
                            **({} if lease is None else {"lease_s": lease}))  # fmt: skip
    lease_s = next(iter(configs.values())).lease_s
    t_prep = time.monotonic() - t0
    write_floor_info(wd, configs, floor)
    t1 = time.monotonic()
    procs = launch(configs, wd, fork=fork)
    converged, online = True, n
    try:
        try:
            _wait_online(wd, set(procs), converge_s or 60.0 + 3.0 * n, procs)
        except InputError as exc:
            if "did not come up" not in str(exc):
                raise
            converged = False
            try:
                doc = floor_status(wd, with_objects=False)
                online = sum(a["online"] for a in doc["assets"])
            except Exception:
                online = 0
        t_up = time.monotonic() - t1
        time.sleep(settle_s)  # the start's tail (modules warming up, first gossip rounds)
        pids = asset_pids(wd)
        mem = {aid: memory(pid) for aid, pid in pids.items()}
        b0, m0 = lo_bytes(), time.monotonic()
        c0 = {aid: cpu_s(pid) for aid, pid in pids.items()}
        time.sleep(idle_s)
        c1 = {aid: cpu_s(pid) for aid, pid in pids.items()}
        span = time.monotonic() - m0
        traffic = (lo_bytes() - b0) / span * 60.0 / n
        load = load_average()
        cpu = {aid: max(0.0, c1[aid] - c0[aid]) / span for aid in pids}
        lat = asyncio.run(status_latency(wd)) if converged else [float("nan")]
        detect = detection_s(wd, pids, lease_s) if converged else None
    finally:
        stop_floor(wd)
        for p in procs.values():
            try:
                p.wait(30)
            except Exception:
                p.kill()
    by_class: dict[str, list[float]] = {}
    cpu_class: dict[str, list[float]] = {}
    for aid, (_, pss) in mem.items():
        cls = configs[aid].asset_id.split("_")[0] if aid[0] != "o" else "object"
        by_class.setdefault(cls, []).append(pss)
        cpu_class.setdefault(cls, []).append(100 * cpu.get(aid, 0.0))
    rss = [r for r, _ in mem.values()]
    pss = [p for _, p in mem.values()]
    return {"n": n, "fork": fork, "lease_s": lease_s, "converged": converged, "online": online,
            "prepare_s": t_prep, "startup_s": t_up,
            "rss_median_mb": statistics.median(rss), "rss_max_mb": max(rss),
            "pss_median_mb": statistics.median(pss), "pss_total_mb": sum(pss),
            "pss_by_class": {k: round(statistics.median(v), 1) for k, v in by_class.items()},
            "cpu_median_pct": 100 * statistics.median(cpu.values()),
            "cpu_kg_pct": 100 * cpu.get("KG", 0.0), "cpu_floor_pct": 100 * sum(cpu.values()),
            "cpu_by_class_pct": {k: round(statistics.median(v), 2) for k, v in cpu_class.items()},
            "load": load, "lo_bytes_per_asset_min": traffic,
            "status_median_ms": 1000 * statistics.median(lat),
            "status_p95_ms": 1000 * sorted(lat)[int(0.95 * (len(lat) - 1))],
            "detect_s": detect}  # fmt: skip


def detection_s(wd: Path, pids: dict[str, int], lease_s: float) -> float | None:
    """Kill one object's process with -9 and time until the graph lists it offline (its
    lease lapsing: no leave is announced); None when it is not seen within 3 leases."""
    import os
    import signal

    from transfertwin.cli._cps_floor import floor_status

    victim = max(a for a in pids if a.startswith("o"))
    os.kill(pids[victim], signal.SIGKILL)
    t0 = time.monotonic()
    while time.monotonic() - t0 < 3 * lease_s + 10:
        try:
            doc = floor_status(wd, with_objects=False)
        except Exception:
            doc = None
        if doc and not next(a for a in doc["assets"] if a["id"] == victim)["online"]:
            return time.monotonic() - t0
        time.sleep(0.2)
    return None


def main() -> int:
    logging.getLogger("asyncua").setLevel(logging.ERROR)  # one warning per session otherwise
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="10,50,200")
    ap.add_argument("--lease", type=float, default=None,
                    help="lease in seconds (default: the launcher's for the floor's size)")
    ap.add_argument("--converge-timeout", type=float, default=None,
                    help="seconds a floor may take to converge (default 60 + 3 per asset)")
    ap.add_argument("--idle", type=float, default=30.0, help="seconds of idle traffic measured")
    ap.add_argument("--settle", type=float, default=15.0,
                    help="seconds a converged floor idles before it is measured")
    ap.add_argument("--workdir")
    ap.add_argument("--credentials", type=int, default=None, metavar="N",
                    help="also prepare N assets' credentials both ways, the floor CA and the "
                         "pinned lists of before (default: the largest size; 0: not)")
    ap.add_argument("--no-baseline", dest="baseline", action="store_false",
                    help="skip the smallest size with one interpreter per asset")
    args = ap.parse_args()
    try:
        sizes = [int(s) for s in args.sizes.split(",")]
    except ValueError:
        ap.error(f"--sizes: a comma-separated list of integers, got {args.sizes!r}")
    base = Path(args.workdir or tempfile.mkdtemp(prefix="cps-scale-"))
    rows = []
    by_class: dict[str, float] | None = None  # the largest median PSS per class so far
    runs = [(sizes[0], False)] if args.baseline else []
    for n, fork in [*runs, *((n, True) for n in sizes)]:
        row = run_size(n, base, args.lease, args.idle, by_class if fork else None, fork,
                       args.converge_timeout, args.settle)  # fmt: skip
        rows.append(row)
        if "skipped" in row:
            print(f"{n:4d} assets: skipped ({row['skipped']})", flush=True)
            continue
        if fork:
            by_class = {k: max(v, (by_class or {}).get(k, 0.0))
                        for k, v in row["pss_by_class"].items()}  # fmt: skip
        how = "forked" if fork else "one interpreter each (baseline)"
        up = (f"up in {row['startup_s']:.1f} s" if row["converged"] else
              f"NOT converged: {row['online']} of {n} online after {row['startup_s']:.0f} s")
        detect = "not seen" if row["detect_s"] is None else f"{row['detect_s']:.1f} s"
        print(f"{n:4d} assets, {how}, lease {row['lease_s']:g} s: {up} (certificates "
              f"{row['prepare_s']:.1f} s before), RSS median {row['rss_median_mb']:.0f} MB "
              f"(max {row['rss_max_mb']:.0f}), PSS median {row['pss_median_mb']:.0f} MB, "
              f"total PSS {row['pss_total_mb'] / 1024:.2f} GB, by class {row['pss_by_class']}, "
              f"idle CPU: median asset {row['cpu_median_pct']:.2f} %, graph "
              f"{row['cpu_kg_pct']:.1f} %, floor {row['cpu_floor_pct']:.0f} % of a core, "
              f"median by class {row['cpu_by_class_pct']}, "
              f"loopback {row['lo_bytes_per_asset_min'] / 1024:.1f} KiB per asset per min, "
              f"status {row['status_median_ms']:.1f} ms (p95 {row['status_p95_ms']:.1f}), "
              f"a kill -9 seen offline in {detect}; load average {row['load']:.1f}",
              flush=True)  # fmt: skip
    base_row = next((r for r in rows if r.get("fork") is False), None)
    same = next((r for r in rows if r.get("fork") and base_row and r["n"] == base_row["n"]),
                None)  # fmt: skip
    if base_row and same:
        print(f"{same['n']} assets, forked vs one interpreter each: PSS per asset "
              f"{same['pss_total_mb'] / base_row['pss_total_mb']:.2f}x "
              f"({same['pss_total_mb'] / same['n']:.0f} vs "
              f"{base_row['pss_total_mb'] / base_row['n']:.0f} MB), start-up "
              f"{same['startup_s'] / base_row['startup_s']:.2f}x")  # fmt: skip
    done = [r for r in rows if "skipped" not in r and r.get("fork") and r["converged"]]
    if len(done) > 1:
        a = done[0]
        for r in done[1:]:
            k = r["n"] / a["n"]
            print(f"{r['n']} vs {a['n']} assets ({k:.0f}x): start-up "
                  f"{r['startup_s'] / a['startup_s']:.1f}x, traffic per asset "
                  f"{r['lo_bytes_per_asset_min'] / a['lo_bytes_per_asset_min']:.2f}x, "
                  f"idle CPU per asset {r['cpu_median_pct'] / a['cpu_median_pct']:.2f}x, "
                  f"status latency {r['status_median_ms'] / a['status_median_ms']:.1f}x, "
                  f"PSS per asset "
                  f"{r['pss_total_mb'] / r['n'] / (a['pss_total_mb'] / a['n']):.2f}x")  # fmt: skip
    n_cred = max(sizes) if args.credentials is None else args.credentials
    if n_cred > 0:  # what the floor's certificates cost, against the way before, same run
        from cps_certificates import compare

        print(f"credentials of {n_cred} assets, both ways:")
        print("\n".join(compare(n_cred)), flush=True)
    print(json.dumps(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
