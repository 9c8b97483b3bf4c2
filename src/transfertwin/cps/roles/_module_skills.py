"""The transport module's skills (`TransportSkills`, Fig. 5.9a) on its own simulation:
navigate or be put at the station, dock, form the OTS (from the simulation's true box or
the depth camera's scan) and transfer, each through the module's public side
(`transfertwin.cps.node.ModuleHost`, which `ModuleRole` implements); with the hand-over
policy (`HandOverRetries`) on top (`ModuleSkills`).
"""

from __future__ import annotations

import asyncio
import logging

from transfertwin.cps.apps import (
    DEFAULT_STATE,
    HandOverRetries,
    Leg,
    StepResult,
    form_ots,
    height_key,
    scan_check,
    transfer_step,
)
from transfertwin.cps.node import ModuleHost
from transfertwin.ots import POSITIONS, BeltThresholds, TransferDirection
from transfertwin.perception import (
    AABB,
    CameraIntrinsics,
    DepthCamera,
    Workspace,
    ground_truth_aabb,
    workspace_scan,
)
from transfertwin.sim import DockingError
from transfertwin.study.experiment import experiment_seeds

__all__ = ["SCAN_SIZE", "ModuleSkills", "VirtualTransport"]

log = logging.getLogger("transfertwin.cps")


#: Depth image size of the workspace scan when forming the OTS (the perception benchmarks'
#: size: enough for a core's box within a centimetre or two, ~0.5 s per scan).
SCAN_SIZE = (160, 120)


def _load_args(state: dict[str, object] | None) -> tuple[str, float, float]:
    """(face, θ deg, lateral offset m) that put an object on a unit's belts so that it
    crosses onto the module in `state`: the conveyor's lateral position of the study's
    states (Eq. 6.3), the unit's belts being in line with the module's."""
    state = state or DEFAULT_STATE
    return (str(state["face"]), float(state["theta_deg"]),
            float(POSITIONS[str(state["conveyor"])][1]))  # fmt: skip


class VirtualTransport:
    """The virtual transport module's skills (`TransportSkills`), one try each.

    With ``docking = "navigated"`` the module drives on the shop floor
    (`FloorRobot`), docks with the error that emerges there and forms the OTS from its
    depth camera's workspace scan; with 'sampled' it is put at the station with an error
    drawn from the fitted generator and forms the OTS from the simulation's true box.
    """

    #: The pre-transfer state the object is loaded in at the source ({face, conveyor,
    #: theta_deg}; None: `DEFAULT_STATE`).
    load_state: dict[str, object] | None = None
    #: The module's depth camera forms the OTS and checks the ledger (floor: sensor =
    #: "camera"); the face the object lies on, for that check.
    camera: bool = False
    face: str = "front"
    #: Heights the camera has learnt ('o10/front' -> m; `cps.apps._camera`), None: none kept.
    heights: dict[str, float] | None = None

    def __init__(self, host: ModuleHost, source: str, target: str, obj: str):
        self.host, self.tm, self.obj = host, host.aid, obj
        self.source, self.target = source, target
        self.robot = host.robot
        self.navigated = host.docking == "navigated"

    def _seed(self, leg: Leg) -> int:
        seed, _ = experiment_seeds(self.host.seed, f"{self.obj}:{self.source}:{self.target}",
                                   leg.index, 0)  # fmt: skip
        return seed

    def _station(self, leg: Leg) -> str:
        return self.host.station_of(leg.unit)

    async def navigate(self, leg: Leg) -> StepResult:
        station = self._station(leg)
        if not self.navigated:
            return StepResult(True, info={"station": station})
        res = await asyncio.to_thread(self.robot.navigate, station, self._seed(leg))
        await self.host.publish_pose()
        info = {"station": station, "path_m": round(res.path_m, 3),
                "drive_s": round(res.drive_s, 2)}  # fmt: skip
        return StepResult(res.status == "ok", res.reason, info)

    async def dock(self, leg: Leg) -> StepResult:
        host, station = self.host, self._station(leg)
        if self.navigated:
            res = await asyncio.to_thread(self.robot.dock, station)
        else:
            err = host.docking_error(self.source, self.target, self.obj, leg.index)
            res = self.robot.teleport_dock(station, err)
        await host.publish_pose()
        info = {k: v for k, v in res.as_dict().items() if k not in ("path_m", "reason")}
        if res.status != "ok":
            return StepResult(False, f"docking at {leg.unit}: {res.reason}", info)
        err, env = res.docking_error(), host.env
        err, props = await host.docking_estimate(leg.unit, err, self._seed(leg))
        if props is not None:
            info["props"] = props
        if leg.name == "pick-up":  # the object lies on the source unit's belts
            await asyncio.to_thread(host.locked, env.load_object_at_unit, self.obj, leg.unit,
                                    err, *_load_args(self.load_state))  # fmt: skip
        else:
            await asyncio.to_thread(host.locked, env.dock, leg.unit, err)
        await host.dock(leg.unit)
        log.info("%s: docked at %s, docking error %s", self.tm, leg.unit,
                 tuple(round(v, 2) for v in err.as_mm_deg()))  # fmt: skip
        return StepResult(True, info=info)

    def _scan(self, seed: int) -> list[AABB]:
        scene, system = self.host.env.scene, self.host.env.system
        workspace = Workspace.for_layout(scene.layout, scene.gap_m, docked=True)
        size = CameraIntrinsics(*SCAN_SIZE)
        with DepthCamera(system.model, system.data, intrinsics=size) as camera:
            detection, _ = workspace_scan(camera, workspace, seed=seed)
        return list(detection.boxes)

    async def form_ots(self, leg: Leg) -> StepResult:
        host = self.host
        scene = host.env.scene
        seeing = self.navigated or self.camera
        if seeing:
            boxes = await asyncio.to_thread(host.locked, self._scan, self._seed(leg))
        else:
            boxes = [host.locked(ground_truth_aabb, host.env.system)]
        info = {"source": "depth camera" if seeing else "ground truth",
                "boxes": [b.as_dict() for b in boxes]}  # fmt: skip
        if self.camera:  # what it sees against what the ledger says (Sec. 5.5)
            verdict = scan_check(
                boxes, self.obj, self.face, self.tm, leg.unit,
                leg.direction is TransferDirection.TU_TO_TM, scene.gap_m,
                self.heights)  # fmt: skip
            info["possessions"] = verdict.summary
            if not verdict.ok:
                log.info("%s: scanned %s and itself: %s", self.tm, leg.unit, verdict.why)
                return StepResult(False, verdict.why, info)
            if verdict.height_m is not None and self.heights is not None:
                self.heights[height_key(self.obj, self.face)] = round(verdict.height_m, 4)
                log.info("%s: learnt %s", self.tm, verdict.summary["learnt"][0])
        # The transport module carries objects only on its belts; a unit's representation
        # also lists what its station holds off the belts, so for a unit the scan decides.
        pickup = leg.direction is TransferDirection.TU_TO_TM
        holds = host.carried() if pickup else []
        check = form_ots(
            boxes, leg.direction, BeltThresholds(t_max=scene.t_max_s),
            obj=self.obj, tm=self.tm, unit=leg.unit, receiver_holds=holds,
        )  # fmt: skip
        log.info("%s: scanned %s and itself: %d object(s) seen%s", self.tm, leg.unit,
                 len(boxes), "" if check.ok else f"; no OTS: {check.reason}")  # fmt: skip
        return StepResult(check.ok, check.reason, info)

    async def transfer(self, leg: Leg) -> StepResult:
        rec = await self.host.transfer(leg.unit, leg.direction)
        if leg.name == "pick-up":
            log.info("%s: took %s from %s: y = %d", self.tm, self.obj, leg.unit, rec.y)
        else:
            log.info("%s: handed %s to %s: y = %d", self.tm, self.obj, leg.unit, rec.y)
        return transfer_step(rec)

    async def resolve(self, leg: Leg, success: bool) -> None:
        host = self.host
        if success:
            await host.moved(self.obj, self.tm if leg.name == "pick-up" else leg.unit)
        await host.undock()
        with host.env.lock:
            host.env.undock()


class ModuleSkills(HandOverRetries, VirtualTransport):
    """The skills of `VirtualTransport` with the hand-over policy (`HandOverRetries`: a
    failed transfer taken back and tried again); a module that restarted with an object
    on board puts it back on its belts in the simulation before docking to deliver it."""

    def _seed(self, leg: Leg) -> int:
        return super()._seed(leg) + 7919 * self.attempt

    async def dock(self, leg: Leg) -> StepResult:
        env = self.host.env
        if leg.name != "pick-up" and env.object_ref != self.obj:
            await asyncio.to_thread(self.host.locked, _load_on_module, env, self.obj)
        return await super().dock(leg)


def _load_on_module(env, obj: str) -> None:
    """Put `obj` on the module's belts in the simulation (after a restart of the module)."""
    system = env.use(obj)
    system.reset(DockingError(0.0, 0.0, 0.0))
    system.place("front", 0.0, -0.2, 0.0)
    system.clock.wait(env.scene.placement.settle_time_s)
    env.docked_unit = None
