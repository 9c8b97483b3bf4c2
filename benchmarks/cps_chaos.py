"""Chaos on a process floor: orders flow while a random asset process is killed with -9
every few seconds and restarted by hand (Jepsen-style: a workload, injected faults, an
invariant checked at the end).

    PYTHONPATH=src .venv/bin/python benchmarks/cps_chaos.py --kills 10 --period 8
    PYTHONPATH=src .venv/bin/python benchmarks/cps_chaos.py --kills 100 --period 8 \
        --plant-seed 3 --lease 15

With ``--plant-seed`` the floor runs on the emulated plant (its hidden physics decide every
transfer) and the TMS's policy is the default, predictive: the twin's best state per
object, learnt from the floor's transfers, so hand-overs happen under faults as they do in
operation (``--policy nearest-idle`` for the baseline without a twin).

Prints the kills, the orders completed / failed with their reasons / lost (must be 0),
objects lost or duplicated (must be 0) and marked unknown (with the operation that lost
them), the time from a kill to the knowledge graph marking the asset offline, and from a
restart to the asset being online again. Exit 1 when an invariant is broken.

The floor runs with the simulation as fast as it goes (``--time-scale 0``); each kill's
victim is drawn from a seeded generator, so a run's fault schedule is reproducible (the
timing of the faults against the operations is not: it depends on the host).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import logging
import os
import random
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

from _floor_client import tt

ROOT = Path(__file__).resolve().parents[1]


class Floor:
    """Client side of a running process floor."""

    def __init__(self, wd: Path) -> None:
        from transfertwin.cps.opcua import load_credentials

        self.wd = wd
        self.info = json.loads((wd / "cps.json").read_text())
        self.creds = load_credentials(Path(self.info["credentials_file"]))
        self.endpoint = {a["id"]: a["endpoint"] for a in self.info["assets"]}
        # the floor's own assets by class; a plant's physical units (TU_A_P...) are not
        # destinations of orders (the TMS refuses them) and hold nothing of the ledger's
        self.cls = {a["id"]: a["class"] for a in self.info["assets"]
                    if a.get("kind") != "physical"}  # fmt: skip
        self.ids = sorted(a["id"] for a in self.info["assets"])  # every asset can be killed

    async def call(self, aid: str, op: str, *args, timeout_s: float = 5.0):
        from transfertwin.cps.opcua import connect

        cert_dir = Path(self.info["cert_dir"])
        async with connect(self.endpoint[aid], aid, credentials=self.creds, cert_dir=cert_dir,
                           timeout_s=timeout_s) as s:  # fmt: skip
            return await asyncio.wait_for(s.call(op, *args), timeout_s)

    async def read(self, aid: str, prop: str, timeout_s: float = 5.0):
        from transfertwin.cps.opcua import connect

        cert_dir = Path(self.info["cert_dir"])
        async with connect(self.endpoint[aid], aid, credentials=self.creds, cert_dir=cert_dir,
                           timeout_s=timeout_s) as s:  # fmt: skip
            return await asyncio.wait_for(s.read("OperationalData", prop), timeout_s)

    async def status(self) -> dict | None:
        try:
            return json.loads(await self.call("KG", "Status"))
        except Exception:
            return None

    async def ledger(self) -> dict | None:
        try:
            return json.loads(await self.call("TMS", "Ledger"))
        except Exception:
            return None

    def pid(self, aid: str) -> int | None:
        try:
            return int((self.wd / "assets" / aid / "state" / "pid").read_text())
        except (OSError, ValueError):
            return None

    def restart(self, aid: str) -> subprocess.Popen:
        log = (self.wd / "logs" / f"{aid}.log").open("ab")
        return subprocess.Popen(
            [sys.executable, "-m", "transfertwin", "cps", "asset", str(self.wd / "assets" / aid)],
            stdout=log, stderr=subprocess.STDOUT, start_new_session=True)  # its bundle


async def wait_online(floor: Floor, aid: str, online: bool, timeout_s: float,
                      pid: int | None = None) -> float | None:  # fmt: skip
    """Seconds until the graph lists `aid` as (not) online (with `pid`); None on timeout."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        doc = await floor.status()
        if doc is not None:
            row = next((a for a in doc["assets"] if a["id"] == aid), None)
            if row is not None and row["online"] == online and (pid is None or row["pid"] == pid):
                return time.monotonic() - t0
        await asyncio.sleep(0.2)
    return None


async def order_flow(floor: Floor, rng: random.Random, stop: asyncio.Event,
                     submitted: list[str], refused: Counter, modules: int) -> None:  # fmt: skip
    """Keep about one order per module in flight: a random object with a known place to a
    random other unit; an object a module still carries after a failed delivery first (a
    module carries one object at a time, so it takes no other order until then)."""
    units = sorted(a for a, c in floor.cls.items() if c == "transfer_unit")
    while not stop.is_set():
        ledger = await floor.ledger()
        if ledger is None:
            await asyncio.sleep(0.5)
            continue
        running = sum(op["state"] != "finished" for op in ledger["operations"])
        free = [o for o, at in ledger["locations"].items()
                if o not in ledger["moving"] and o not in ledger["unknown"]]  # fmt: skip
        for obj in ledger["unknown"]:  # an operator takes it out of the gap onto a station
            if obj not in ledger["moving"]:
                with contextlib.suppress(Exception):
                    await floor.call("TMS", "Locate", obj, rng.choice(units))
        carried = [o for o in free if floor.cls.get(ledger["locations"][o]) == "transport_module"]
        if running < modules and free:  # what a module still carries goes on first
            obj = rng.choice(sorted(carried or free))
            source = ledger["locations"][obj]
            target = rng.choice([u for u in units if u != source])
            try:
                submitted.append(await floor.call("TMS", "SubmitTransportOperation", source,
                                                  target, obj))  # fmt: skip
            except Exception as exc:
                reason = getattr(exc, "reason", type(exc).__name__)
                refused[reason[:60]] += 1
                if "outside a pre-transfer state" in reason:  # as an operator would:
                    with contextlib.suppress(Exception):  # take it off onto a station
                        await floor.call("TMS", "Locate", obj, target)
        await asyncio.sleep(0.5)


async def chaos(args: argparse.Namespace) -> int:
    wd = Path(args.workdir or tempfile.mkdtemp(prefix="cps-chaos-")) / "floor"
    t0 = time.monotonic()
    plant = [] if args.plant_seed is None else [
        "--plant-seed", str(args.plant_seed), "--plant-kind", args.plant_kind]  # fmt: skip
    up = tt("cps", "up", "--floor", args.floor, "--workdir", str(wd), "--detach",
            "--time-scale", "0", "--lease", str(args.lease), "--seed", str(args.seed),
            "--policy", args.policy, *plant, "--start-timeout", "300", timeout=400)  # fmt: skip
    if up.returncode != 0:
        print(up.stderr, file=sys.stderr)
        return 1
    print(up.stdout.strip(), f"({time.monotonic() - t0:.1f} s)")
    floor = Floor(wd)
    rng = random.Random(args.seed + 1)  # the orders
    victim_rng = random.Random(args.seed)  # the kills: the schedule is the seed's alone
    modules = sum(c == "transport_module" for c in floor.cls.values())
    stop = asyncio.Event()
    submitted: list[str] = []
    refused: Counter = Counter()
    flow = asyncio.ensure_future(order_flow(floor, rng, stop, submitted, refused, modules))
    victims = floor.ids
    detect, rejoin, kills = [], [], []
    try:
        for k in range(args.kills):
            await asyncio.sleep(args.period)
            aid = victim_rng.choice(victims)
            pid = floor.pid(aid)
            if pid is None:
                continue
            os.kill(pid, signal.SIGKILL)
            t_kill = time.monotonic()
            took = None if aid == "KG" else await wait_online(floor, aid, False, 30)
            if took is not None:
                detect.append(took)
            proc = floor.restart(aid)
            back = await wait_online(floor, aid, True, 90, pid=proc.pid)
            if back is not None:
                rejoin.append(back)
            kills.append(aid)
            print(f"kill {k + 1:2d}: {aid:6s} offline after "
                  f"{'-' if took is None else f'{took:.1f} s'}, online again "
                  f"{'never' if back is None else f'{back:.1f} s'} after restart "
                  f"({time.monotonic() - t_kill:.1f} s in all)", flush=True)  # fmt: skip
    finally:
        stop.set()
        await flow
    # let every operation end (a module that was killed fails its operation within a lease)
    deadline = time.monotonic() + args.drain
    ledger = await floor.ledger()
    while time.monotonic() < deadline:
        ledger = await floor.ledger()
        if ledger is not None and all(op["state"] == "finished" for op in ledger["operations"]):
            break
        await asyncio.sleep(1.0)
    holders = [a for a, c in floor.cls.items() if c in ("transfer_unit", "transport_module")]
    held: Counter = Counter()
    for h in holders:
        try:
            for o in str(await floor.read(h, "PossessedObjects")).split(","):
                if o:
                    held[o] += 1
        except Exception:
            pass
    tt("cps", "down", "--workdir", str(wd), timeout=300)
    return report(ledger, submitted, refused, kills, detect, rejoin, held, floor)


def report(ledger, submitted, refused, kills, detect, rejoin, held, floor) -> int:
    ops = {op["operation"]: op for op in (ledger or {"operations": []})["operations"]}
    finished = [ops[o] for o in submitted if o in ops and ops[o]["state"] == "finished"]
    lost = [o for o in submitted if o not in ops or ops[o]["state"] != "finished"]
    done = [op for op in finished if op["phase"] == "done"]
    reasons = Counter(f"{op['result'].get('failed_step')}: "
                      f"{str(op['result'].get('reason', ''))[:70]}"
                      for op in finished if op["phase"] != "done")  # fmt: skip
    objects = sorted(a for a, c in floor.cls.items() if c == "object")
    located = set((ledger or {}).get("locations", {}))
    objects_lost = [o for o in objects if o not in located]
    duplicated = sorted(o for o, n in held.items() if n > 1)
    unknown_ops = sum(bool(op["result"].get("location_unknown")) for op in finished)
    print("\nkills:", len(kills), dict(Counter(kills)))
    print(f"orders submitted {len(submitted)}: completed {len(done)}, failed "
          f"{len(finished) - len(done)}, lost {len(lost)} (must be 0); refused up front "
          f"{sum(refused.values())}")  # fmt: skip
    for reason, n in reasons.most_common():
        print(f"  failed {n:3d}x  {reason}")
    for reason, n in refused.most_common(5):
        print(f"  refused {n:3d}x  {reason}")
    print(f"objects lost {len(objects_lost)}, duplicated {len(duplicated)} (both must be 0); "
          f"marked unknown by {unknown_ops} operations (caught in the gap, or lost with a "
          "module killed mid-transfer) and put on a station again by the operator")
    if detect:
        print(f"time to detect a leave: median {statistics.median(detect):.1f} s, max "
              f"{max(detect):.1f} s ({len(detect)} kills)")  # fmt: skip
    if rejoin:
        print(f"time to rejoin after a restart (process start included): median "
              f"{statistics.median(rejoin):.1f} s, max {max(rejoin):.1f} s")  # fmt: skip
    broken = lost or objects_lost or duplicated or ledger is None
    print("INVARIANTS HOLD" if not broken else "INVARIANT BROKEN")
    return 1 if broken else 0


def main() -> int:
    logging.getLogger("asyncua").setLevel(logging.ERROR)  # one warning per session otherwise
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--floor", default=str(ROOT / "examples" / "floor-demo.toml"))
    ap.add_argument("--kills", type=int, default=10)
    ap.add_argument("--period", type=float, default=8.0, help="seconds between kills")
    ap.add_argument("--lease", type=float, default=5.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--drain", type=float, default=120.0,
                    help="seconds to let operations end after the last kill")  # fmt: skip
    ap.add_argument("--workdir", help="where the floor's work folder goes (default: a temp dir)")
    ap.add_argument("--plant-seed", type=int, help="run the floor on the emulated plant")
    ap.add_argument("--plant-kind", choices=("in-class", "mismatch"), default="in-class")
    ap.add_argument("--policy", choices=("predictive", "nearest-idle"), default="predictive")
    return asyncio.run(chaos(ap.parse_args()))


if __name__ == "__main__":
    sys.exit(main())
