"""Transfer units (`UnitRole`: belt drives, light barriers, possession kept by others) and
objects (`ObjectRole`: others keep their state; they persist what is written to them).
"""

from __future__ import annotations

import asyncio
import logging
from typing import TYPE_CHECKING, Any

from transfertwin.cps.aas import Capability
from transfertwin.cps.hal import GatewayHAL, poll_gateway
from transfertwin.cps.node import Role, find_partner_ids

if TYPE_CHECKING:
    from transfertwin.cps.node import AssetNode

__all__ = ["POSE_REPORT_S", "UNIT_SIGMA_THETA_RAD", "UNIT_SIGMA_XY_M", "ObjectRole", "UnitRole"]

log = logging.getLogger("transfertwin.cps")


#: Standard deviations of a unit's surveyed floor pose (what it tells PropS).
UNIT_SIGMA_XY_M = 0.002
UNIT_SIGMA_THETA_RAD = 0.002

#: How often a unit tells PropS its pose again, s.
POSE_REPORT_S = 60.0
#: How often a unit asks the knowledge graph for a pose fuser while it lists none, s.
NO_FUSER_S = 10.0


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
        self.node.spawn(self._report_pose())
        self.node.spawn(self._watch_docked())

    async def _watch_docked(self) -> None:
        """A module that dies while docked here must not leave the belts running: while a
        module is docked, its lease at the knowledge graph is checked every half lease;
        once the graph says it is offline (lapsed or left), the unit stops its belts (its
        drive first, on a gateway) and undocks it. A graph that does not answer decides
        nothing (the belts are the docked module's to command meanwhile)."""
        period = max(0.25, self.node.cfg.lease_s / 2)
        while True:
            await asyncio.sleep(period)
            docked = await self.get("DockedTransportModule")
            if not docked or await self._online(docked) is not False:
                continue
            for belt in ("left", "right"):
                try:
                    await self._set_belt(belt, 0.0)
                except Exception as exc:  # a gateway away: said, and tried again next time
                    log.warning("%s: belt %s not stopped: %s", self.aid, belt, exc)
                    break
            else:
                await self.set("DockedTransportModule", "")
                self._written("OperationalData", "DockedTransportModule", "")
                log.warning("%s: %s went offline while docked here: belts stopped, undocked",
                            self.aid, docked)  # fmt: skip

    async def _online(self, module: str) -> bool | None:
        """Whether the knowledge graph holds `module`'s lease (None: the graph is away)."""
        assets = await self.node.graph_status()
        row = next((a for a in assets or () if a.get("id") == module), None)
        return None if row is None else bool(row.get("online"))

    async def _report_pose(self) -> None:
        """Tell the pose fusers (the assets that realise FusePoses: PropS, `find_partner_ids`)
        where this unit stands (its surveyed docking goal on the floor), and again every
        `POSE_REPORT_S` (a restarted one hears it then). While the graph lists none online,
        those the floor file says offer it are told (one still starting answers within
        seconds: tried again every 2 s, as an order may dock by then); with none at all, the
        graph is asked again every `NO_FUSER_S`."""

        floor = self.node.floor
        spec = next(s for s in floor.stations if s.unit == self.aid)
        x, y, theta = (float(v) for v in floor.shop_floor().station(spec.name).goal_pose())
        while True:
            fusers = await find_partner_ids(self.node, Capability.FUSE_POSES)
            if not fusers:  # none online yet: those the floor file says offer it (a fuser
                fusers = sorted(aid for aid, d in self.node.descriptors.items()  # starting
                                if Capability.FUSE_POSES in d.capabilities)  # fmt: skip
            delay = POSE_REPORT_S if fusers else NO_FUSER_S
            for fuser in fusers:
                try:
                    await asyncio.wait_for(self.node.peers.call(
                        fuser, "ReportPose", self.aid, self.aid, x, y, theta,
                        UNIT_SIGMA_XY_M, UNIT_SIGMA_THETA_RAD), 10.0)  # fmt: skip
                except Exception as exc:  # not (yet) answering: try again soon
                    log.debug("%s: %s not answering (%s)", self.aid, fuser, exc)
                    delay = 2.0
            await asyncio.sleep(delay)

    async def stop(self) -> None:
        if self.gateway is not None:
            await self.gateway.close()

    async def _poll_barriers(self) -> None:
        """Publish the gateway's barriers as they change (a gateway away: said once, kept
        trying; the last values stay)."""

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
        for prop, value in self.state.data.get("shown", {}).items():  # face, history, ...
            await self.set(prop, value)
        self.node.server.on_client_write(self._written)

    def _written(self, submodel: str, prop: str, value: object) -> None:
        if prop == "PossessedBy":
            self.state.data["possessed_by"] = str(value)
        else:
            self.state.data.setdefault("shown", {})[prop] = value
        self.state.save()

    async def live(self) -> dict[str, Any]:
        return {"state": "idle", "location": self.state.data["possessed_by"] or None}


