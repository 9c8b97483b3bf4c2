"""`transfertwin cps up --floor`, `cps asset`, `cps down`, `cps locate` and the process
floor's `cps status`: the DT network with one process per asset (docs/architecture.md,
"Deployment")."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import logging
import os
import re
import signal
import sys
import threading
import time
from pathlib import Path

from transfertwin._errors import InputError
from transfertwin.cli._cps_client import (
    add_access,
    call_asset,
    check_access,
    floor_access,
    load_info,
    text_table,
)
from transfertwin.cli._cps_ops import register as register_ops
from transfertwin.cli._paths import out_dir

__all__ = ["cmd_asset", "cmd_down", "cmd_locate", "cmd_up_floor", "floor_document", "floor_status",
           "register"]  # fmt: skip


def _floor_spec(name: str):
    from transfertwin.cps import default_floor_spec, load_floor

    return default_floor_spec() if name == "demo" else load_floor(name)


def _mismatch_off(text: str, kind: str) -> tuple[str, ...]:
    """``--plant-mismatch-off``'s parts (`check_mismatch_off`); InputError."""
    from transfertwin.plant import check_mismatch_off

    parts = tuple(p.strip() for p in text.split(",") if p.strip())
    try:
        check_mismatch_off(parts, kind)
    except InputError as exc:
        raise InputError(f"--plant-mismatch-off (with --plant-kind mismatch): {exc}") from None
    return parts


def _floor_to_run(args: argparse.Namespace):
    """The floor `cps up` runs: `--floor` (or the built-in one) with `--policy`/`--study`,
    every unit and module on the emulated plant with `--plant-seed` (InputError on a flag
    that does not fit)."""
    for flag, value, default in (("--config", args.config, None), ("--host", args.host,
                                                                     "127.0.0.1")):
        if value != default:  # each asset has its own address; the physics are the defaults
            raise InputError(f"{flag} is not taken by a floor: its assets bind their own "
                             "addresses from the floor and use the built-in physics")
    if not args.time_scale >= 0:
        raise InputError(f"--time-scale must be >= 0, got {args.time_scale}")
    if args.docking not in ("sampled", "navigated"):
        raise InputError(f"--docking must be sampled or navigated, got {args.docking!r}")
    if args.lease is not None and not args.lease >= 0.5:
        raise InputError(f"--lease must be at least 0.5 s, got {args.lease}")
    floor = _with_operation(_floor_spec(args.floor), args.policy, args.study)
    if args.plant_kind != "in-class" and args.plant_seed is None:
        raise InputError("--plant-kind needs --plant-seed (the plant's hidden parameters)")
    args.plant_mismatch_off = _mismatch_off(args.plant_mismatch_off, args.plant_kind)
    if args.plant_seed is not None:  # every unit and module on the emulated plant
        from transfertwin.cps import check_plant_seed
        from transfertwin.plant import check_camera

        check_plant_seed(args.plant_seed)
        check_camera(args.plant_kind, floor.operation.sensor, args.docking)
        if args.insecure:
            raise InputError("--plant-seed with --insecure: a plant floor is served only "
                             "with security (drop --insecure)")  # fmt: skip
        floor = floor.with_hal("plant")
    return floor


def _check_here(floor) -> None:
    """Refuse to start a floor whose file binds an asset (not on standby) to an address this
    host does not have: that asset starts on its own host, from its bundle."""
    from transfertwin.cps import local_address

    standby = floor.standby()
    away = [(aid, floor.bind_address(aid)[0]) for aid, _ in floor.bind if aid not in standby]
    away = [(aid, host) for aid, host in away if not local_address(host)]
    if away:
        aid, host = away[0]
        raise InputError(f"{aid} is bound to {host}, an address of another host "
                         f"({len(away)} such assets): prepare the bundles with 'cps up "
                         "--prepare-only' and start each on its host ('cps asset BUNDLE')")


def cmd_up_floor(args: argparse.Namespace) -> int:
    """Start one process per asset of the floor; wait until the knowledge graph knows them
    all; then stay until SIGINT/SIGTERM (stopping the floor) or until no asset process of
    the floor runs any more (`cps down` from another shell, or each one stopped), or, with
    --detach, exit and leave the floor running."""
    from transfertwin.cps import (
        asset_pids,
        check_workdir,
        launch,
        prepare_floor,
        stop_floor,
        write_floor_info,
    )

    floor = _floor_to_run(args)
    if not args.prepare_only:
        _check_here(floor)
    wd = out_dir(args.workdir)
    check_workdir(wd)
    configs = prepare_floor(floor, wd, insecure=args.insecure, seed=args.seed,
                            time_scale=args.time_scale, docking=args.docking,
                            lease_s=args.lease, plant_seed=args.plant_seed,
                            plant_kind=args.plant_kind,
                            plant_mismatch_off=args.plant_mismatch_off)  # fmt: skip
    write_floor_info(wd, configs, floor)
    if args.prepare_only:  # each bundle goes to its host and starts there
        print(f"floor {floor.name} prepared: {len(configs)} bundles in {wd / 'assets'}; start "
              "each on its host with 'transfertwin cps asset BUNDLE'", flush=True)  # fmt: skip
        return 0
    t0 = time.monotonic()
    standby = floor.standby()
    procs = launch(configs, wd, skip=standby)
    expected = set(procs)
    try:
        online = _wait_online(wd, expected, args.start_timeout, procs)
    except BaseException:  # a floor that did not come up is not left half running
        stop_floor(wd)
        raise
    took = time.monotonic() - t0
    print(f"floor {floor.name} up: {len(online)} asset processes in {took:.1f} s"
          f"{f', {len(standby)} on standby' if standby else ''}; {wd / 'cps.json'}",
          flush=True)  # fmt: skip
    if args.detach:
        return 0
    stop = _stop_event()
    ended, tick = False, 0
    try:
        while not stop["set"]:
            time.sleep(0.2)
            tick += 1
            if tick % 5 == 0:  # once a second: reap the ended children, then look at all
                for p in procs.values():  # (an asset restarted by hand keeps the floor up)
                    p.poll()
                if not asset_pids(wd):
                    ended = True
                    break
    finally:
        stop_floor(wd)
        for p in procs.values():
            with contextlib.suppress(Exception):
                p.wait(15)
    print("floor down" + (": no asset process of it runs any more" if ended else ""),
          flush=True)  # fmt: skip
    return 0


def cmd_up_local(args: argparse.Namespace) -> int:
    """Every asset of the floor on a node in this process, one event loop (`LocalFloor`):
    serve until SIGINT/SIGTERM (`cps down` from another shell sends it); the work folder
    and cps.json as a floor of processes has them, the log in ``W/cps.log``."""
    from transfertwin.cps import LocalFloor

    if args.detach or args.prepare_only:
        raise InputError(f"{'--detach' if args.detach else '--prepare-only'} is for a floor "
                         "of processes; --single-process runs the floor in this process: "
                         "choose one")  # fmt: skip
    floor = _floor_to_run(args)
    _check_here(floor)
    wd = out_dir(args.workdir)
    wd.mkdir(parents=True, exist_ok=True)
    handler = logging.FileHandler(wd / "cps.log")
    handler.setFormatter(logging.Formatter("%(asctime)s %(message)s"))
    cps_log = logging.getLogger("transfertwin.cps")
    cps_log.addHandler(handler)
    cps_log.setLevel(logging.INFO)
    cps_log.propagate = False  # the assets' log is the floor's file, as each process's is
    logging.getLogger("asyncua.client.client").setLevel(logging.CRITICAL)
    local = LocalFloor(floor, wd, insecure=args.insecure, seed=args.seed,
                       time_scale=args.time_scale, docking=args.docking, lease_s=args.lease,
                       plant_seed=args.plant_seed, plant_kind=args.plant_kind,
                       plant_mismatch_off=args.plant_mismatch_off,
                       online_timeout_s=args.start_timeout)  # fmt: skip

    async def serve() -> None:
        stop = asyncio.Event()
        loop = asyncio.get_running_loop()

        def on_signal(signum: int, frame: object) -> None:
            _exit_after(SHUTDOWN_LIMIT_S, wd)
            loop.call_soon_threadsafe(stop.set)

        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, on_signal)
        async with local:
            print(f"CPS up: {len(local.nodes)} assets; {wd / 'cps.json'}", flush=True)
            ended = asyncio.ensure_future(local.ended.wait())  # every asset shut down
            signalled = asyncio.ensure_future(stop.wait())
            await asyncio.wait({ended, signalled}, return_when=asyncio.FIRST_COMPLETED)
            for waiter in (ended, signalled):
                waiter.cancel()
        print("CPS down", flush=True)

    # Not asyncio.run: at its end it joins the default executor's threads, and a simulation
    # step still running there would hold the process past `cps down`'s limit.
    loop = asyncio.new_event_loop()
    loop.run_until_complete(serve())
    logging.shutdown()
    sys.stdout.flush()
    os._exit(0)


#: Seconds a stopping single-process floor may take before it ends without waiting further.
SHUTDOWN_LIMIT_S = 30.0


def _exit_after(seconds: float, wd: Path) -> None:
    """Start (once) a watchdog that ends the process if stopping takes longer than
    `seconds`: a stop that hangs (a session or a thread that never returns) must not keep
    stale endpoints around."""
    if getattr(_exit_after, "armed", False):
        return
    _exit_after.armed = True

    def force() -> None:
        for pid_file in (wd / "assets").glob("*/state/pid"):
            pid_file.unlink(missing_ok=True)
        (wd / "cps.json").unlink(missing_ok=True)
        print(f"CPS down (forced: stopping took over {seconds:g} s)", flush=True)
        os._exit(0)

    timer = threading.Timer(seconds, force)
    timer.daemon = True
    timer.start()


def _with_operation(floor, policy: str | None, study: str | None):
    """The floor with `cps up --policy/--study` applied; the study store must exist."""
    import dataclasses

    op = floor.operation
    if policy is not None:
        op = dataclasses.replace(op, policy=policy)
    if study is not None:
        op = dataclasses.replace(op, study=str(Path(study).resolve()))
    if op.study is not None and not Path(op.study).is_file():
        raise InputError(f"study store {op.study}: no such file (run 'transfertwin study' or "
                         "'./dev.sh run' to make one)")  # fmt: skip
    return dataclasses.replace(floor, operation=op)


def _stop_event() -> dict[str, bool]:
    flag = {"set": False}

    def handler(signum, frame) -> None:
        flag["set"] = True

    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, handler)
    return flag


def _wait_online(wd: Path, expected: set[str], timeout_s: float, procs) -> set[str]:
    """Poll the graph until every expected asset is online (InputError on a timeout or
    an asset process that exits)."""
    deadline = time.monotonic() + timeout_s
    online: set[str] = set()
    while time.monotonic() < deadline:
        for aid, p in procs.items():
            if p.poll() is not None:
                log = wd / "logs" / f"{aid}.log"
                tail = log.read_text().strip().splitlines()[-1:] if log.exists() else []
                last = tail[0] if tail else "no output"
                raise InputError(f"asset {aid} exited with code {p.returncode} while the floor "
                                 f"started: {last} ({log})")
        try:
            doc = floor_status(wd, with_objects=False)
            online = {a["id"] for a in doc["assets"] if a["online"]}
        except (InputError, OSError, TimeoutError, ConnectionError):
            pass
        if expected <= online:
            return online
        time.sleep(0.5)
    missing = sorted(expected - online)
    raise InputError(f"the floor did not come up within {timeout_s:g} s: not online: "
                     f"{', '.join(missing[:8])}{' ...' if len(missing) > 8 else ''} "
                     f"(logs in {wd / 'logs'})")  # fmt: skip


def cmd_asset(args: argparse.Namespace) -> int:
    """Serve one asset until SIGINT/SIGTERM or an operator's ``Shutdown``; announce the
    leave; exit 0. The asset is a bundle folder (``assets/<id>/``, as `cps up` writes it,
    copied to any host) or its file (``--config``). With several: fork one such process
    per asset from this one (`_fork_assets`)."""
    from transfertwin.cps import bundle_config, load_asset_config

    paths = [str(bundle_config(Path(b))) for b in args.bundle] + list(args.config or [])
    if not paths:
        raise InputError("cps asset: give the asset's bundle folder (W/assets/<id>) or "
                         "--config ASSET.toml")  # fmt: skip
    if len(paths) > 1 or args.log_dir is not None:
        return _fork_assets(paths, args.log_dir)
    _serve_asset(load_asset_config(paths[0]))


def _fork_assets(paths: list[str], log_dir: str | None) -> int:
    """Prepare once (imports, the standard address space), then fork one asset process
    per file: each in a session of its own, its output in ``LOG_DIR/<id>.log``, serving as
    ``cps asset --config`` does. Prints ``forked <id> <pid>`` per asset and exits: the
    assets do not depend on this process (they share its prepared pages copy-on-write)."""
    from transfertwin.cps import load_asset_config, prepare_forking

    if log_dir is None:
        raise InputError("--log-dir is required with several --config (each asset's output "
                         "goes to LOG_DIR/<id>.log)")  # fmt: skip
    configs = [load_asset_config(p) for p in paths]  # every file checked before any fork
    logs = Path(log_dir)
    logs.mkdir(parents=True, exist_ok=True)
    prepare_forking()
    sys.stdout.flush()
    for cfg in configs:
        pid = os.fork()
        if pid == 0:  # the asset process
            try:
                os.setsid()
                out = os.open(logs / f"{cfg.asset_id}.log", os.O_WRONLY | os.O_CREAT | os.O_APPEND)
                null = os.open(os.devnull, os.O_RDONLY)
                os.dup2(null, 0)
                os.dup2(out, 1)
                os.dup2(out, 2)
                _serve_asset(cfg)
            except BaseException:
                import traceback

                traceback.print_exc()
            finally:
                os._exit(1)  # only reached when serving failed before it could exit itself
        print(f"forked {cfg.asset_id} {pid}", flush=True)
    return 0


def _serve_asset(cfg) -> None:
    """The asset process: serve `cfg`'s asset until SIGINT/SIGTERM, announce the leave,
    end the process (never returns)."""
    from transfertwin.cps import asset_node

    logging.getLogger("transfertwin.cps").setLevel(logging.INFO)
    handler = logging.StreamHandler()
    handler.setFormatter(logging.Formatter("%(asctime)s %(message)s"))
    logging.getLogger("transfertwin.cps").addHandler(handler)
    # a peer that died leaves a session asyncua cannot close; it logs that with a traceback
    logging.getLogger("asyncua.client.client").setLevel(logging.CRITICAL)
    pid_file = cfg.state_dir / "pid"

    def bounded_stop() -> None:
        # a leave that hangs (a peer that never answers) must not keep the process
        timer = threading.Timer(15.0, lambda: (pid_file.unlink(missing_ok=True),
                                               os._exit(0)))  # fmt: skip
        timer.daemon = True
        timer.start()

    async def serve() -> None:
        stop = asyncio.Event()
        loop = asyncio.get_running_loop()

        def on_signal(signum: int, frame: object) -> None:
            bounded_stop()
            loop.call_soon_threadsafe(stop.set)

        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, on_signal)
        cfg.state_dir.mkdir(parents=True, exist_ok=True)
        pid_file.write_text(f"{os.getpid()}\n")  # before it joins: 'cps down' finds it then
        try:
            async with asset_node(cfg) as node:
                print(f"{cfg.asset_id} up at {node.server.endpoint} (pid {os.getpid()}, "
                      f"instance {node.instance})", flush=True)  # fmt: skip
                asked = asyncio.ensure_future(node.shutdown.wait())  # an operator's Shutdown
                signalled = asyncio.ensure_future(stop.wait())
                await asyncio.wait({asked, signalled}, return_when=asyncio.FIRST_COMPLETED)
                for waiter in (asked, signalled):
                    waiter.cancel()
                if node.shutdown.is_set():
                    bounded_stop()
                    print(f"{cfg.asset_id}: shutdown asked over OPC UA", flush=True)
        finally:
            pid_file.unlink(missing_ok=True)
        print(f"{cfg.asset_id} left", flush=True)

    # Not asyncio.run: at its end it joins the default executor's threads, and a warm-up or
    # a simulation step still running there (tens of seconds on a loaded host) would hold
    # the process past `cps down`'s limit after its leave was announced.
    loop = asyncio.new_event_loop()
    try:
        loop.run_until_complete(serve())
    except InputError as exc:  # e.g. a plant seed file that cannot be read
        print(f"transfertwin: error: {exc}", file=sys.stderr, flush=True)
        logging.shutdown()
        os._exit(2)
    # Every change of state was written when it happened and the leave is announced: end
    # here rather than wait for a simulation thread still stepping (the interpreter joins
    # its worker threads at exit, a transfer in real time takes tens of seconds).
    logging.shutdown()
    sys.stdout.flush()
    os._exit(0)


def cmd_down(args: argparse.Namespace) -> int:
    """Stop every asset of a floor: ``Shutdown`` over OPC UA to each asset the graph lists
    online, the graph last (each announces its leave and ends its process), from any host.
    On a floor of this host (``--workdir``) what did not stop is sent SIGTERM by its pid
    file (the one-host fallback: an asset that does not answer), then killed after
    ``--timeout``. With ``--asset``, that asset only."""
    from transfertwin.cps import asset_pids

    check_access(args)
    wd = Path(args.workdir) if args.workdir is not None else None
    asked, refused = [], []
    if wd is None or (wd / "cps.json").is_file():
        _, info, creds = floor_access(args)
        if args.asset is not None and args.asset not in {a["id"] for a in info["assets"]}:
            raise InputError(f"--asset {args.asset}: no such asset on the floor")
        asked, refused = asyncio.run(_shutdown_floor(info, creds, args.timeout, args.asset))
    if wd is None:
        print(f"stopped {len(asked)} assets over OPC UA"
              + (f"; not answering: {', '.join(refused)}" if refused else ""))  # fmt: skip
        return 0 if not refused else 1
    def running() -> dict[str, int]:
        # a process that also serves an asset not asked to stop (a single-process floor)
        # is not signalled for one asset
        pids = asset_pids(wd)
        others = {p for a, p in pids.items() if args.asset not in (None, a)}
        return {a: p for a, p in pids.items() if args.asset in (None, a) and p not in others}

    deadline = time.monotonic() + args.timeout
    while running() and time.monotonic() < deadline:
        time.sleep(0.2)
    pids = running()  # the one-host fallback: by pid, what is still running
    for pid in set(pids.values()):
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGTERM)
    while running() and time.monotonic() < deadline + args.timeout:
        time.sleep(0.2)
    left = running()
    for aid in left:  # what did not stop in time is killed (its state is on disk)
        # its pid file goes first: a process killed as asked is not one that died unasked
        # (`cps supervise` restarts those)
        (wd / "assets" / aid / "state" / "pid").unlink(missing_ok=True)
    for pid in set(left.values()):
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)
    print(f"stopped {len(asked) + len(pids) - len(left)} assets ({len(asked)} over OPC UA, "
          f"{len(pids) - len(left)} by signal)"
          f"{f'; killed {sorted(left)} (no exit within {args.timeout:g} s)' if left else ''}")
    return 0


async def _shutdown_floor(info: dict, creds, timeout_s: float,
                         only: str | None = None) -> tuple[list[str], list[str]]:  # fmt: skip
    """``Shutdown`` every asset the graph lists online, then the graph once they have left
    (or `timeout_s` passed), or the asset `only`; returns (the assets asked, those that did
    not answer)."""
    from transfertwin.cps.node import LIFECYCLE

    async def shut(aid: str) -> bool:
        try:
            await call_asset(info, creds, aid, "Shutdown", submodel=LIFECYCLE, timeout_s=5)
        except Exception:
            return False
        return True

    async def online() -> set[str]:
        try:
            doc = json.loads(await call_asset(info, creds, "KG", "Status", timeout_s=5))
        except (OSError, TimeoutError, ConnectionError):
            return set()
        return {a["id"] for a in doc["assets"] if a["online"] and a["id"] != "KG"}

    if only is not None:
        if not await shut(only):
            return [], [only]
        deadline = time.monotonic() + timeout_s
        while only != "KG" and only in await online() and time.monotonic() < deadline:
            await asyncio.sleep(0.3)  # it announces its leave at the graph
        return [only], []
    running = sorted(await online())
    answers = await asyncio.gather(*(shut(a) for a in running))
    asked = [a for a, ok in zip(running, answers, strict=True) if ok]
    refused = [a for a, ok in zip(running, answers, strict=True) if not ok]
    deadline = time.monotonic() + timeout_s
    while set(asked) & await online() and time.monotonic() < deadline:
        await asyncio.sleep(0.3)  # each announces its leave at the graph
    if await shut("KG"):
        asked.append("KG")
    return asked, refused


def floor_status(wd: Path, *, with_objects: bool = True) -> dict:
    """The floor of work folder `wd` as one document (`floor_document`)."""
    return floor_document(str(wd), *load_info(wd), with_objects=with_objects)


def floor_document(where: str, info: dict, creds, *, with_objects: bool = True) -> dict:
    """The floor as one document: assets (id, kind, class, address, pid, online, state)
    from the knowledge graph, objects' locations from the TMS's ledger (`where`, `info`,
    `creds`: as `floor_access` gives them)."""

    async def ask() -> dict:
        try:
            doc = json.loads(await call_asset(info, creds, "KG", "Status", timeout_s=5))
        except (OSError, TimeoutError, ConnectionError) as exc:
            raise InputError(f"{where}: the floor is not running or not answering (its knowledge "
                             f"graph: {type(exc).__name__}); start it with 'transfertwin cps "
                             "up'") from None  # fmt: skip
        heard = {a["id"] for a in doc["assets"]}
        for a in info["assets"]:  # prepared but never heard of: on standby, or not joined yet
            if a["id"] not in heard:
                why = "standby" if a.get("standby") else "not joined"
                doc["assets"].append({
                    "id": a["id"], "kind": a["kind"], "class": a["class"],
                    "address": a["endpoint"], "pid": None, "online": False, "state": why,
                    "offline": {"reason": why, "detail": "no heartbeat since the graph "
                                "started", "since": None, "since_s": None}})  # fmt: skip
        doc["assets"].sort(key=lambda a: natural_key(a["id"]))
        if with_objects:
            try:
                ledger = json.loads(await call_asset(info, creds, "TMS", "Ledger", timeout_s=5))
            except (OSError, TimeoutError, ConnectionError) as exc:
                doc["objects"] = None
                doc["objects_error"] = f"the TMS is not answering ({type(exc).__name__})"
            else:
                doc["objects"] = {
                    o: ({"location": None, "unknown": True, "last_seen": u["last_seen"],
                         "operation": u["operation"]}
                        if (u := ledger["unknown"].get(o)) else
                        {"location": at, "unknown": False,
                         "moving": ledger["moving"].get(o)})
                    for o, at in sorted(ledger["locations"].items(),
                                        key=lambda item: natural_key(item[0]))
                }  # fmt: skip
        return doc

    return asyncio.run(ask())


def natural_key(name: str) -> tuple:
    """Sort key of an id that orders its numbers by value: o1, o2, …, o10; TM_2 before
    TM_10."""
    return tuple(int(part) if part.isdigit() else part for part in re.split(r"(\d+)", name))


def print_floor_status(doc: dict) -> None:
    """`cps status` for a process floor, as plain columns."""
    rows = [{**a, "online": "online" if a["online"] else "OFFLINE",
             "pid": a.get("pid") or "", "why offline": _why(a.get("offline"))}
            for a in doc["assets"]]  # fmt: skip
    print("assets (knowledge graph)")
    print(text_table(rows, ("id", "class", "online", "state", "pid", "address", "why offline")))
    objects = doc.get("objects")
    if objects is None:
        print(f"objects: {doc.get('objects_error', 'not known')}")
        return
    print("objects (TMS ledger)")
    lines = [{"object": o, "location": (f"unknown, last seen at {v['last_seen']} "
                                        f"({v['operation']})" if v["unknown"] else
                                        v["location"] + (f" (moving: {v['moving']})"
                                                         if v.get("moving") else ""))}
             for o, v in objects.items()]  # fmt: skip
    print(text_table(lines, ("object", "location")))


def _why(offline: dict | None) -> str:
    """An offline asset's reason in words: 'left 12 s ago', 'lapsed 3 s ago (no heartbeat
    for 5 s (lease expired))', 'standby'."""
    if not offline:
        return ""
    ago = offline.get("since_s")
    when = f" {ago:.0f} s ago" if isinstance(ago, int | float) else ""
    detail = f" ({offline['detail']})" if offline.get("reason") == "lapsed" else ""
    return f"{offline['reason']}{when}{detail}"


def cmd_locate(args: argparse.Namespace) -> int:
    """Tell the TMS where an object whose place is unknown lies."""
    from transfertwin.cps.opcua import OperationRefused

    where, info, creds = floor_access(args)
    try:
        asyncio.run(call_asset(info, creds, "TMS", "Locate", args.object, args.at))
    except OperationRefused as exc:
        raise InputError(f"the TMS refused: {exc.reason}") from None
    except (OSError, TimeoutError, ConnectionError) as exc:
        raise InputError(f"{where}: the TMS is not answering ({type(exc).__name__})") from None
    print(f"{args.object} is at {args.at}")
    return 0


def register(csub: argparse._SubParsersAction) -> None:
    """Add `cps asset|down|locate` (`cps up --floor` is `cps up`'s option)."""
    p = csub.add_parser("asset", help="serve one asset of a floor (one process per asset)")
    p.add_argument("bundle", nargs="*", metavar="BUNDLE",
                   help="the asset's bundle folder (W/assets/<id>, as cps up writes it; "
                        "copied to its own host, it runs there as it is)")  # fmt: skip
    p.add_argument("--config", action="append",
                   help="ASSET.toml (W/assets/<id>/asset.toml); several (or several "
                        "bundles): one process forked per asset (with --log-dir), this one "
                        "exits")  # fmt: skip
    p.add_argument("--log-dir", help="where forked assets write <id>.log")
    p.set_defaults(func=cmd_asset)
    p = csub.add_parser("down", help="stop every asset of a floor (Shutdown over OPC UA)")
    add_access(p)
    p.add_argument("--asset", metavar="ID", help="stop this asset only")
    p.add_argument("--timeout", type=float, default=20.0,
                   help="seconds to wait for each to leave before killing it (default 20)")
    p.set_defaults(func=cmd_down)
    p = csub.add_parser("locate", help="say where an object lies (its place unknown, or a module "
                        "still carries it by its own record)")
    add_access(p)
    p.add_argument("--object", required=True)
    p.add_argument("--at", required=True, help="transfer unit or transport module")
    p.set_defaults(func=cmd_locate)
    register_ops(csub)


#: Exit code of `cps order` on a process floor when the operation failed (the object is
#: where the last line says; the order can be issued again).
ORDER_FAILED = 3


def floor_order(where: str, info: dict, creds, args: argparse.Namespace) -> int:
    """`cps order` on a process floor: submit to the TMS (the source found in its ledger
    when --from is left out), then follow the operation's history to its end, across a
    restart of the TMS. Exit 0 when delivered, `ORDER_FAILED` when it failed."""
    from transfertwin.cps.opcua import OperationRefused

    by_id = {a["id"]: a.get("role_class", a["class"]) for a in info["assets"]}  # generic
    if by_id.get(args.object) != "object":
        objects = sorted(a for a, c in by_id.items() if c == "object")
        raise InputError(f"--object {args.object}: not an object of this floor; objects: "
                         f"{', '.join(objects)}")  # fmt: skip
    groups = [g for g, _ in info.get("groups") or []]
    known = info.get("groups") is not None  # from elsewhere: the TMS checks the groups
    if by_id.get(args.target) != "transfer_unit" and args.target not in groups and known:
        units = sorted(a for a, c in by_id.items() if c == "transfer_unit")
        raise InputError(f"--to {args.target}: no such transfer unit; units: {', '.join(units)}"
                         + (f"; destination groups: {', '.join(groups)}" if groups else ""))
    if args.source is not None and args.source == args.target:
        raise InputError(f"--from and --to are both {args.source}: nothing to transport")

    async def submit() -> tuple[str, str]:
        source = args.source
        try:
            if source is None:  # by destination: the TMS finds the source (orders chain)
                op = await call_asset(info, creds, "TMS", "OrderTo", args.object, args.target)
                status = json.loads(await call_asset(info, creds, "TMS", "OperationStatus", op))
                return op, status["source"] or f"where {args.object} is after {status['after']}"
            op = await call_asset(info, creds, "TMS", "SubmitTransportOperation", source,
                                  args.target, args.object)  # fmt: skip
        except OperationRefused as exc:
            raise InputError(f"the TMS refused the order: {exc.reason}") from None
        return op, source

    try:
        op, source = asyncio.run(submit())
    except (OSError, TimeoutError, ConnectionError) as exc:
        raise InputError(f"{where}: the TMS is not answering ({type(exc).__name__})") from None
    print(f"submitted {op}: {args.object} {source} -> {args.target}", flush=True)
    deadline = time.monotonic() + args.timeout
    shown = 0
    while True:
        try:
            status = json.loads(asyncio.run(call_asset(info, creds, "TMS", "OperationStatus", op)))
        except (OSError, TimeoutError, ConnectionError):
            status = None  # the TMS is restarting: the operation is in its state file
        if status is not None:
            for t, what in status["history"][shown:]:
                print(f"{time.strftime('%H:%M:%S', time.localtime(t))} {op}: {what}", flush=True)
            shown = len(status["history"])
            if status["state"] == "finished":
                break
        if time.monotonic() > deadline:
            raise InputError(f"{op} did not finish within --timeout {args.timeout:g} s; it goes "
                             "on on the floor ('cps status')")  # fmt: skip
        time.sleep(0.5)
    result = status["result"]
    line = f"{op} finished: {result['status']}; {args.object} is at {status['location']}"
    if result.get("reason"):
        line += f" ({result.get('failed_step')}: {result['reason']})"
    print(line)
    return 0 if result["status"] == "delivered" else ORDER_FAILED
