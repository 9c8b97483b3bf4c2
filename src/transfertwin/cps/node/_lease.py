"""The lease an asset holds at the knowledge graph, and how its heartbeats stay cheap as the
floor grows (docs/architecture.md "Deployment", docs/scaling.md).

As DDS liveliness and ROS 2's liveliness lease do, an asset asserts that it is alive every
``lease_s / 3`` seconds; the graph marks it offline when it hears nothing for ``lease_s``.
What a heartbeat carries scales with what changed, not with the floor:

- the *full* heartbeat (the asset's description and live state, `heartbeat_payload`) goes
  out when that payload differs from the last one the graph acknowledged, and whenever the
  graph asks for it;
- otherwise a *renewal* goes out: the asset's id and the id of this start of its process
  only (`instance_id`: random per start, so two processes of one asset on two hosts never
  share it, as two pids may). A graph that holds no lease for that instance (restarted, or
  the lease lapsed) refuses it (``BadNotFound``) and the asset sends its full heartbeat at
  once;
- the graph answers with its directory (the endpoints of the online assets) only when it
  changed since the version the asset holds: an idle floor's heartbeats carry no list.

Heartbeats are jittered (each period drawn from [0.8, 1] of ``lease_s / 3`` by a generator
seeded with the asset's id), so assets started together do not beat together forever. The
lease a floor gets by default grows with its size (`default_lease`): the graph, the one
lease holder, is sized for `HEARTBEATS_PER_S` heartbeats a second.
"""

from __future__ import annotations

import json
import random
import secrets
import zlib
from typing import Any

__all__ = [
    "DEFAULT_LEASE_S",
    "HEARTBEATS_PER_S",
    "NO_LEASE",
    "Renewal",
    "default_lease",
    "directory_reply",
    "heartbeat_period",
    "instance_id",
]

#: The lease of a small floor: an asset that dies is offline within 5 s.
DEFAULT_LEASE_S = 5.0

#: Heartbeats a second the knowledge graph is sized for by default (one asyncua server on
#: one shared core; docs/scaling.md measures it).
HEARTBEATS_PER_S = 40.0

#: The status a graph refuses a renewal with when it holds no lease for that process.
NO_LEASE = "BadNotFound"


def default_lease(assets: int) -> float:
    """The default lease of a floor of `assets` asset processes: `DEFAULT_LEASE_S` while the
    graph gets at most `HEARTBEATS_PER_S` heartbeats a second from them, longer beyond
    (whole seconds): 5 s up to 66 assets, 15 s at 200, 150 s at 2,000."""
    need = 3.0 * max(0, assets) / HEARTBEATS_PER_S
    return max(DEFAULT_LEASE_S, float(-(-need // 1)))


def instance_id() -> str:
    """A new id for one start of an asset's process: 16 random hex digits (a pid is unique
    on one host only; a floor spans hosts)."""
    return secrets.token_hex(8)


def heartbeat_period(lease_s: float) -> float:
    """Seconds between heartbeats: a third of the lease (two may be lost before it lapses)."""
    return lease_s / 3.0


class Renewal:
    """An asset's side of its lease: what the next heartbeat carries, and what the graph's
    answer teaches it.

    Args:
        asset_id: The asset.
        instance: This start of its process (`instance_id`; a renewal names it: a restarted
            process holds no lease yet).
    """

    def __init__(self, asset_id: str, instance: str) -> None:
        self.asset_id = asset_id
        self.instance = instance
        self.delivered: str | None = None  # the last full payload the graph acknowledged
        self.directory = ""  # version of the graph's directory this asset holds
        self.full_sent = 0
        self.renewals_sent = 0
        self._rng = random.Random(zlib.crc32(asset_id.encode()))
        self._sent: str | None = None

    def request(self, payload: str) -> str:
        """The heartbeat to send now for the asset's current full `payload`."""
        if payload == self.delivered:
            self._sent = None
            self.renewals_sent += 1
            return json.dumps({"id": self.asset_id, "instance": self.instance, "renew": True,
                               "directory": self.directory})  # fmt: skip
        self._sent = payload
        self.full_sent += 1
        d = json.loads(payload)
        d["directory"] = self.directory
        return json.dumps(d)

    def answered(self, reply: str) -> dict[str, str] | None:
        """Take the graph's answer; returns the directory (asset id -> endpoint) when the
        graph sent one (it changed since the version held here), else None."""
        if self._sent is not None:
            self.delivered = self._sent
        doc = json.loads(reply)
        endpoints = doc.get("endpoints")
        if endpoints is not None:
            self.directory = str(doc.get("directory", ""))
        return endpoints

    def refused(self) -> None:
        """The graph holds no lease for this instance: the next heartbeat is the full one."""
        self.delivered = None

    def pause(self, period_s: float) -> float:
        """Seconds until the next heartbeat: `period_s` shortened by a jitter of up to 20 %
        (never longer, so two may still be lost before the lease lapses)."""
        return period_s * (0.8 + 0.2 * self._rng.random())


def directory_reply(version: str, endpoints: dict[str, str], held: str | None) -> str:
    """The graph's answer to a heartbeat: its directory's version, and the directory itself
    only when the sender holds another version (`held`)."""
    doc: dict[str, Any] = {"directory": version}
    if held != version:
        doc["endpoints"] = endpoints
    return json.dumps(doc)
