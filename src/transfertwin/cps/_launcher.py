"""Lay out a floor's asset processes and start them (docs/architecture.md, "Deployment").

`prepare_floor` writes the work folder: the floor file, the command-line clients'
certificates, and one **bundle** per asset, ``assets/<id>/``: everything its process needs
and nothing else, with paths relative to the bundle (`asset.toml`; a copy of the floor file,
of the people's user table (hashes, no password), of the plant seed for an asset on the
plant, of the study store for the Experiment Manager; its certificates, trust list and
state). A bundle copied to another
host runs there with ``transfertwin cps asset BUNDLE``. An asset listens on a loopback
address of its own, or on the address the floor file's ``[bind]`` gives it (then with
security only). `launch` starts one detached process per asset of this host: the floor does
not depend on the launcher staying alive, and any asset can be restarted by hand.
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
from collections.abc import Iterable
from dataclasses import replace
from pathlib import Path

from transfertwin._atomic import write_atomic
from transfertwin._errors import InputError
from transfertwin.cps._pki import prepare_certificates
from transfertwin.cps.floor import (
    PLANT_SEED_FILE,
    AssetConfig,
    FloorSpec,
    HalConfig,
    floor_toml,
    load_asset_config,
    write_asset_config,
    write_plant_seed,
)
from transfertwin.cps.node import default_lease
from transfertwin.cps.opcua import (
    free_port,
    load_credentials,
    new_credentials,
    write_credentials,
    write_user_table,
)
from transfertwin.cps.roles import PLANT_LOG

__all__ = ["BUNDLE_CONFIG", "asset_pids", "bundle_config", "floor_configs", "launch",
           "local_address", "prepare_floor", "stop_floor"]  # fmt: skip

#: Seeds every asset joins through: the knowledge graph and the TMS.
SEED_ASSETS = ("KG", "TMS")

#: The asset's own file in its bundle (``assets/<id>/asset.toml``).
BUNDLE_CONFIG = "asset.toml"

#: The port of an asset bound beyond loopback (``[bind]`` without a port): OPC UA's own;
#: a second asset on the same address gets the next one.
BIND_PORT = 4840


def bundle_config(path: Path) -> Path:
    """The asset file of `path`: a bundle folder's ``asset.toml``, or `path` itself."""
    return path / BUNDLE_CONFIG if path.is_dir() else path


def local_address(host: str) -> bool:
    """Whether this host has address `host` (an asset bound to it can start here)."""
    if ipaddress.ip_address(host).is_loopback:
        return True
    with contextlib.suppress(OSError), socket.socket() as s:
        s.bind((host, 0))
        return True
    return False


def _address(i: int, base: str) -> str:
    """The i-th emulated host: consecutive loopback addresses from `base`."""
    return str(ipaddress.ip_address(base) + i)


def prepare_floor(
    floor: FloorSpec,
    workdir: Path,
    *,
    insecure: bool = False,
    seed: int = 0,
    time_scale: float = 1.0,
    docking: str = "sampled",
    lease_s: float | None = None,
    base_host: str = "127.0.0.2",
    plant_seed: int | None = None,
    plant_kind: str = "in-class",
    plant_mismatch_off: tuple[str, ...] = (),
) -> dict[str, AssetConfig]:
    """Write the floor's work folder and every asset's bundle; returns asset id -> its
    configuration (absolute paths; the bundle's file holds them relative to the bundle).

    A work folder used before keeps its credentials, certificates and every asset's state
    (the ledger, operation ids, possessions): a floor started again goes on where it was.
    A floor with assets on the emulated plant (``hal = "plant"``) needs `plant_seed` (and
    `plant_kind`, 'in-class' or 'mismatch', `FLOOR_PLANT_KINDS`, and the mismatch parts
    switched off, `plant_mismatch_off`, for an ablation); it is
    written to ``W/plant.secret`` (owner-only) and copied into those assets' bundles only.
    The floor's study store is copied into the Experiment Manager's bundle, which answers
    the TMS's questions from it. Without `lease_s` the floor gets the default lease for its
    size (`default_lease`).
    """
    if floor.uses_plant() and plant_seed is None:
        raise InputError(f"floor {floor.name} runs assets on the emulated plant (hal = "
                         "\"plant\"): give the plant seed (cps up --plant-seed N)")  # fmt: skip
    if insecure and floor.bind:
        raise InputError(f"floor {floor.name} binds assets beyond loopback ([bind]): they are "
                         "served only with security (drop --insecure)")  # fmt: skip
    workdir.mkdir(parents=True, exist_ok=True)
    seed_file = None
    if floor.uses_plant():
        seed_file = write_plant_seed(workdir / PLANT_SEED_FILE, plant_seed,
                                     plant_kind, plant_mismatch_off).resolve()
    write_atomic(workdir / "floor.toml", floor_toml(floor))
    study = floor.operation.study
    # an asset's copy of the floor names no file of another host (the study is the EM's)
    bundled = floor_toml(replace(floor, operation=replace(floor.operation, study=None)))
    creds_file = workdir / "credentials.json"
    if not insecure and not creds_file.is_file():
        write_credentials(creds_file, new_credentials())
    users_file = None if insecure else _user_table(creds_file, workdir / "users.json")
    descs = floor.descriptors()
    if lease_s is None:
        lease_s = default_lease(len(descs))
    order = sorted(descs, key=lambda d: (d.asset_id not in SEED_ASSETS, d.asset_id))
    hosts, ports = _addresses(floor, [d.asset_id for d in order], base_host)
    seeds = tuple(f"opc.tcp://{hosts[a]}:{ports[a]}/transfertwin/{a}" for a in SEED_ASSETS)
    configs = {}
    for d in descs:
        aid = d.asset_id
        home = (workdir / "assets" / aid).resolve()
        home.mkdir(parents=True, exist_ok=True)
        floor_file = write_atomic(home / "floor.toml", bundled)
        kind, gateway = floor.hal_of(aid)
        own_seed = _copy_private(seed_file, home / PLANT_SEED_FILE) if kind == "plant" else None
        hal = HalConfig(kind, plant_seed_file=own_seed, endpoint=gateway,
                        insecure=insecure)  # fmt: skip
        own_study = None
        if floor.uses_plant() and d.role_class == "experiment_manager":
            _rotate(home / PLANT_LOG)  # this start's E^P rows in a table of their own
        if study is not None and d.role_class == "experiment_manager":
            own_study = _copy_private(Path(study), home / "study.sqlite")
        configs[aid] = AssetConfig(
            asset_id=aid, floor_file=floor_file, host=hosts[aid], port=ports[aid],
            seeds=seeds, cert_dir=home / "certs", trust_dir=home / "trusted",
            credentials_file=None if insecure else _copy_private(users_file,
                                                                 home / "users.json"),
            state_dir=home / "state", insecure=insecure,
            allow_remote=not ipaddress.ip_address(hosts[aid]).is_loopback, lease_s=lease_s,
            seed=seed, time_scale=time_scale, docking=docking, hal=hal, study_file=own_study,
        )  # fmt: skip
        write_asset_config(home / BUNDLE_CONFIG, configs[aid], relative=True)
    if not insecure:
        asyncio.run(_certificates(workdir, configs.values()))
    return configs


def _addresses(floor: FloorSpec, order: list[str],
               base_host: str) -> tuple[dict[str, str], dict[str, int]]:  # fmt: skip
    """Each asset's address and port: the floor file's ``[bind]`` (port `BIND_PORT` and up
    where it gives none), else consecutive loopback addresses from `base_host` and a free
    port there."""
    hosts, ports = {}, {}
    used = {tuple(v.split(":")) for _, v in floor.bind if ":" in v}
    i = 0
    for aid in order:
        bound = floor.bind_address(aid)
        if bound is None:
            hosts[aid] = _address(i, base_host)
            ports[aid] = free_port(hosts[aid])
            i += 1
            continue
        hosts[aid], port = bound
        if port is None:
            port = BIND_PORT
            while (hosts[aid], str(port)) in used:
                port += 1
            used.add((hosts[aid], str(port)))
        ports[aid] = port
    return hosts, ports


def _user_table(creds_file: Path, table: Path) -> Path:
    """``W/users.json``: the people's users as the servers check them (salted scrypt
    hashes, no password: `write_user_table`), made again when the credentials changed.
    Every bundle gets a copy; the passwords stay in ``W/credentials.json``."""
    if not table.is_file() or table.stat().st_mtime_ns < creds_file.stat().st_mtime_ns:
        write_user_table(table, load_credentials(creds_file))
    return table


def _copy_private(source: Path, target: Path) -> Path:
    """Copy `source` to `target` (owner-only, as the secrets and credentials are), unless
    `target` holds it already; returns `target`."""
    if not source.is_file():
        raise InputError(f"{source}: no such file")
    if not (target.is_file() and target.stat().st_size == source.stat().st_size
            and target.read_bytes() == source.read_bytes()):  # fmt: skip
        tmp = target.with_name(f".{target.name}.tmp")
        shutil.copyfile(source, tmp)
        os.chmod(tmp, 0o600)
        os.replace(tmp, target)
    return target


async def _certificates(workdir: Path, configs: Iterable[AssetConfig]) -> None:
    """Every asset's certificate signed by the floor's CA (``W/ca``), the command-line
    clients' too, and in every trust folder the CA and its CRL (`prepare_certificates`)."""
    prepare_certificates(workdir, configs)


def _rotate(path: Path) -> None:
    """Move an earlier start's table out of the way (``NAME.1.csv``, ``NAME.2.csv``, ...)."""
    if not path.exists():
        return
    n = 1
    while (old := path.with_name(f"{path.stem}.{n}{path.suffix}")).exists():
        n += 1
    path.rename(old)


def floor_configs(workdir: Path) -> dict[str, AssetConfig]:
    """The asset configurations of a prepared work folder (its bundles)."""
    return {p.parent.name: load_asset_config(p)
            for p in sorted((workdir / "assets").glob(f"*/{BUNDLE_CONFIG}"))}  # fmt: skip


def launch(configs: dict[str, AssetConfig], workdir: Path, skip: Iterable[str] = (), *,
           fork: bool = True) -> dict[str, subprocess.Popen | ForkedAsset]:  # fmt: skip
    """Start one detached process per asset (logs in ``W/logs/<id>.log``).

    With `fork` (the default) one ``cps asset`` process prepares what every asset needs
    once and forks the asset processes from it (they share those pages copy-on-write:
    docs/scaling.md), then exits; otherwise each asset is an interpreter of its own
    (`start_asset`, as a restart by hand is).
    """
    logs = workdir / "logs"
    logs.mkdir(parents=True, exist_ok=True)
    skip = set(skip)
    order = [a for a in sorted(configs, key=lambda a: (a not in SEED_ASSETS, a)) if a not in skip]
    files = {aid: workdir / "assets" / aid / BUNDLE_CONFIG for aid in order}
    if not fork:
        return {aid: start_asset(files[aid], logs / f"{aid}.log") for aid in order}
    # the seeds first, and the rest once they answer: an asset joins through them
    seeds = [a for a in order if a in SEED_ASSETS]
    procs = _fork(seeds, files, logs)
    _wait_listening({a: configs[a] for a in seeds}, procs)
    procs.update(_fork([a for a in order if a not in SEED_ASSETS], files, logs))
    return procs


def _fork(order: list[str], files: dict[str, Path], logs: Path) -> dict[str, ForkedAsset]:
    """Fork the assets `order` from one ``cps asset --config ... --log-dir`` process."""
    if not order:
        return {}
    cmd = [sys.executable, "-m", "transfertwin", "cps", "asset", "--log-dir", str(logs)]
    for aid in order:
        cmd += ["--config", str(files[aid])]
    done = subprocess.run(cmd, capture_output=True, text=True, stdin=subprocess.DEVNULL,
                          timeout=120, env={**os.environ, "PYTHONUNBUFFERED": "1"})  # fmt: skip
    procs = {}
    for line in done.stdout.splitlines():
        word, aid, pid = [*line.split(), "", "", ""][:3]
        if word == "forked" and aid in files and pid.isdigit():
            procs[aid] = ForkedAsset(int(pid))
    if done.returncode != 0 or set(procs) != set(order):
        for p in procs.values():
            p.kill()
        last = (done.stderr.strip().splitlines() or ["no output"])[-1]
        raise InputError(f"the asset processes could not be started ({done.returncode}): {last}")
    return procs


def _wait_listening(configs: dict[str, AssetConfig], procs, timeout_s: float = 60.0) -> None:
    """Wait until every asset in `configs` accepts connections on its port (or has ended:
    the caller's wait for the floor reports that)."""
    import time

    deadline = time.monotonic() + timeout_s
    waiting = dict(configs)
    while waiting and time.monotonic() < deadline:
        for aid, cfg in list(waiting.items()):
            if procs[aid].poll() is not None:
                waiting.pop(aid)
                continue
            with contextlib.suppress(OSError), socket.create_connection((cfg.host, cfg.port), 0.5):
                waiting.pop(aid)
        time.sleep(0.1)


class ForkedAsset:
    """A forked asset process, seen as much like a `subprocess.Popen` as a launcher needs
    (`pid`, `poll`, `wait`, `kill`); it is not this process's child, so its exit code is
    not known here (``returncode`` 'unknown' once it has ended)."""

    def __init__(self, pid: int) -> None:
        self.pid = pid
        self.returncode: str | None = None

    def poll(self) -> str | None:
        if self.returncode is None and not pid_alive(self.pid):
            self.returncode = "unknown"
        return self.returncode

    def wait(self, timeout: float | None = None) -> str:
        import time

        deadline = None if timeout is None else time.monotonic() + timeout
        while self.poll() is None:
            if deadline is not None and time.monotonic() > deadline:
                raise subprocess.TimeoutExpired(f"asset process {self.pid}", timeout)
            time.sleep(0.1)
        return self.returncode

    def kill(self) -> None:
        with contextlib.suppress(OSError):
            os.kill(self.pid, signal.SIGKILL)


def pid_alive(pid: int) -> bool:
    """Whether process `pid` runs (a zombie, ended but not reaped, does not)."""
    try:
        os.kill(pid, 0)
    except OSError:
        return False
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return True
    return state not in ("Z", "X")


def start_asset(config: Path, log_file: Path) -> subprocess.Popen:
    """`transfertwin cps asset --config CONFIG` in a session of its own."""
    with log_file.open("ab") as out:
        return subprocess.Popen(
            [sys.executable, "-m", "transfertwin", "cps", "asset", "--config", str(config)],
            stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
            start_new_session=True, env={**os.environ, "PYTHONUNBUFFERED": "1"},
        )  # fmt: skip


def write_floor_info(workdir: Path, configs: dict[str, AssetConfig], floor: FloorSpec) -> Path:
    """``W/cps.json``: the endpoints and security of the floor, for its clients."""
    by_id = {d.asset_id: d for d in floor.descriptors()}
    standby = floor.standby()
    first = next(iter(configs.values()))
    info = {
        "floor": str((workdir / "floor.toml").resolve()),
        "assets": [{"id": aid, "kind": by_id[aid].kind.value, "class": by_id[aid].asset_class,
                    "role_class": by_id[aid].role_class,
                    "type": by_id[aid].physical_type.value if by_id[aid].physical_type else None,
                    "endpoint": cfg.endpoint,
                    "security_policy": "None" if cfg.insecure else "Basic256Sha256_SignAndEncrypt",
                    "config": str((workdir / "assets" / aid / BUNDLE_CONFIG).resolve()),
                    "standby": aid in standby}
                   for aid, cfg in sorted(configs.items())],
        "credentials_file": None if first.insecure else str((workdir / "credentials.json")
                                                                .resolve()),
        "cert_dir": str((workdir / "certs").resolve()),
        "trust_dir": str((workdir / "certs" / "trusted").resolve()),
        "insecure": first.insecure,
        "policy": floor.operation.policy,
        "groups": [[g, list(units)] for g, units in floor.operation.groups],
    }
    return write_atomic(workdir / "cps.json", json.dumps(info, indent=2) + "\n")


def asset_pids(workdir: Path) -> dict[str, int]:
    """Asset id -> pid of its running process (from the pid files the processes keep)."""
    pids = {}
    for f in (workdir / "assets").glob("*/state/pid"):
        try:
            pid = int(f.read_text())
        except (ValueError, OSError):
            continue
        if pid_alive(pid):
            pids[f.parent.parent.name] = pid
    return pids


def stop_floor(workdir: Path, sig: int = signal.SIGTERM) -> dict[str, int]:
    """Send `sig` to every asset process of the floor; returns those signalled."""
    pids = asset_pids(workdir)
    for pid in pids.values():
        with contextlib.suppress(OSError):
            os.kill(pid, sig)
    return pids


def check_workdir(workdir: Path) -> None:
    """Refuse a work folder whose floor is still running."""
    running = asset_pids(workdir)
    if running:
        raise InputError(f"{workdir}: a floor is running there ({len(running)} asset processes, "
                         f"e.g. {next(iter(running))}); stop it with 'transfertwin cps down "
                         f"--workdir {workdir}'")  # fmt: skip
