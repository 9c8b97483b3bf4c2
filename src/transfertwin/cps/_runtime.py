"""The demo cyber-physical system on loopback (Sec. 5.3, Fig. 5.8).

Every asset runs its own OPC UA server whose address space comes from its AAS. Virtual
transfer units and the virtual transport module are backed by the MuJoCo environment and by
the same OTS controller the in-process experiments use: the transport module drives its own
belts through its local (virtual) HAL and a docked unit's belts through that unit's OPC UA
interface (`OpcUaUnitHAL`), exactly as it would drive a physical unit. Logical assets: the
Transport Module System allocates transport operations to idle transport modules found in
the knowledge graph; the Experiment Manager runs experiments against a unit through its
OPC UA interface; PropS fuses reported poses; the knowledge graph serves SPARQL queries.
"""

from __future__ import annotations

import asyncio
import itertools
import json
import logging
from collections.abc import Awaitable, Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from transfertwin._atomic import write_atomic
from transfertwin._errors import InputError
from transfertwin.cps._plant_assets import PhysicalAssets, check_plant_seed, plant_representation
from transfertwin.cps.aas import (
    DEMO_PLACEMENT,
    AssetDescriptor,
    AssetKind,
    build_representation,
    demo_descriptors,
    externally_synced,
)
from transfertwin.cps.apps import (
    AssetApplications,
    Environment,
    FloorRobot,
    ObjectLedger,
    PoseGraph,
    docking_model,
)
from transfertwin.cps.kg import KnowledgeGraph
from transfertwin.cps.opcua import (
    ROLES,
    AssetServer,
    Credentials,
    Discovery,
    Peer,
    ServerConfig,
    connect,
    ensure_certificate,
    free_port,
    new_credentials,
    trust_certificate,
    write_credentials,
)
from transfertwin.sim import SceneConfig

__all__ = ["DOCKING_MODES", "Cps", "CpsConfig"]

#: Values of `CpsConfig.docking`.
DOCKING_MODES = ("sampled", "navigated")

log = logging.getLogger("transfertwin.cps")


@dataclass(frozen=True)
class CpsConfig:
    """Settings of the demo CPS.

    Attributes:
        workdir: Where cps.json, credentials, certificates and the log go.
        host: Interface the servers bind (loopback by default).
        insecure: Serve NoSecurity (explicit opt-in only).
        time_scale: Simulated seconds per wall second (0: as fast as possible).
        seed: Seed of the docking errors drawn for transport operations.
        gossip_period_s: Discovery gossip period of every asset.
        scene: Virtual system configuration.
        placement: Object id -> transfer unit it lies on when the CPS starts.
        docking: How the transport module gets to a station and sees the belts
            (docs/architecture.md, "Transport operation flow"): 'sampled' puts it at the
            station with a docking error drawn from the generator fitted to the real errors
            and forms the OTS from the simulation's true object box; 'navigated' plans and
            drives on the shop floor, docks by laser (the error emerges) and forms the OTS
            from its depth camera's workspace scan (about 1–2 s more per leg).
        plant_seed: Start an emulated plant drawn from this seed as the physical assets
            (``TU_A_P``…``TU_D_P``, `transfertwin.cps._plant_assets`); None: none.
    """

    workdir: Path
    host: str = "127.0.0.1"
    insecure: bool = False
    time_scale: float = 0.0
    seed: int = 0
    gossip_period_s: float = 1.0
    scene: SceneConfig = field(default_factory=SceneConfig)
    placement: Mapping[str, str] = field(default_factory=lambda: dict(DEMO_PLACEMENT))
    docking: str = "sampled"
    plant_seed: int | None = None

    def __post_init__(self) -> None:
        if self.docking not in DOCKING_MODES:
            raise InputError(f"CpsConfig.docking must be one of {', '.join(DOCKING_MODES)}, "
                             f"got {self.docking!r}")  # fmt: skip
        if self.plant_seed is not None:
            check_plant_seed(self.plant_seed)


@dataclass
class _Asset:
    desc: AssetDescriptor
    server: AssetServer
    discovery: Discovery | None = None


class Cps(PhysicalAssets, AssetApplications):
    """The running demo CPS (async context manager)."""

    def __init__(self, config: CpsConfig) -> None:
        self.config = config
        self.credentials: Credentials = new_credentials()
        self.assets: dict[str, _Asset] = {}
        self.kg = KnowledgeGraph()
        self.env = Environment(config.scene, config.time_scale)
        self.poses = PoseGraph()
        self._docking = docking_model()
        self._ops = itertools.count(1)
        self._tasks: set[asyncio.Task] = set()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._tm_free = asyncio.Condition()
        self._claimed: set[str] = set()  # transport modules allocated to an operation
        units = [d.asset_id for d in demo_descriptors() if d.asset_class == "transfer_unit"]
        self.ledger = ObjectLedger(config.placement, units)
        self.operations: dict[str, dict[str, object]] = {}
        self.completed: list[dict[str, object]] = []
        self.floor_robots = {d.asset_id: FloorRobot() for d in demo_descriptors()
                             if d.asset_class == "transport_module"}  # fmt: skip

    # -- life cycle -----------------------------------------------------------------------
    async def __aenter__(self) -> Cps:
        self._loop = asyncio.get_running_loop()
        wd = self.config.workdir
        wd.mkdir(parents=True, exist_ok=True)
        self.env.on_step(self._sync_barriers)
        if not self.config.insecure:  # the CPS's own clients (apps, web console) are trusted
            for role in ROLES:
                cert, _ = await ensure_certificate(self.cert_dir, f"client-{role}")
                trust_certificate(self.trust_dir, cert)
        for desc in demo_descriptors():
            await self._start(desc)
        await self._start_physical()
        for obj, holder in self.ledger.locations().items():
            await self._publish_location(obj, holder)
        write_credentials(wd / "credentials.json", self.credentials)
        write_atomic(wd / "cps.json", json.dumps(self.describe(), indent=2) + "\n")
        log.info("CPS up: %d assets", len(self.assets))
        return self

    async def __aexit__(self, *exc: object) -> None:
        for task in list(self._tasks):
            task.cancel()
        for aid, asset in reversed(list(self.assets.items())):
            if asset.discovery is not None:
                await asset.discovery.stop()
            self.kg.leave(aid)
        # Together: asyncua's stop waits for its server clock's next tick (up to 1 s each).
        await asyncio.gather(*(a.server.__aexit__(None, None, None) for a in self.assets.values()))
        self.assets.clear()
        (self.config.workdir / "cps.json").unlink(missing_ok=True)  # no stale endpoints
        log.info("CPS down")

    @property
    def cert_dir(self) -> Path:
        """Where the application certificates of the servers and clients are."""
        return self.config.workdir / "certs"

    @property
    def trust_dir(self) -> Path:
        """The servers' trust list of client certificates (`transfertwin cps trust`)."""
        return self.cert_dir / "trusted"

    def describe(self) -> dict[str, object]:
        """The cps.json content."""
        return {
            "assets": [
                {
                    "id": a.desc.asset_id,
                    "kind": a.desc.kind.value,
                    "type": a.desc.physical_type.value if a.desc.physical_type else None,
                    "class": a.desc.asset_class,
                    "endpoint": a.server.endpoint,
                    "security_policy": a.server.security_policy,
                }
                for a in self.assets.values()
            ],
            "credentials_file": str((self.config.workdir / "credentials.json").resolve()),
            "cert_dir": str(self.cert_dir.resolve()),
            "trust_dir": str(self.trust_dir.resolve()),
            "insecure": self.config.insecure,
        }

    async def _start(self, desc: AssetDescriptor) -> None:
        host = self.config.host
        port = free_port(host)
        endpoint = f"opc.tcp://{host}:{port}/transfertwin/{desc.asset_id}"
        if desc.kind is AssetKind.PHYSICAL:
            rep = plant_representation(desc, endpoint)
        else:
            rep = build_representation(
                desc, endpoint=endpoint, provenance="transfertwin virtual model (MuJoCo)"
            )
        writable = frozenset(("OperationalData", p) for p in externally_synced(rep))
        cfg = ServerConfig(
            host=host, port=port, insecure=self.config.insecure,
            cert_dir=self.cert_dir, trust_dir=self.trust_dir,
            credentials=None if self.config.insecure else self.credentials,
        )  # fmt: skip
        server = AssetServer(desc.asset_id, rep.submodels, cfg, self._handlers(desc), writable)
        await server.__aenter__()
        asset = _Asset(desc, server)
        self.assets[desc.asset_id] = asset
        asset.discovery = Discovery(
            server, period_s=self.config.gossip_period_s, on_change=self._peer_change(desc)
        )
        seeds = [a.server.endpoint for a in self.assets.values() if a is not asset][:1]
        await asset.discovery.join(seeds, self._connector)
        self.kg.join(desc, endpoint=server.endpoint, security_policy=server.security_policy)
        if desc.asset_class == "transport_module":
            self.kg.set_state(desc.asset_id, await server.get("OperationalData", "State"))
            await self._publish_pose(desc.asset_id)
        log.info("%s joined at %s", desc.asset_id, server.endpoint)

    async def leave(self, asset_id: str) -> None:
        """Take one asset off the network; its peers notice through discovery."""
        asset = self.assets.pop(asset_id)
        if asset.discovery is not None:
            await asset.discovery.stop()
        await asset.server.__aexit__(None, None, None)
        log.info("%s left", asset_id)

    def _peer_change(self, desc: AssetDescriptor) -> Callable[[str, Peer], None]:
        """The knowledge graph asset keeps the graph current from what its discovery sees."""

        def changed(kind: str, peer: Peer) -> None:
            if desc.asset_class == "knowledge_graph" and kind == "leave":
                self.kg.leave(peer.asset_id)

        return changed

    def _connector(self, url: str):
        """An operator session to a peer known only by its URL (discovery)."""
        return self._session(url, url.rsplit("/", 1)[-1])

    def _session(self, url: str, asset_id: str, role: str = "operator", timeout_s: float = 10.0):
        return connect(
            url, asset_id, credentials=None if self.config.insecure else self.credentials,
            role=role, cert_dir=self.cert_dir, insecure=self.config.insecure,
            timeout_s=timeout_s,
        )  # fmt: skip

    # -- clients --------------------------------------------------------------------------
    def client(self, asset_id: str, role: str = "operator"):
        """An OPC UA session with one asset of this CPS."""
        return self._session(self.assets[asset_id].server.endpoint, asset_id, role, 120.0)

    def _spawn(self, coro: Awaitable[object]) -> None:
        task = asyncio.ensure_future(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
