"""PropS in its own process (`AssetNode`): the floor's pose graph (Sec. 5.2; docs/
architecture.md, "PropS in the loop").

Nodes are the floor's transfer units (the frame of a unit is its station's docking goal
F_DG) and transport modules. PropS holds the *current* estimates, not a trajectory: one
observation per (source, subject, frame), a newer one in place of the older. What it is
told:

* a unit's fixed pose in the world, surveyed: the floor file's station pose (loaded at
  start, as the unit would report it; `ReportPose` replaces it);
* a module's own estimate of its world pose (localisation against the map, laser) with its
  standard deviations (`ReportPose` with source = subject). A module that reports a new
  pose of itself has moved: the observations of it relative to other nodes are dropped;
* a camera's observation of a module relative to a unit: the ChArUco board on the module
  seen by the unit's camera, i.e. the docking error (`ReportRelativePose`).

`DockingError(module, unit)` answers the fused pose of the module in the unit's goal frame
with its covariance; every subject's fused pose and standard deviations are in the
``FusedPosesJson`` variable, the last docking error per module in ``DockingErrorsJson``.
"""

from __future__ import annotations

import json
import math
from typing import TYPE_CHECKING, Any

from transfertwin._errors import InputError
from transfertwin.cps.apps import PoseGraph, PoseObservation
from transfertwin.cps.node import Role
from transfertwin.cps.roles._unit import UNIT_SIGMA_THETA_RAD, UNIT_SIGMA_XY_M

if TYPE_CHECKING:
    from transfertwin.cps.node import AssetNode

__all__ = ["PropsRole"]


def _sd(cov) -> list[float]:
    return [math.sqrt(max(float(cov[i, i]), 0.0)) for i in range(3)]


class PropsRole(Role):
    """PropS: fuses reported poses in its pose graph."""

    def __init__(self, node: AssetNode) -> None:
        super().__init__(node)

        self.poses = PoseGraph()
        self.docking: dict[str, dict[str, Any]] = {}  # module -> its last docking error
        self.reported: set[str] = set()  # nodes that told their own pose over OPC UA

    def handlers(self) -> dict[str, Any]:
        return {"ReportPose": self._report, "ReportRelativePose": self._report_relative,
                "FusedPose": self._fused, "DockingError": self._docking_error}  # fmt: skip

    async def start(self) -> None:

        floor = self.node.floor
        shop = floor.shop_floor()
        for spec in floor.stations:
            unit = spec.unit
            x, y, theta = (float(v) for v in shop.station(spec.name).goal_pose())
            self.poses.put(PoseObservation(unit, unit, x, y, theta, UNIT_SIGMA_XY_M,
                                           UNIT_SIGMA_THETA_RAD))  # fmt: skip
        await self._publish()

    async def _report(self, source, subject, x, y, theta, sigma_xy, sigma_theta) -> bool:

        obs = PoseObservation(source, subject, x, y, theta, sigma_xy, sigma_theta)
        if source == subject:  # it moved: what others saw of it is stale
            self.reported.add(subject)
            self.poses.drop(lambda o: o.subject == subject and o.relative_to is not None)
        self.poses.put(obs)
        await self._publish()
        return True

    async def _report_relative(self, source, subject, relative_to, x, y, theta, sigma_xy,
                               sigma_theta) -> bool:  # fmt: skip

        self.poses.put(PoseObservation(source, subject, x, y, theta, sigma_xy, sigma_theta,
                                       relative_to=relative_to))  # fmt: skip
        await self._publish()
        return True

    async def _fused(self, subject: str) -> str:
        try:
            pose = self.poses.fused(subject)
            sd = _sd(self.poses.covariance(subject))
        except InputError as exc:
            raise ValueError(str(exc)) from None
        return json.dumps({"x": pose.x, "y": pose.y, "theta": pose.theta,
                           "sd_x": sd[0], "sd_y": sd[1], "sd_theta": sd[2],
                           "reported": subject in self.reported})  # fmt: skip

    async def _docking_error(self, module: str, unit: str) -> str:
        """The fused pose of `module` in `unit`'s goal frame (its docking error)."""
        try:
            rel, cov = self.poses.solution().relative(unit, module)
        except InputError as exc:
            raise ValueError(str(exc)) from None
        sources = sorted({o.source for o in self.poses.observations
                          if module in (o.subject, o.relative_to)})  # fmt: skip
        sd = _sd(cov)
        est = {"unit": unit, "x_m": rel.x, "y_m": rel.y, "theta_rad": rel.theta,
               "sd_x_m": sd[0], "sd_y_m": sd[1], "sd_theta_rad": sd[2],
               "cov": [[float(v) for v in row] for row in cov], "sources": sources}  # fmt: skip
        self.docking[module] = est
        await self._publish()
        return json.dumps(est)

    async def _publish(self) -> None:
        if not self.poses.observations:
            return
        try:
            sol = self.poses.solution()
        except InputError:  # a node not linked to the world yet
            return
        fused = {}
        for node, pose in sorted(sol.poses.items()):
            sd = _sd(sol.covariances[node])
            fused[node] = {"x": round(pose.x, 6), "y": round(pose.y, 6),
                           "theta": round(pose.theta, 6), "sd_x": sd[0], "sd_y": sd[1],
                           "sd_theta": sd[2], "reported": node in self.reported}  # fmt: skip
        await self.set("FusedPoses", len(fused))
        await self.set("FusedPosesJson", json.dumps(fused))
        await self.set("DockingErrorsJson", json.dumps(self.docking))
