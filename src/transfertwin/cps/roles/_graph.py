"""The knowledge graph's asset (`GraphRole`): it holds the graph (`KnowledgeGraph`), answers
SPARQL queries, keeps every asset's lease from its heartbeats and publishes the floor's
directory of endpoints.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import time
from typing import TYPE_CHECKING, Any

from transfertwin._errors import InputError
from transfertwin.cps.aas import AssetDescriptor, AssetKind, Capability, PhysicalType
from transfertwin.cps.node import NO_LEASE, Role, directory_reply
from transfertwin.cps.opcua import OperationRefused, current_caller

if TYPE_CHECKING:
    from transfertwin.cps.node import AssetNode

__all__ = ["GraphRole"]

log = logging.getLogger("transfertwin.cps")


class GraphRole(Role):
    """The knowledge graph: the semantic layer, kept current by the other assets' leases.

    Its content is soft state: a heartbeat carries the sender's whole description when it
    changed, a renewal otherwise, and the graph refuses the renewal of a lease it does not
    hold (`_lease.NO_LEASE`), upon which the asset sends its description; so a restarted
    graph is complete again one heartbeat period after it comes back. Its directory (the
    online assets' endpoints) has a version that changes with every join, leave and move;
    a heartbeat gets the directory only when the sender holds another version.

    On a secure floor an asset speaks only for itself (`_speaks_for`): a heartbeat comes
    from the asset it names, authenticated by its certificate (an X.509 identity naming
    ``urn:transfertwin:<id>``), and a peer announces no leave but its own.
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
        from transfertwin.cps.kg import KnowledgeGraph  # rdflib: only the graph's process

        srv = self.node.server
        self.kg = KnowledgeGraph(self.aid, endpoint=srv.endpoint,
                                 security_policy=srv.security_policy)  # fmt: skip
        self.node.spawn(self._expire())

    async def beat_self(self) -> None:
        """The graph's own lease (it is an asset like any other)."""
        srv = self.node.server
        self.info[self.aid] = {"id": self.aid, "kind": "logical", "class": "knowledge_graph",
                               "endpoint": srv.endpoint, "pid": os.getpid(),
                               "instance": self.node.instance, "state": "idle",
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

    def _speaks_for(self, aid: str, *, people: bool) -> None:
        """OperationRefused (BadUserAccessDenied) unless the caller may speak for `aid`: on
        a secure server, a peer asset only for itself, a person (operator) only if
        `people`; on an insecure one (explicit opt-in), anyone."""
        caller = current_caller()
        if caller is None or not caller.secure:
            return
        if caller.asset_id == aid or (people and caller.asset_id is None):
            return
        who = caller.asset_id or f"a {caller.role or 'session'} without an asset identity"
        log.warning("KG: refused %s speaking for %s", who, aid)
        raise OperationRefused(f"{who} may not speak for {aid}: an asset heartbeats and "
                               "leaves in its own name, with its own certificate",
                               status="BadUserAccessDenied")  # fmt: skip

    async def _heartbeat(self, payload: str) -> str:
        d = json.loads(payload)
        aid = d["id"]
        self._speaks_for(aid, people=False)
        held = d.pop("directory", None)
        # a lease is held by one start of the asset's process (its random instance id: pids
        # repeat across hosts, and a process of the asset restarted elsewhere is a new one)
        instance = d.get("instance")
        fresh = aid not in self.leases or self.info.get(aid, {}).get("instance") != instance
        if d.get("renew"):
            if fresh:
                self.beats["refused"] += 1
                raise OperationRefused(f"no lease of {aid} (instance {instance}) held here: "
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
                constraints=tuple((Capability(c), str(n), v)
                                  for c, n, v in d.get("constraints", ())),
            )  # fmt: skip
            self.kg.join(desc, endpoint=d["endpoint"], security_policy=d["security_policy"],
                         state=_state_word(d.get("state")))  # fmt: skip
            log.info("KG: %s joined (instance %s, pid %s, %s)", aid, instance, d.get("pid"),
                     d["endpoint"])  # fmt: skip
        self._apply(aid, d)
        self._changed = True
        return self._reply(held)

    def _apply(self, aid: str, d: dict[str, Any]) -> None:
        """The live part of a heartbeat into the graph (each fact on its own: one that does
        not fit yet, e.g. a location on an asset not joined, waits for the next beat)."""
        kg = self.kg
        updates = [lambda: kg.set_state(aid, _state_word(d.get("state")) or "idle")]
        if "transport" in d.get("capabilities", ()):  # a module, whatever its class
            docked = d.get("docked")
            updates.append(lambda: kg.set_docked(aid, docked if docked in self.leases else None))
        if "possesses" in d:
            updates.append(lambda: kg.set_possesses(aid, d["possesses"]))
        if d.get("location") in self.leases:  # an object (only objects report one)
            updates.append(lambda: kg.set_location(aid, d["location"]))
        for update in updates:
            try:
                update()
            except InputError as exc:
                log.debug("KG: %s: %s", aid, exc)

    async def _leave(self, aid: str) -> bool:
        self._speaks_for(aid, people=True)
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
                         "role_class": d.get("role_class", d.get("class")),
                         "address": d.get("endpoint"), "pid": d.get("pid"),
                         "instance": d.get("instance"), "online": online,
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
