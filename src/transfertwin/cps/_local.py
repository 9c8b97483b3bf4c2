"""A floor in one process (`cps up --single-process`): the same asset nodes and roles as a
floor of processes, in one event loop (`LocalFloor`).

The work folder is prepared as for a floor of processes (`prepare_floor`: the floor file,
each asset's file, certificates, trust lists, state folders), and ``W/cps.json`` says
where each asset answers, so every client (`cps status`, `cps order`, the web console)
talks to it as to any floor. An operator's ``Shutdown`` of an asset stops that node; once
every node has stopped so, `ended` is set. Each asset's pid file names this process, the
one-host fallback of `cps down` (once per asset, the first signal is enough), and a floor
started again in the same folder goes on where it was. Once every node has stopped,
cps.json goes: the floor is gone with the process (an asset of a floor of processes can
be restarted by hand; here none).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import time
from pathlib import Path

from transfertwin._aio import stop_tasks
from transfertwin._errors import InputError
from transfertwin.cps._compose import asset_node
from transfertwin.cps._launcher import SEED_ASSETS, check_workdir, prepare_floor, write_floor_info
from transfertwin.cps.floor import AssetConfig, FloorSpec
from transfertwin.cps.node import AssetNode
from transfertwin.cps.opcua import connect, load_credentials

__all__ = ["STOP_LIMIT_S", "LocalFloor"]

log = logging.getLogger("transfertwin.cps")

#: Seconds one node may take to stop (its leave, its role, its sessions and server).
STOP_LIMIT_S = 15.0


class LocalFloor:
    """Every asset of `floor` on a node in this event loop (async context manager).

    Args:
        floor: The floor.
        workdir: Its work folder (prepared here; one used before keeps its state).
        insecure, seed, time_scale, docking, lease_s, plant_seed, plant_kind: As
            `prepare_floor` takes them.
        plant_mismatch_off, base_host: As `prepare_floor` takes them.
        online_timeout_s: How long entering waits until the graph holds every asset's lease.
    """

    def __init__(self, floor: FloorSpec, workdir: Path, *, insecure: bool = False,
                 seed: int = 0, time_scale: float = 1.0, docking: str = "sampled",
                 lease_s: float | None = None, plant_seed: int | None = None,
                 plant_kind: str = "in-class", plant_mismatch_off: tuple[str, ...] = (),
                 base_host: str = "127.0.0.2", online_timeout_s: float = 60.0) -> None:  # fmt: skip
        self.floor = floor
        self.workdir = Path(workdir)
        self._prepare = dict(insecure=insecure, seed=seed, time_scale=time_scale,
                             docking=docking, lease_s=lease_s, plant_seed=plant_seed,
                             plant_kind=plant_kind, plant_mismatch_off=plant_mismatch_off,
                             base_host=base_host)  # fmt: skip
        self._online_timeout_s = online_timeout_s
        self.configs: dict[str, AssetConfig] = {}
        self.nodes: dict[str, AssetNode] = {}
        #: Set once every node has stopped on an operator's ``Shutdown``.
        self.ended = asyncio.Event()
        self._watches: set[asyncio.Task] = set()

    # -- life cycle -----------------------------------------------------------------------
    async def __aenter__(self) -> LocalFloor:
        check_workdir(self.workdir)
        self.configs = await asyncio.to_thread(prepare_floor, self.floor, self.workdir,
                                               **self._prepare)  # fmt: skip
        write_floor_info(self.workdir, self.configs, self.floor)
        standby = self.floor.standby()
        order = [a for a in self.configs if a not in standby]
        try:
            for aid in (a for a in SEED_ASSETS if a in order):  # an asset joins through them
                await self.start(aid)
            await asyncio.gather(*(self.start(a) for a in order if a not in SEED_ASSETS))
            await self._online(set(order))
        except BaseException:
            await self.__aexit__(None, None, None)
            raise
        log.info("floor %s up in one process: %d assets", self.floor.name, len(self.nodes))
        return self

    async def __aexit__(self, *exc: object) -> None:
        await stop_tasks(list(self._watches))
        rest = [a for a in self.nodes if a not in SEED_ASSETS]
        await asyncio.gather(*(self.stop(a) for a in rest), return_exceptions=True)
        for aid in [a for a in SEED_ASSETS if a in self.nodes][::-1]:
            with contextlib.suppress(Exception):
                await self.stop(aid)
        # the floor is gone with this process: no stale endpoints for its clients
        (self.workdir / "cps.json").unlink(missing_ok=True)
        log.info("floor %s down", self.floor.name)

    async def start(self, aid: str) -> AssetNode:
        """Start asset `aid` (one on standby, or one stopped before) in this process."""
        if aid in self.nodes:
            raise InputError(f"{aid} runs already")
        cfg = self.configs.get(aid)
        if cfg is None:
            raise InputError(f"no asset {aid!r} on floor {self.floor.name}")
        node = asset_node(cfg, self.floor)
        cfg.state_dir.mkdir(parents=True, exist_ok=True)
        (cfg.state_dir / "pid").write_text(f"{os.getpid()}\n")  # 'cps down' finds it
        try:
            await node.__aenter__()
        except BaseException:
            (cfg.state_dir / "pid").unlink(missing_ok=True)
            raise
        self.nodes[aid] = node
        watch = asyncio.ensure_future(self._on_shutdown(aid, node))
        self._watches.add(watch)
        watch.add_done_callback(self._watches.discard)
        return node

    async def _on_shutdown(self, aid: str, node: AssetNode) -> None:
        """Stop `aid` when an operator asks it to (``Shutdown``); the last one ends the floor."""
        await node.shutdown.wait()
        if self.nodes.get(aid) is node:
            await self.stop(aid)
        if not self.nodes:
            self.ended.set()

    async def stop(self, aid: str) -> None:
        """Take asset `aid` off the floor: it announces its leave and stops serving (within
        `STOP_LIMIT_S`; a stop that hangs is logged and given up, as a process's is)."""
        node = self.nodes.pop(aid)
        try:
            await asyncio.wait_for(node.__aexit__(None, None, None), STOP_LIMIT_S)
        except TimeoutError:
            log.warning("%s did not stop within %g s; left behind", aid, STOP_LIMIT_S)
        finally:
            (self.configs[aid].state_dir / "pid").unlink(missing_ok=True)

    async def _online(self, expected: set[str]) -> None:
        """Wait until the knowledge graph holds a lease of every asset in `expected`."""
        graph = self.nodes.get("KG")
        if graph is None:
            return
        deadline = time.monotonic() + self._online_timeout_s
        while not expected <= set(graph.role.leases) | {"KG"}:
            if time.monotonic() > deadline:
                missing = sorted(expected - set(graph.role.leases) - {"KG"})
                raise InputError(f"floor {self.floor.name}: not online within "
                                 f"{self._online_timeout_s:g} s: {', '.join(missing[:8])}")
            await asyncio.sleep(0.05)

    # -- clients --------------------------------------------------------------------------
    def client(self, aid: str, role: str = "operator", timeout_s: float = 120.0):
        """An OPC UA session with asset `aid` as a command-line client has it (the work
        folder's client certificates and credentials), as an async context manager."""
        cfg = self.configs[aid]
        insecure = cfg.insecure
        return connect(cfg.endpoint, aid,
                       credentials=None if insecure else load_credentials(
                           self.workdir / "credentials.json"),
                       role=role, cert_dir=self.workdir / "certs", insecure=insecure,
                       timeout_s=timeout_s)  # fmt: skip
