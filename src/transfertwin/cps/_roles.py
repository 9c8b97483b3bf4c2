"""What each asset does in its own process (`AssetNode`): transfer units, objects and the
knowledge graph. The transport module and the TMS, which carry the transport operations,
are in `_role_tm` and `_role_tms`; PropS in `_role_props`, the Experiment Manager in
`_role_em`.

Every role offers `handlers()` (the OPC UA operations), `writable()` (properties others
may write besides the externally synchronised ones), `live()` (its part of the heartbeat),
`start()` and `stop()`.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import time
from typing import TYPE_CHECKING, Any

from transfertwin._errors import InputError
from transfertwin.cps._lease import NO_LEASE, directory_reply
from transfertwin.cps._node import NodeState
from transfertwin.cps.opcua import OperationRefused

if TYPE_CHECKING:
    from transfertwin.cps._node import AssetNode

__all__ = ["Role", "role_for"]

log = logging.getLogger("transfertwin.cps")


class Role:
    """The default role: serve the AAS, nothing else."""

    def __init__(self, node: AssetNode) -> None:
        self.node = node
        self.aid = node.desc.asset_id
        self.state = NodeState(node.cfg.state_dir / f"{self.aid}.json", self.initial())

    def initial(self) -> dict[str, Any]:
        """The persisted state before the first save."""
        return {}

    def handlers(self) -> dict[str, Any]:
        return {}

    def writable(self) -> set[str]:
        return set()

    async def start(self) -> None:
        pass

    async def stop(self) -> None:
        pass

    async def live(self) -> dict[str, Any]:
        """This asset's live state for the heartbeat."""
        return {"state": "idle"}

    async def set(self, prop: str, value: object) -> None:
        """Set one of this asset's OperationalData properties."""
        await self.node.server.set("OperationalData", prop, value)

    async def get(self, prop: str) -> Any:
        return await self.node.server.get("OperationalData", prop)


#: How often a unit tells PropS its pose again, s.
POSE_REPORT_S = 60.0


class UnitRole(Role):
    """A transfer unit (type D/E): belt drives, possession kept by others.

    With a virtual or plant HAL its light barriers are written by the environment that
    simulates it (the docked module's process). With a remote HAL (`GatewayHAL`) its belt
    commands go to the hardware's gateway and its barriers are read from there every
    ``poll_s`` and published; nobody else may write them.
    """

    def __init__(self, node: AssetNode) -> None:
        super().__init__(node)
        self.gateway = None
        if node.cfg.hal.kind == "remote":
            from transfertwin.cps._hal import GatewayHAL

            self.gateway = GatewayHAL(node.cfg)

    def initial(self) -> dict[str, Any]:
        return {"possessed": [], "docked": ""}

    def handlers(self) -> dict[str, Any]:
        return {"SetBeltSpeed": self._set_belt, "SetPossessedObjects": self._set_possessed}

    def writable(self) -> set[str]:
        if self.gateway is not None:
            return set()  # the hardware's barriers: read from its gateway only
        return {"BarrierNearInterrupted", "BarrierFarInterrupted"}

    async def start(self) -> None:
        await self.set("PossessedObjects", ",".join(self.state.data["possessed"]))
        await self.set("DockedTransportModule", self.state.data["docked"])
        self.node.server.on_client_write(self._written)
        if self.gateway is not None:
            self.node.spawn(self._poll_barriers())
        if "PropS" in self.node.floor.logical:
            self.node.spawn(self._report_pose())

    async def _report_pose(self) -> None:
        """Tell PropS where this unit stands (its surveyed docking goal on the floor), and
        again every `POSE_REPORT_S` (a restarted PropS hears it then)."""
        from transfertwin.cps._role_props import UNIT_SIGMA_THETA_RAD, UNIT_SIGMA_XY_M

        floor = self.node.floor
        spec = next(s for s in floor.stations if s.unit == self.aid)
        x, y, theta = (float(v) for v in floor.shop_floor().station(spec.name).goal_pose())
        while True:
            try:
                await asyncio.wait_for(self.node.peers.call(
                    "PropS", "ReportPose", self.aid, self.aid, x, y, theta, UNIT_SIGMA_XY_M,
                    UNIT_SIGMA_THETA_RAD), 10.0)  # fmt: skip
                delay = POSE_REPORT_S
            except Exception as exc:  # PropS not (yet) there: try again soon
                log.debug("%s: PropS not answering (%s)", self.aid, exc)
                delay = 2.0
            await asyncio.sleep(delay)

    async def stop(self) -> None:
        if self.gateway is not None:
            await self.gateway.close()

    async def _poll_barriers(self) -> None:
        """Publish the gateway's barriers as they change (a gateway away: said once, kept
        trying; the last values stay)."""
        from transfertwin.cps._gateway import poll_gateway

        shown: dict[str, bool] | None = None

        async def publish(now: dict[str, bool]) -> None:
            nonlocal shown
            if now != shown:
                await self.set("BarrierNearInterrupted", now["near"])
                await self.set("BarrierFarInterrupted", now["far"])
                shown = now

        await poll_gateway(self.aid, self.gateway.barriers, self.node.cfg.hal.poll_s, publish)

    def _written(self, submodel: str, prop: str, value: object) -> None:
        if prop == "PossessedObjects":
            self.state.data["possessed"] = [o for o in str(value).split(",") if o]
            self.state.save()
        elif prop == "DockedTransportModule":
            self.state.data["docked"] = str(value)
            self.state.save()

    async def _set_belt(self, belt: str, speed: float) -> bool:
        if belt not in ("left", "right"):
            raise ValueError(f"unknown belt {belt!r}")
        if self.gateway is not None:  # the drive first: publish what the hardware was told
            await self.gateway.set_belt(belt, float(speed))
        await self.set(f"BeltSpeed{belt.capitalize()}", float(speed))
        return True

    async def _set_possessed(self, objects: str) -> bool:
        ids = [o for o in objects.split(",") if o]
        await self.set("PossessedObjects", ",".join(ids))
        self.state.data["possessed"] = ids
        self.state.save()
        return True

    async def live(self) -> dict[str, Any]:
        docked = await self.get("DockedTransportModule")
        return {"state": "docked" if docked else "idle", "docked": docked or None,
                "possesses": self.state.data["possessed"]}  # fmt: skip


class ObjectRole(Role):
    """A virtual object (type B): others keep its state; it persists what they wrote."""

    def initial(self) -> dict[str, Any]:
        return {"possessed_by": self.node.floor.placement().get(self.aid, "")}

    async def start(self) -> None:
        await self.set("PossessedBy", self.state.data["possessed_by"])
        self.node.server.on_client_write(self._written)

    def _written(self, submodel: str, prop: str, value: object) -> None:
        if prop == "PossessedBy":
            self.state.data["possessed_by"] = str(value)
            self.state.save()

    async def live(self) -> dict[str, Any]:
        return {"state": "idle", "location": self.state.data["possessed_by"] or None}


class GraphRole(Role):
    """The knowledge graph: the semantic layer, kept current by the other assets' leases.

    Its content is soft state: a heartbeat carries the sender's whole description when it
    changed, a renewal otherwise, and the graph refuses the renewal of a lease it does not
    hold (`_lease.NO_LEASE`), upon which the asset sends its description; so a restarted
    graph is complete again one heartbeat period after it comes back. Its directory (the
    online assets' endpoints) has a version that changes with every join, leave and move;
    a heartbeat gets the directory only when the sender holds another version.
    """

    def __init__(self, node: AssetNode) -> None:
        super().__init__(node)
        self.kg = None
        self.leases: dict[str, float] = {}  # asset id -> monotonic deadline
        self.info: dict[str, dict[str, Any]] = {}  # last heartbeat per asset
        self.gone: dict[str, dict[str, Any]] = {}  # offline asset -> why and since when
        self.beats = {"full": 0, "renewals": 0, "refused": 0}  # heartbeats taken, by kind
        self.stalled_s = 0.0  # time the graph did not run, which its leases did not count
        self._boot = f"{time.time_ns():x}"  # a directory version from an earlier graph
        self._directory = 0  # ... never equals one of this graph's
        self._changed = True  # the graph changed since its counts were last published
        self._lock = asyncio.Lock()

    def handlers(self) -> dict[str, Any]:
        return {"Query": self._query, "Heartbeat": self._heartbeat, "Leave": self._leave,
                "Status": self._status}  # fmt: skip

    async def start(self) -> None:
        from transfertwin.cps.kg import KnowledgeGraph

        srv = self.node.server
        self.kg = KnowledgeGraph(self.aid, endpoint=srv.endpoint,
                                 security_policy=srv.security_policy)  # fmt: skip
        self.node.spawn(self._expire())

    async def beat_self(self) -> None:
        """The graph's own lease (it is an asset like any other)."""
        import os

        srv = self.node.server
        self.info[self.aid] = {"id": self.aid, "kind": "logical", "class": "knowledge_graph",
                               "endpoint": srv.endpoint, "pid": os.getpid(), "state": "idle",
                               "seen": time.time()}  # fmt: skip
        await self._counts()

    async def _counts(self) -> None:
        """Publish the graph's size (two SPARQL counts: only when something changed)."""
        if not self._changed:
            return
        self._changed = False
        await self.set("Triples", self.kg.triples())
        await self.set("Assets", len(self.kg.assets(online_only=True)))

    def _moved(self) -> None:
        """The directory changed (an asset joined, left or answers elsewhere)."""
        self._directory += 1
        self._changed = True

    def _reply(self, held: str | None) -> str:
        endpoints = {a: i["endpoint"] for a, i in self.info.items()
                     if a in self.leases or a == self.aid}  # fmt: skip
        return directory_reply(f"{self._boot}.{self._directory}", endpoints, held)

    async def _query(self, sparql: str) -> str:
        return json.dumps(self.kg.query(sparql))

    async def _heartbeat(self, payload: str) -> str:
        from transfertwin.cps.aas import AssetDescriptor, AssetKind, Capability, PhysicalType

        d = json.loads(payload)
        aid = d["id"]
        held = d.pop("directory", None)
        fresh = aid not in self.leases or self.info.get(aid, {}).get("pid") != d.get("pid")
        if d.get("renew"):
            if fresh:
                self.beats["refused"] += 1
                raise OperationRefused(f"no lease of {aid} (pid {d.get('pid')}) held here: "
                                       "send the full heartbeat", status=NO_LEASE)  # fmt: skip
            self.beats["renewals"] += 1
            self.leases[aid] = time.monotonic() + self.node.cfg.lease_s
            self.info[aid]["seen"] = time.time()
            return self._reply(held)
        self.beats["full"] += 1
        self.leases[aid] = time.monotonic() + self.node.cfg.lease_s
        self.gone.pop(aid, None)
        d["seen"] = time.time()
        before = self.info.get(aid)
        self.info[aid] = d
        if fresh or before is None or before.get("endpoint") != d["endpoint"]:
            self._moved()
        if fresh:
            desc = AssetDescriptor(
                aid, AssetKind(d["kind"]), d["class"],
                physical_type=PhysicalType(d["type"]) if d.get("type") else None,
                capabilities=tuple(Capability(c) for c in d.get("capabilities", ())),
                station=d.get("station"), models=d.get("models"),
            )  # fmt: skip
            self.kg.join(desc, endpoint=d["endpoint"], security_policy=d["security_policy"],
                         state=_state_word(d.get("state")))  # fmt: skip
            log.info("KG: %s joined (pid %s, %s)", aid, d.get("pid"), d["endpoint"])
        self._apply(aid, d)
        self._changed = True
        return self._reply(held)

    def _apply(self, aid: str, d: dict[str, Any]) -> None:
        """The live part of a heartbeat into the graph (each fact on its own: one that does
        not fit yet, e.g. a location on an asset not joined, waits for the next beat)."""
        kg = self.kg
        updates = [lambda: kg.set_state(aid, _state_word(d.get("state")) or "idle")]
        if d["class"] == "transport_module":
            docked = d.get("docked")
            updates.append(lambda: kg.set_docked(aid, docked if docked in self.leases else None))
        if "possesses" in d:
            updates.append(lambda: kg.set_possesses(aid, d["possesses"]))
        if d["class"] == "object" and d.get("location") in self.leases:
            updates.append(lambda: kg.set_location(aid, d["location"]))
        for update in updates:
            try:
                update()
            except InputError as exc:
                log.debug("KG: %s: %s", aid, exc)

    async def _leave(self, aid: str) -> bool:
        if aid in self.leases:
            del self.leases[aid]
            self.kg.leave(aid)
            self._moved()
            self.gone[aid] = {"reason": "left", "at": time.time(),
                              "detail": "announced its leave"}  # fmt: skip
            log.info("KG: %s left", aid)
        return True

    async def _expire(self) -> None:
        counted = 0.0
        last = time.monotonic()
        while True:
            await asyncio.sleep(0.25)
            now = time.monotonic()
            late = now - last - 0.25
            last = now
            if late > 0.1:
                # the graph itself did not run for that long (a starved host, a burst of
                # joins): heartbeats may be waiting unread in its sockets, and that time is
                # not the assets' silence. Without this, an overloaded graph expired the
                # leases it had not read, the assets joined again in full, and the load grew.
                self.stalled_s += late
                for aid in self.leases:
                    self.leases[aid] += late
            for aid in [a for a, t in self.leases.items() if t < now]:
                del self.leases[aid]
                with contextlib.suppress(InputError):
                    self.kg.leave(aid)
                self._moved()
                self.gone[aid] = {"reason": "lapsed", "at": time.time(),
                                  "detail": f"no heartbeat for {self.node.cfg.lease_s:g} s "
                                            "(lease expired)"}  # fmt: skip
                log.info("KG: %s offline (lease of %.1f s expired)", aid, self.node.cfg.lease_s)
            if now - counted >= 1.0:  # counted again when something changed, at most 1/s
                await self._counts()
                counted = now

    async def _status(self) -> str:
        rows = []
        for aid, d in sorted(self.info.items()):
            online = aid in self.leases or aid == self.aid
            rows.append({"id": aid, "kind": d.get("kind"), "class": d.get("class"),
                         "address": d.get("endpoint"), "pid": d.get("pid"), "online": online,
                         "state": d.get("state") if online else "offline",
                         "docked": d.get("docked"), "location": d.get("location"),
                         "pose": d.get("pose"), "possesses": d.get("possesses"),
                         "hal": d.get("hal"),
                         "last_seen_s": round(time.time() - d["seen"], 2),
                         "offline": None if online else _offline(self.gone.get(aid))})  # fmt: skip
        return json.dumps({"assets": rows})


def _offline(gone: dict[str, Any] | None) -> dict[str, Any]:
    """Why and since when an asset is offline: ``left`` (it announced its leave) or
    ``lapsed`` (its lease expired: a crash, a cut cable, a host gone)."""
    if gone is None:  # pragma: no cover - every offline asset went through leave/expire
        return {"reason": "unknown", "detail": "", "since": None, "since_s": None}
    at = gone["at"]
    return {"reason": gone["reason"], "detail": gone["detail"],
            "since": time.strftime("%Y-%m-%dT%H:%M:%S%z", time.localtime(at)),
            "since_s": round(time.time() - at, 2)}  # fmt: skip


def _state_word(state: object) -> str | None:
    """An operational state as the graph stores it (lower-case letters and '_')."""
    if not isinstance(state, str) or not state:
        return None
    word = "".join(c if c.isalpha() else "_" for c in state.lower())
    return word or None


def role_for(node: AssetNode) -> Role:
    """The role of the node's asset class."""
    cls = node.desc.asset_class
    if cls == "transport_module":
        if node.cfg.hal.kind == "remote":  # on real hardware, behind its HAL gateway
            from transfertwin.cps._role_tm_remote import RemoteModuleRole

            return RemoteModuleRole(node)
        from transfertwin.cps._role_tm import ModuleRole

        return ModuleRole(node)
    if cls == "transport_module_system":
        from transfertwin.cps._role_tms import TmsRole

        return TmsRole(node)
    if cls == "props":
        from transfertwin.cps._role_props import PropsRole

        return PropsRole(node)
    if cls == "experiment_manager":
        from transfertwin.cps._role_em import ExperimentRole

        return ExperimentRole(node)
    roles = {"transfer_unit": UnitRole, "object": ObjectRole, "knowledge_graph": GraphRole}
    return roles.get(cls, Role)(node)
