"""The twin in operation, measured on the emulated plant: the same orders under the TMS's
policies (docs/architecture.md, "Operation"): does the twin earn its place beside learning
from the floor's own transfers?

    PYTHONPATH=src .venv/bin/python benchmarks/operations.py --orders 200
    PYTHONPATH=src .venv/bin/python benchmarks/operations.py --regime cold-start \
        --plant-kind mismatch --plant-seeds 11,12,13 --campaign

Arms (each a floor of asset processes started anew on the same plant, the same orders):

- ``nearest-idle``: the default state, no twin, no learning;
- ``learning-alone``: every state of the grid from a flat prior, ranked by the floor's own
  transfers only (``[operation] twin = false``);
- ``twin-only``: the uncalibrated twin's predictions of both legs, no learning
  (``learn = false``);
- ``predictive``: the uncalibrated twin + learning (the default policy);
- with ``--campaign``: ``calibrated-only`` and ``calibrated``: the same two after a
  calibration campaign on the floor's own physical units (``cps campaign start --wait``),
  whose floor time is counted in the arm's operations per floor hour.

Regimes: **steady** (``--orders`` orders over the floor's objects, default
``examples/floor-large.toml``: 8 stations, 3 modules, 20 cores; each object's next
destination differs from its last two) and **cold start** (a stream of new objects: the
floor's stations hold ``--cold-objects`` cores, 37 by default, that no prediction has seen,
each entering with its first of ``--cold-orders`` orders, 3 by default; the metric is the
success share of each object's first order and of its first three).

The predictive arms of the steady regime rank from a study store of the floor's cores
(made first: ``--runs`` runs per state of the 28-state grid, both legs); in cold start no
store is given: every new object's prediction is the Experiment Manager's on-the-fly one.
An object lost in the gap is freed by an operator and put on the unit of the leg that lost
it (`Locate`) before its next order.

Prints per plant seed and arm: orders, delivered, success share with its Clopper–Pearson
95 % interval (over transfer outcomes; faults apart), operations per hour of modelled floor
time (the campaign's included) with a bootstrap interval, the outcomes by leg and the
states the twin got wrong per leg (its predicted leg probability ≥ ½ and the leg failed,
or < ½ and it succeeded); then, pooled over the seeds, each arm's share and the
differences with their Newcombe intervals (better, worse, or undecided where the interval
holds 0), and the issue's targets with a verdict (met / missed / undecided); a difference
is pooled over the seeds on which both arms ran (`_operations_report.py`). Writes
``benchmarks/results/operations-<regime>-<plant kind>.json``; ``--pool A.json B.json ...``
runs nothing and prints the report of several such outputs (a long run split by seed or
arm) pooled.

``--camera`` runs the predictive policy a second time with the modules' depth cameras in
the loop (steady regime, first seed only) and says whether its success share lies inside
the ground-truth run's interval.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import random
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from _floor_client import Tms, tt
from _operations_report import load_runs, report

ROOT = Path(__file__).resolve().parents[1]
BOOTSTRAP = 4000


def make_study(floor, path: Path, runs: int, seed: int) -> None:
    """The twin's study of the floor's cores, both legs (the predictive policy's store)."""
    from transfertwin.cps.apps import docking_model
    from transfertwin.store import SQLiteResultStore
    from transfertwin.study.experiment import StudyPlan, run_study

    objects = tuple(o for o, _ in floor.objects)
    plan = StudyPlan(objects, 30, runs, seed, docking_model(), leg="operation")
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


def unload_idle(tms, units: set[str], pending: list, running: dict) -> int:
    """An object a module still carries after a failed delivery, with no order of it left
    or running, blocks that module: an operator takes it off onto a unit (`Locate` onto
    its order's destination). Returns how many were taken off."""
    ledger = json.loads(tms("Ledger"))
    wanted = {o for o, _ in pending} | set(running)
    ops = ledger["operations"]
    n = 0
    for obj, at in ledger["locations"].items():
        if at in units or obj in wanted or obj in ledger["moving"]:
            continue
        last = [o for o in ops if o["object"] == obj]
        unit = (last[-1].get("target") or (last[-1].get("targets") or [None])[0]) if last else None
        tms("Locate", obj, unit if unit in units else sorted(units)[0])
        n += 1
    return n


def drive(wd: Path, orders: list[tuple[str, str]], inflight: int, timeout_s: float) -> dict:
    """Send `orders` to the floor in `wd`; returns the finished operations and counts."""
    from transfertwin.cps.opcua import OperationRefused

    tms = Tms(wd)
    units = {a["id"] for a in tms.info["assets"]  # the floor's units: not the plant's
             if a["class"] == "transfer_unit" and a.get("kind") != "physical"}  # fmt: skip
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
        ledger = json.loads(tms("Ledger"))
        while pending:
            # an object a module carries goes on first, past the in-flight limit: while it
            # waits its module takes no other order, and with every module so blocked the
            # orders in flight would wait for ever (seen on seed 23: three failed deliveries)
            carried = {o for o, at in ledger["locations"].items() if at not in units}
            free = [i for i, (o, _) in enumerate(pending) if o not in running]
            nxt = next((i for i in free if pending[i][0] in carried), None)
            if nxt is None and len(running) < inflight and free:
                nxt = free[0]
            if nxt is None:
                break
            obj, dest = pending.pop(nxt)
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
                if "outside a pre-transfer state" in exc.reason:  # left on a module where
                    tms("Locate", obj, next(u for u in sorted(units) if u != dest))  # no
                    located += 1  # transfer starts: an operator puts it on a unit, and
                    pending.insert(nxt, (obj, dest))  # the order goes from there
                    break
                refused.append({"object": obj, "destination": dest, "reason": exc.reason})
        located += unload_idle(tms, units, pending, running)  # a module kept blocked
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


def cold_floor(floor, n: int, seed: int):
    """The floor with `n` new cores (o1, o2, …) on its stations, in a seeded order, round
    robin: the cold start's stream of objects no prediction has seen."""
    from transfertwin.objects import builtin_ids

    ids = list(builtin_ids())[:n]
    random.Random(seed).shuffle(ids)
    units = list(floor.units)
    return dataclasses.replace(floor, objects=tuple((o, units[i % len(units)])
                                                    for i, o in enumerate(ids)))  # fmt: skip


def cold_orders(floor, per_object: int, seed: int) -> list[tuple[str, str]]:
    """Each object's `per_object` orders in a row (it enters with the first), objects in
    the floor's order; each destination differs from the object's last two places."""
    rng = random.Random(seed)
    out = []
    for obj, at in floor.objects:
        history = [at]
        for _ in range(per_object):
            dest = rng.choice([u for u in floor.units if u not in history[-2:]])
            history.append(dest)
            out.append((obj, dest))
    return out


def _leg_outcomes(result: dict) -> dict[str, int]:
    """y of each leg that ran a transfer (its last try)."""
    out = {}
    for leg in result.get("legs") or []:
        tr = leg.get("transferring")
        if isinstance(tr, dict) and tr.get("valid"):
            out[leg.get("leg")] = int(tr.get("y") or 0)
    return out


def twin_wrong(ops: list[dict]) -> dict[str, dict[str, int]]:
    """Per leg, how often the twin's prediction of the chosen state (its leg probability
    before the floor's evidence, `twin_priors`) was on the wrong side of ½, and of how many
    legs it predicted."""
    from transfertwin.cps.dispatch import twin_priors

    out = {leg: {"predicted": 0, "wrong": 0, "wrong_states": {}}
           for leg in ("pick-up", "delivery")}  # fmt: skip
    for o in ops:
        pred = ((o.get("plan") or {}).get("prediction")) or {}
        if o["state"] != "finished" or not pred.get("n"):
            continue
        priors = twin_priors(pred)
        for leg, y in _leg_outcomes(o["result"]).items():
            m, w = priors[leg]
            if w <= 2.0 and m == 0.5:  # Laplace: the twin did not predict this leg
                continue
            out[leg]["predicted"] += 1
            if (m >= 0.5) != bool(y):
                out[leg]["wrong"] += 1
                key = f"{o['object']} {pred['face']}/{pred['conveyor']}/{pred['theta_deg']}"
                out[leg]["wrong_states"][key] = out[leg]["wrong_states"].get(key, 0) + 1
    return out


def first_orders(ops: list[dict], k: int) -> tuple[int, int]:
    """(delivered, n) over each object's first `k` finished orders (faults apart)."""
    from transfertwin.cps.dispatch import is_fault

    by_obj: dict[str, list[dict]] = {}
    for o in sorted(ops, key=lambda o: float(o["history"][0][0])):
        if o["state"] == "finished":
            by_obj.setdefault(o["object"], []).append(o)
    got = [o for mine in by_obj.values() for o in mine[:k] if not is_fault(o["result"])]
    return sum(o["result"].get("status") == "delivered" for o in got), len(got)


def summarise(ops: list[dict], modules: int, rng: np.random.Generator,
              campaign_s: float = 0.0) -> dict:  # fmt: skip
    from transfertwin.cps.dispatch import is_fault
    from transfertwin.study.fullstate import clopper_pearson

    ended = [o for o in ops if o["state"] == "finished"]
    faults = [o for o in ended if is_fault(o["result"])]  # not transfer outcomes: apart
    finished = [o for o in ended if not is_fault(o["result"])]
    ok = np.array([o["result"].get("status") == "delivered" for o in finished], dtype=float)
    floor_s = np.array([float(o["result"].get("floor_s") or 0.0) for o in finished])
    ci = clopper_pearson(int(ok.sum()), len(ok))

    def per_hour(ok_, s_):  # the campaign's floor time is a cost of the arm
        return 3600.0 * ok_.sum() / ((s_.sum() + campaign_s) / modules)

    idx = rng.integers(0, len(ok), size=(BOOTSTRAP, len(ok)))
    boot = np.array([per_hour(ok[i], floor_s[i]) for i in idx])
    first = {f"first_{k}": first_orders(ops, k) for k in (1, 3)}
    return {"n": len(ok), "delivered": int(ok.sum()), "share": float(ok.mean()),
            "share_ci95": [ci.low, ci.high], "ops_per_floor_hour": per_hour(ok, floor_s),
            "ops_ci95": [float(np.percentile(boot, 2.5)), float(np.percentile(boot, 97.5))],
            "campaign_floor_s": campaign_s, "boot": boot,
            "failed_by_reason": _reasons(finished), "faults": len(faults),
            "twin_wrong": twin_wrong(ended), **first}  # fmt: skip


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


def campaign(pwd: Path, args) -> float:
    """A calibration campaign on the floor's physical units (``cps campaign``); its floor
    seconds (the E^P's transfer time on the plant's clock)."""
    run = tt("cps", "campaign", "start", "--workdir", str(pwd), "--wait",
             "--experiments", str(args.campaign_experiments), "--seed", str(args.seed),
             "--object-prior", args.campaign_object_prior,
             "--min-face-rows", str(args.campaign_min_face_rows),
             "--tune-trials", str(args.campaign_tune_trials), "--runs", str(args.campaign_runs),
             timeout=args.timeout)  # fmt: skip
    if run.returncode != 0:
        raise SystemExit(f"the campaign failed: {run.stderr.strip() or run.stdout[-400:]}")
    st = tt("cps", "campaign", "status", "--workdir", str(pwd), "--json")
    doc = json.loads(st.stdout) if st.returncode == 0 else {}
    s = doc.get("summary") or {}
    if s:
        print(f"  campaign: F0.5 on held-out E^P {s.get('f05_before', float('nan')):.3f} "
              f"before, {s.get('f05_after', float('nan')):.3f} after; folder "
              f"{doc.get('folder')}", flush=True)  # fmt: skip
    return float(doc.get("floor_s") or doc.get("campaign_floor_s") or 0.0)


def run_arm(args, floor, name: str, policy: str, floor_file: str, study: Path | None,
            wd: Path, orders: list, rng: np.random.Generator, plant_seed: int,
            calibrate: bool = False) -> dict | None:  # fmt: skip
    """Start the floor of one arm, (calibrate,) drive the orders, stop it; its summary."""
    pwd = wd / name
    print(f"{name}: starting {floor.name} on the {args.plant_kind} plant of seed "
          f"{plant_seed}", flush=True)  # fmt: skip
    up = tt("cps", "up", "--floor", floor_file, "--workdir", str(pwd), "--detach",
            "--time-scale", "0", "--seed", str(args.seed), "--plant-seed", str(plant_seed),
            "--plant-kind", args.plant_kind, "--policy", policy,
            *(["--plant-mismatch-off", args.mismatch_off] if args.mismatch_off else []),
            *(["--study", str(study)] if study else []),
            "--lease", str(args.lease), "--start-timeout", "600", timeout=900)  # fmt: skip
    if up.returncode != 0:
        print(up.stderr, file=sys.stderr)
        return None
    try:
        campaign_s = campaign(pwd, args) if calibrate else 0.0
        run = drive(pwd, orders, len(floor.modules), args.timeout)
    finally:
        tt("cps", "down", "--workdir", str(pwd))
    r = {**summarise(run["operations"], len(floor.modules), rng, campaign_s),
         "refused": run["refused"], "located": run["located"],
         "retried": run["retried"], "wall_s": run["wall_s"],
         "by_leg": _by_leg(run["operations"])}  # fmt: skip
    print(f"{name}: {r['delivered']}/{r['n']} delivered, share {r['share']:.3f} "
          f"{[round(v, 3) for v in r['share_ci95']]}; first orders {r['first_1']}, first "
          f"three {r['first_3']}; {r['by_leg']}", flush=True)  # fmt: skip
    return r


#: The arms: (name, policy, [operation] settings, campaign first).
ARMS = (
    ("nearest-idle", "nearest-idle", {}, False),
    ("learning-alone", "predictive", {"twin": False}, False),
    ("twin-only", "predictive", {"learn": False}, False),
    ("predictive", "predictive", {}, False),
    ("calibrated-only", "predictive", {"learn": False}, True),
    ("calibrated", "predictive", {}, True),
)
def main() -> int:
    from transfertwin.cps import load_floor
    from transfertwin.cps.floor import floor_toml
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--floor", default=str(ROOT / "examples" / "floor-large.toml"))
    ap.add_argument("--regime", choices=("steady", "cold-start"), default="steady")
    ap.add_argument("--orders", type=int, default=200, help="steady: orders (default 200)")
    ap.add_argument(
        "--cold-objects", type=int, default=37, help="cold start: new objects (default 37)"
    )
    ap.add_argument(
        "--cold-orders", type=int, default=3, help="cold start: orders per object (default 3)"
    )
    ap.add_argument("--plant-kind", choices=("in-class", "mismatch", "bullet"), default="in-class")
    ap.add_argument("--mismatch-off", default="", metavar="PART,...",
                    help="with --plant-kind mismatch: parts of the mismatch switched off on "
                         "every arm's plant (an ablation, cps up --plant-mismatch-off)")
    ap.add_argument("--plant-seeds", default="7", help="comma-separated (default 7)")
    ap.add_argument("--plant-seed", type=int, help="one plant seed (as --plant-seeds N)")
    ap.add_argument("--arms", help="comma-separated subset of " +
                    ", ".join(a[0] for a in ARMS))  # fmt: skip
    ap.add_argument(
        "--campaign",
        action="store_true",
        help="add the calibrated arms (a campaign on each of their floors)",
    )
    ap.add_argument("--campaign-experiments", type=int, default=40)
    ap.add_argument("--campaign-object-prior", choices=("plain", "shipped"), default="shipped",
                    help="the campaign's object prior (cps campaign start --object-prior)")
    ap.add_argument("--campaign-min-face-rows", type=int, default=1,
                    help="rows a face needs before the campaign searches its depth")
    ap.add_argument("--campaign-tune-trials", type=int, default=0,
                    help="the campaign's TPE trials over mu and the gap (default 0)")
    ap.add_argument("--campaign-runs", type=int, default=4,
                    help="the campaign's runs per state and replayed row (default 4)")
    ap.add_argument("--seed", type=int, default=0, help="orders, study and floor seed")
    ap.add_argument("--runs", type=int, default=4, help="study runs per state (default 4)")
    ap.add_argument("--study", help="an existing study store of the floor's cores")
    ap.add_argument("--workdir", help="where floors and the study go (default: a temp dir)")
    ap.add_argument("--timeout", type=float, default=3600.0, help="per arm, seconds")
    ap.add_argument(
        "--camera",
        action="store_true",
        help="also run predictive with the modules' cameras in the loop",
    )
    ap.add_argument("--lease", type=float, default=30.0,
                    help="the floor's lease, s (default 30: a 35-process floor on a loaded "
                         "2-core host misses 5 s heartbeats)")  # fmt: skip
    ap.add_argument("--pool", nargs="+", metavar="JSON",
                    help="run nothing: pool these outputs of earlier runs (one experiment "
                         "split by seed or arm) and print their report")  # fmt: skip
    args = ap.parse_args()
    if args.pool:
        try:
            regime, kind, off, per_seed = load_runs([Path(p) for p in args.pool])
        except ValueError as exc:
            print(f"operations.py: error: {exc}", file=sys.stderr)
            return 2
        report(per_seed, regime, kind, f"{regime}, {kind} plant"
               f"{' without ' + ','.join(off) if off else ''}, pooled from "
               f"{len(args.pool)} runs")  # fmt: skip
        return 0
    seeds = [args.plant_seed] if args.plant_seed is not None else [
        int(s) for s in args.plant_seeds.split(",") if s.strip()]  # fmt: skip
    arms = [a for a in ARMS if args.campaign or not a[3]]
    if args.arms:
        names = {n.strip() for n in args.arms.split(",")}
        unknown = names - {a[0] for a in ARMS}
        if unknown:
            raise SystemExit(f"--arms: unknown {', '.join(sorted(unknown))}")
        arms = [a for a in ARMS if a[0] in names]
    floor = load_floor(args.floor)
    if "[operation]" in Path(args.floor).read_text():
        raise SystemExit("the floor file has an [operation] table already")
    wd = Path(args.workdir or tempfile.mkdtemp(prefix="operations-"))
    wd.mkdir(parents=True, exist_ok=True)
    if args.regime == "cold-start":
        floor = cold_floor(floor, args.cold_objects, args.seed)
        orders = cold_orders(floor, args.cold_orders, args.seed)
        study = None  # new objects: no study has seen them
    else:
        orders = order_sequence(floor, args.orders, args.seed)
        study = Path(args.study) if args.study else wd / "study.sqlite"
        if not args.study and not study.exists():
            print(f"study of {len(floor.objects)} cores x 28 states x {args.runs} runs, both "
                  f"legs -> {study}")  # fmt: skip
            make_study(floor, study, args.runs, args.seed)

    def variant(name: str, settings: dict) -> str:
        """The floor file of an arm: the floor with its [operation] settings."""
        op = dataclasses.replace(floor.operation, **settings)
        path = wd / f"floor-{name}.toml"
        path.write_text(floor_toml(dataclasses.replace(floor, operation=op)))
        return str(path)

    rng = np.random.default_rng(args.seed)
    per_seed: dict[int, dict[str, dict]] = {}
    for ps in seeds:
        out: dict[str, dict] = {}
        for name, policy, table, calib in arms:
            r = run_arm(args, floor, name, policy, variant(name, table), study,
                        wd / f"seed-{ps}", orders, rng, ps, calib)  # fmt: skip
            if r is None:
                return 1
            r.pop("boot")
            out[name] = r
        if args.camera and ps == seeds[0] and args.regime == "steady":
            c = run_arm(args, floor, "predictive+camera", "predictive",
                        variant("camera", {"sensor": "camera"}), study, wd / f"seed-{ps}",
                        orders, rng, ps)  # fmt: skip
            if c is not None:
                c.pop("boot")
                out["predictive+camera"] = c
        per_seed[ps] = out
    title = (f"{args.regime}: {len(orders)} orders on {floor.name}, {args.plant_kind} plant"
             f"{' without ' + args.mismatch_off if args.mismatch_off else ''}, seeds {seeds}")
    figures = report(per_seed, args.regime, args.plant_kind, title)
    off = "-off-" + args.mismatch_off.replace(",", "-") if args.mismatch_off else ""
    res = ROOT / "benchmarks" / "results" / f"operations-{args.regime}-{args.plant_kind}{off}.json"
    res.write_text(json.dumps({
        "regime": args.regime, "plant_kind": args.plant_kind, "plant_seeds": seeds,
        "mismatch_off": args.mismatch_off.split(",") if args.mismatch_off else [],
        "floor": floor.name, "orders": len(orders), "seed": args.seed, "runs": args.runs,
        "arms": [a[0] for a in arms], "per_seed": {str(s): v for s, v in per_seed.items()},
        **figures}, indent=2) + "\n")  # fmt: skip
    print(f"wrote {res}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
