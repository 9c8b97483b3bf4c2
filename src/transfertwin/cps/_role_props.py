"""PropS in its own process (`AssetNode`): the pose graph of the floor."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any

from transfertwin._errors import InputError
from transfertwin.cps._roles import Role

if TYPE_CHECKING:
    from transfertwin.cps._node import AssetNode

__all__ = ["PropsRole"]


class PropsRole(Role):
    """PropS: fuses reported poses in its pose graph."""

    def __init__(self, node: AssetNode) -> None:
        super().__init__(node)
        from transfertwin.cps.apps import PoseGraph

        self.poses = PoseGraph()

    def handlers(self) -> dict[str, Any]:
        return {"ReportPose": self._report, "FusedPose": self._fused}

    async def _report(self, source, subject, x, y, theta, sigma_xy, sigma_theta) -> bool:
        from transfertwin.cps.apps import PoseObservation

        self.poses.add(PoseObservation(source, subject, x, y, theta, sigma_xy, sigma_theta))
        await self.set("FusedPoses", len(self.poses.solve()))
        return True

    async def _fused(self, subject: str) -> str:
        try:
            pose = self.poses.fused(subject)
        except InputError as exc:
            raise ValueError(str(exc)) from None
        return json.dumps({"x": pose.x, "y": pose.y, "theta": pose.theta})
