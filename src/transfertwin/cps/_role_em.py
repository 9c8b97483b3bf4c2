"""The Experiment Manager in its own process (`AssetNode`)."""

from __future__ import annotations

import asyncio
import json
from typing import Any

from transfertwin.cps._roles import Role

__all__ = ["ExperimentRole"]


class ExperimentRole(Role):
    """The Experiment Manager: runs E^V against a unit through that unit's OPC UA interface;
    the virtual unit's physics runs here and mirrors its belt commands (`MirroredUnitHAL`)."""

    def handlers(self) -> dict[str, Any]:
        return {"RunExperiment": self._run}

    async def _run(self, unit: str, obj: str, face: str, conveyor: str, theta_deg: int,
                   seed: int) -> str:  # fmt: skip
        from transfertwin.cps._role_tm import MirroredUnitHAL, load_scene
        from transfertwin.cps.opcua import OpcUaUnitHAL
        from transfertwin.study.experiment import ExperimentSpec, run_experiment, system_for

        if unit not in self.node.floor.units:
            raise ValueError(f"no transfer unit {unit!r}")
        scene = load_scene()
        spec = ExperimentSpec(obj, face, conveyor, int(theta_deg), scene=scene, seed=int(seed))
        await self.set("State", "running")
        try:
            session = await self.node.peers.session(unit)
            loop = asyncio.get_running_loop()
            system = system_for(obj, "m", scene)
            hal = MirroredUnitHAL(OpcUaUnitHAL(session, loop, timeout_s=30), system.tu, loop)
            result = await asyncio.to_thread(run_experiment, spec, tu_hal=hal)
        finally:
            await self.set("State", "idle")
        await self.set("ExperimentsDone", int(await self.get("ExperimentsDone")) + 1)
        return json.dumps(result.row())
