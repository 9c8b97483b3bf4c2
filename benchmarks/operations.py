"""The twin in operation, measured on the emulated plant: the same orders under the TMS's
``nearest-idle`` and ``predictive`` policies (docs/architecture.md, "Operation").

    PYTHONPATH=src .venv/bin/python benchmarks/operations.py --orders 200

For each policy it starts the floor (default ``examples/floor-large.toml``: 8 stations, 3
transport modules, 20 cores) as asset processes on the emulated plant (``--plant-seed``: the
plant's hidden physics, not the twin's, decide every transfer), sends the same seeded
sequence of orders by destination (each object's next destination differs from its last
two), at most one order per object and one per module in flight, and reads every finished
operation back from the TMS. An object lost in the gap is freed by an operator and put on
the unit of the leg that lost it (`Locate`) before its next order. ``predictive`` loads each
object in the twin's best state from a study store of the floor's cores (made first,
``--runs`` runs per state of the 28-state grid, docking errors from the fitted generator),
``nearest-idle`` in the default state. ``predictive`` also learns from the floor's own
transfers (`cps.dispatch._learn`: each finished transfer updates the twin's per-state shares of its
object, pick-up and delivery); ``twin-only`` is the same policy with ``learn = false``, the
ablation that shows what the twin's study alone is worth on this plant; ``learning-alone``
is the same policy with ``twin = false`` (every state of the grid from a flat prior, ranked
by the floor's transfers only), the baseline that shows what the twin adds to learning
(``predictive - learning-alone``).

Prints, per policy: orders, delivered, success share with its Clopper–Pearson 95 % interval,
operations per hour of modelled floor time (each operation's ``floor_s``: driving from the
planner, docking, the transfers' simulated time; the work divided among the modules) with a
bootstrap 95 % interval; then each arm minus nearest-idle, and predictive minus
learning-alone: the success-share difference with its Newcombe interval (better, worse, or
undecided where the interval holds 0) and the operations-per-hour difference with a
bootstrap interval.
``--camera`` runs the predictive policy a second time with the modules' depth cameras in
the loop (floor ``sensor = "camera"``) and says whether its success share lies inside the
ground-truth run's interval. Writes ``benchmarks/results/operations.json``.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import random
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BOOTSTRAP = 4000


def tt(*args: str, timeout: float = 600) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "transfertwin", *args], capture_output=True,
                          text=True, timeout=timeout)  # fmt: skip


def make_study(floor, path: Path, runs: int, seed: int) -> None:
    """The twin's study of the floor's cores (the predictive policy's store)."""
    from transfertwin.cps.apps import docking_model
    from transfertwin.store import SQLiteResultStore
    from transfertwin.study.experiment import StudyPlan, run_study

    objects = tuple(o for o, _ in floor.objects)
    plan = StudyPlan(objects, 30, runs, seed, docking_model())
    store = SQLiteResultStore(path)
    t0 = time.monotonic()

    def progress(done: int, total: int) -> None:
        if done % 200 == 0 or done == total:
            print(f"  study: {done}/{total} experiments ({time.monotonic() - t0:.0f} s)",
                  flush=True)  # fmt: skip

    try:
        run_study(plan, store, workers=2, on_progress=progress)
    finally:
        store.close()


def order_sequence(floor, n: int, seed: int) -> list[tuple[str, str]]:
    """`n` orders (object, destination unit): each object's destination differs from its
    last two (so it is never ordered to where it lies, whatever failed before)."""
    rng = random.Random(seed)
    history = {o: [at] for o, at in floor.objects}
    out = []
    for _ in range(n):
        obj = rng.choice(sorted(history))
        dest = rng.choice([u for u in floor.units if u not in history[obj][-2:]])
        history[obj].append(dest)
        out.append((obj, dest))
    return out


class Tms:
    def __init__(self, wd: Path) -> None:
        from transfertwin.cli._cps_client import load_info

        self.info, self.creds = load_info(wd)

    def __call__(self, op: str, *args):
        from transfertwin.cli._cps_client import call_asset

        return asyncio.run(call_asset(self.info, self.creds, "TMS", op, *args, timeout_s=20))


def drive(wd: Path, orders: list[tuple[str, str]], inflight: int, timeout_s: float) -> dict:
    """Send `orders` to the floor in `wd`; returns the finished operations and counts."""
    from transfertwin.cps.opcua import OperationRefused

    tms = Tms(wd)
    units = {a["id"] for a in tms.info["assets"] if a["class"] == "transfer_unit"}
    pending = list(orders)
    running: dict[str, str] = {}  # object -> operation
    refused, located, retried = [], 0, 0
    t0 = time.monotonic()
    while pending or running:
        if time.monotonic() - t0 > timeout_s:
            raise SystemExit(f"orders did not finish within {timeout_s:g} s")
        ops = {o["operation"]: o for o in json.loads(tms("Orders"))}
        for obj, op in list(running.items()):
            if ops[op]["state"] in ("done", "failed"):
                del running[obj]
        ledger = None
        while pending and len(running) < inflight:
            nxt = next((i for i, (o, _) in enumerate(pending) if o not in running), None)
            if nxt is None:
                break
            obj, dest = pending.pop(nxt)
            ledger = ledger or json.loads(tms("Ledger"))
            if obj in ledger["unknown"]:  # an operator frees it and puts it on the unit
                lost = json.loads(tms("OperationStatus", ledger["unknown"][obj]["operation"]))
                leg = lost["result"].get("status", "")  # of the failed leg (pick-up: source)
                unit = lost["source"] if "pick-up" in leg else lost["target"]
                if unit not in units:
                    unit = lost["target"]
                tms("Locate", obj, unit)
                located += 1
                ledger = json.loads(tms("Ledger"))
            try:
                running[obj] = tms("OrderTo", obj, dest)
            except OperationRefused as exc:
                if exc.status == "BadResourceUnavailable":  # no module now: try again later
                    pending.insert(nxt, (obj, dest))
                    retried += 1
                    break
                refused.append({"object": obj, "destination": dest, "reason": exc.reason})
        done = len(orders) - len(pending) - len(running)
        print(f"\r  {done}/{len(orders)} orders ended ({time.monotonic() - t0:.0f} s)", end="",
              flush=True)  # fmt: skip
        time.sleep(0.5)
    print(flush=True)
    ledger = json.loads(tms("Ledger"))
    kpis = json.loads(tms("Kpis"))
    return {"operations": ledger["operations"], "refused": refused, "located": located,
            "retried": retried, "kpis": kpis,
            "wall_s": round(time.monotonic() - t0, 1)}  # fmt: skip


def summarise(ops: list[dict], modules: int, rng: np.random.Generator) -> dict:
    from transfertwin.cps.dispatch import is_fault
    from transfertwin.study.fullstate import clopper_pearson

    ended = [o for o in ops if o["state"] == "finished"]
    faults = [o for o in ended if is_fault(o["result"])]  # not transfer outcomes: apart
    finished = [o for o in ended if not is_fault(o["result"])]
    ok = np.array([o["result"].get("status") == "delivered" for o in finished], dtype=float)
    floor_s = np.array([float(o["result"].get("floor_s") or 0.0) for o in finished])
    ci = clopper_pearson(int(ok.sum()), len(ok))

    def per_hour(ok_, s_):
        return 3600.0 * ok_.sum() / (s_.sum() / modules)

    idx = rng.integers(0, len(ok), size=(BOOTSTRAP, len(ok)))
    boot = np.array([per_hour(ok[i], floor_s[i]) for i in idx])
    return {"n": len(ok), "delivered": int(ok.sum()), "share": float(ok.mean()),
            "share_ci95": [ci.low, ci.high], "ops_per_floor_hour": per_hour(ok, floor_s),
            "ops_ci95": [float(np.percentile(boot, 2.5)), float(np.percentile(boot, 97.5))],
            "boot": boot, "failed_by_reason": _reasons(finished),
            "faults": len(faults)}  # fmt: skip


def _by_leg(ops: list[dict]) -> dict[str, int]:
    """Finished operations by outcome and the leg it came from (delivered, failed at
    pick-up / delivery, and of those the ones that failed before any transfer)."""
    out: dict[str, int] = {}
    for o in ops:
        if o["state"] != "finished":
            continue
        r = o["result"]
        key = r.get("status", "?")
        if r.get("failed_step") not in (None, "transferring"):
            key += f" ({r['failed_step']})"
        out[key] = out.get(key, 0) + 1
    return dict(sorted(out.items()))


def _reasons(finished: list[dict]) -> dict[str, int]:
    out: dict[str, int] = {}
    for o in finished:
        r = o["result"]
        if r.get("status") != "delivered":
            key = f"failed while {r.get('failed_step')}"
            out[key] = out.get(key, 0) + 1
    return out


def run_arm(args, floor, name: str, policy: str, floor_file: str, study: Path, wd: Path,
            orders: list, rng: np.random.Generator) -> dict | None:  # fmt: skip
    """Start the floor of one arm, drive the orders, stop it; the arm's summary."""
    pwd = wd / name
    print(f"{name}: starting {floor.name} on plant seed {args.plant_seed}", flush=True)
    up = tt("cps", "up", "--floor", floor_file, "--workdir", str(pwd), "--detach",
            "--time-scale", "0", "--seed", str(args.seed), "--plant-seed",
            str(args.plant_seed), "--policy", policy, "--study", str(study),
            "--lease", str(args.lease), "--start-timeout", "600", timeout=900)  # fmt: skip
    if up.returncode != 0:
        print(up.stderr, file=sys.stderr)
        return None
    try:
        run = drive(pwd, orders, len(floor.modules), args.timeout)
    finally:
        tt("cps", "down", "--workdir", str(pwd))
    r = {**summarise(run["operations"], len(floor.modules), rng),
         "refused": run["refused"], "located": run["located"],
         "retried": run["retried"], "wall_s": run["wall_s"],
         "by_leg": _by_leg(run["operations"])}  # fmt: skip
    print(f"{name}: {r['delivered']}/{r['n']} delivered, share {r['share']:.3f} "
          f"{[round(v, 3) for v in r['share_ci95']]}; {r['by_leg']}", flush=True)
    return r


def camera_only(args, floor, arm: tuple[str, str, str], study: Path, wd: Path, orders: list,
                rng: np.random.Generator, res: Path) -> int:  # fmt: skip
    """The camera arm alone, against the stored predictive run of the same orders."""
    before = json.loads(res.read_text()) if res.is_file() else {}
    same = {"orders": args.orders, "floor": floor.name, "plant_seed": args.plant_seed,
            "seed": args.seed, "runs": args.runs}  # fmt: skip
    if any(before.get(k) != v for k, v in same.items()) or "predictive" not in before.get(
            "policies", {}):  # fmt: skip
        raise SystemExit(f"--camera-only: {res} holds no predictive run of these orders "
                         f"({same}); run without --camera-only first")  # fmt: skip
    name, policy, floor_file = arm
    c = run_arm(args, floor, name, policy, floor_file, study, wd, orders, rng)
    if c is None:
        return 1
    c.pop("boot")
    b = before["policies"]["predictive"]
    lo, hi = b["share_ci95"]
    inside = lo <= c["share"] <= hi
    print(f"camera in the loop: success share {c['share']:.3f} "
          f"{[round(v, 3) for v in c['share_ci95']]}, {'inside' if inside else 'OUTSIDE'} the "
          f"ground-truth run's interval [{lo:.3f}, {hi:.3f}] ({b['share']:.3f}); failures "
          f"{c['failed_by_reason'] or 'none'}")  # fmt: skip
    before["policies"][name] = c
    res.write_text(json.dumps(before, indent=2) + "\n")
    print(f"wrote {res}")
    return 0


def main() -> int:
    from transfertwin.cps import load_floor
    from transfertwin.study.validation import newcombe_difference

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--floor", default=str(ROOT / "examples" / "floor-large.toml"))
    ap.add_argument("--orders", type=int, default=200)
    ap.add_argument("--plant-seed", type=int, default=7)
    ap.add_argument("--seed", type=int, default=0, help="orders, study and floor seed")
    ap.add_argument("--runs", type=int, default=4, help="study runs per state (default 4)")
    ap.add_argument("--study", help="an existing study store of the floor's cores")
    ap.add_argument("--workdir", help="where floors and the study go (default: a temp dir)")
    ap.add_argument("--timeout", type=float, default=3600.0, help="per policy, seconds")
    ap.add_argument("--camera", action="store_true",
                    help="also run predictive with the modules' cameras in the loop")
    ap.add_argument("--camera-only", action="store_true",
                    help="run only the camera arm; compare it with the predictive run of the "
                         "same orders in benchmarks/results/operations.json and add it there")
    ap.add_argument("--lease", type=float, default=30.0,
                    help="the floor's lease, s (default 30: a 35-process floor on a loaded "
                         "2-core host misses 5 s heartbeats)")  # fmt: skip
    args = ap.parse_args()
    floor = load_floor(args.floor)
    wd = Path(args.workdir or tempfile.mkdtemp(prefix="operations-"))
    wd.mkdir(parents=True, exist_ok=True)
    study = Path(args.study) if args.study else wd / "study.sqlite"
    if not args.study:
        print(f"study of {len(floor.objects)} cores x 28 states x {args.runs} runs -> {study}")
        make_study(floor, study, args.runs, args.seed)
    orders = order_sequence(floor, args.orders, args.seed)
    rng = np.random.default_rng(args.seed)
    out: dict[str, dict] = {}
    text = Path(args.floor).read_text()
    if "[operation]" in text:
        raise SystemExit("the floor file has an [operation] table already")

    def variant(name: str, table: str) -> str:
        path = wd / f"floor-{name}.toml"
        path.write_text(text + f"\n[operation]\n{table}\n")
        return str(path)

    runs = [("nearest-idle", "nearest-idle", args.floor),
            ("learning-alone", "predictive", variant("learning-alone", "twin = false")),
            ("twin-only", "predictive", variant("twin-only", "learn = false")),
            ("predictive", "predictive", args.floor)]  # fmt: skip
    res = ROOT / "benchmarks" / "results" / "operations.json"
    if args.camera or args.camera_only:  # the same floor with the modules' cameras in the loop
        runs.append(("predictive+camera", "predictive", variant("camera", 'sensor = "camera"')))
    if args.camera_only:
        return camera_only(args, floor, runs[-1], study, wd, orders, rng, res)
    for name, policy, floor_file in runs:
        out[name] = run_arm(args, floor, name, policy, floor_file, study, wd, orders, rng)
        if out[name] is None:
            return 1
    b = out["predictive"]
    diffs = {}
    # each arm against nearest-idle, and the twin's part: twin + learning against learning
    for name, base in (("learning-alone", "nearest-idle"), ("twin-only", "nearest-idle"),
                       ("predictive", "nearest-idle"), ("predictive", "learning-alone")):
        r, a0 = out[name], out[base]
        d = newcombe_difference(r["delivered"], r["n"], a0["delivered"], a0["n"])
        dboot = r["boot"] - a0["boot"]
        diffs[f"{name} - {base}"] = {
            "share": d, "ops": r["ops_per_floor_hour"] - a0["ops_per_floor_hour"],
            "ops_ci95": [float(np.percentile(dboot, 2.5)), float(np.percentile(dboot, 97.5))]}
    for r in out.values():
        r.pop("boot")
    print(f"\n{args.orders} orders on {floor.name}, plant seed {args.plant_seed}")
    print(f"{'policy':<18}{'n':>5}{'deliv.':>8}{'success share [95% CP]':>30}"
          f"{'ops/floor-hour [95% boot.]':>32}{'refused':>9}")
    for policy, r in out.items():
        lo, hi = r["share_ci95"]
        olo, ohi = r["ops_ci95"]
        share = f"{r['share']:.3f} [{lo:.3f}, {hi:.3f}]"
        ops = f"{r['ops_per_floor_hour']:.1f} [{olo:.1f}, {ohi:.1f}]"
        print(f"{policy:<18}{r['n']:>5}{r['delivered']:>8}{share:>30}{ops:>32}"
              f"{len(r['refused']):>9}")
    for name, d in diffs.items():
        sd, (olo, ohi) = d["share"], d["ops_ci95"]
        verdict = ("better" if sd.low > 0 else "worse" if sd.high < 0 else "undecided")
        print(f"{name}: success share {sd.estimate:+.3f} "
              f"[{sd.low:+.3f}, {sd.high:+.3f}] (Newcombe: {verdict}); "
              f"ops/floor-hour {d['ops']:+.1f} [{olo:+.1f}, {ohi:+.1f}] (bootstrap)")
    if "predictive+camera" in out:
        c = out["predictive+camera"]
        inside = b["share_ci95"][0] <= c["share"] <= b["share_ci95"][1]
        print(f"camera in the loop: success share {c['share']:.3f}, "
              f"{'inside' if inside else 'OUTSIDE'} the ground-truth run's interval "
              f"[{b['share_ci95'][0]:.3f}, {b['share_ci95'][1]:.3f}]")
    for policy, r in out.items():
        print(f"{policy}: failures {r['failed_by_reason'] or 'none'}; objects located by an "
              f"operator {r['located']}; refused {[x['reason'] for x in r['refused']]}")
    result = {"orders": args.orders, "floor": floor.name, "plant_seed": args.plant_seed,
              "seed": args.seed, "runs": args.runs, "policies": out,
              "differences": {name: {
                  "share": d["share"].estimate,
                  "share_ci95": [d["share"].low, d["share"].high],
                  "ops_per_floor_hour": d["ops"],
                  "ops_per_floor_hour_ci95": d["ops_ci95"]} for name, d in diffs.items()}}
    res.write_text(json.dumps(result, indent=2) + "\n")
    print(f"wrote {res}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
