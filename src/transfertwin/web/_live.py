"""The live transfer view: a virtual experiment E^V the console runs itself, drawn top-down.

The pose comes from a real MuJoCo simulation in the console's process (the same
`run_experiment` a study runs, in a worker thread), paced to the wall clock: `speed`
simulated seconds per wall second. After every controller sample the object's footprint
(the convex hull of its hull vertices projected onto the belt plane), its heading, the
possessing unit, both units' light barriers and belt speeds are published as a frame;
`scene_outline` gives the belts, barriers and gap in the tip frame F_T (m), with the TU
where the docking error puts it. The page polls the frames over server-sent events.

Why not the CPS's transfers: the CPS's virtual environment publishes belt speeds and light
barriers over OPC UA but not the object's pose, and runs as fast as it can by default
(``--time-scale 0``); drawing its transfers would need a pose variable in its AAS. A transfer
started here is a real E^V with the same physics and controller, self-contained.
"""

from __future__ import annotations

import contextlib
import logging
import math
import threading
import time
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from transfertwin._errors import InputError
from transfertwin.objects import is_builtin_id, load_object
from transfertwin.ots import check_theta_deg, parse_conveyor, parse_face
from transfertwin.sim import DockingError, LayoutConfig, SceneConfig, VirtualTransferSystem
from transfertwin.study.experiment import ExperimentSpec, run_experiment, system_for

__all__ = ["LiveTransfer", "TransferBusyError", "TransferRequest", "footprint", "scene_outline"]

log = logging.getLogger("transfertwin.web")
audit = logging.getLogger("transfertwin.web.audit")

_FIELDS = {"object", "face", "conveyor", "theta_deg", "seed", "speed", "dock_error", "token"}
#: Bounds of a docking error the console accepts (x, y in mm; θ in degrees).
_DOCK_LIMITS = (50.0, 50.0, 10.0)


class TransferBusyError(RuntimeError):
    """A transfer is already running (one at a time)."""


class _Cancelled(BaseException):  # a BaseException: passes run_experiment's `except Exception`
    """Raised in the simulation thread when the console stops."""


def _number(name: str, value: object, lo: float, hi: float) -> float:
    ok = isinstance(value, int | float | str) and not isinstance(value, bool)
    try:
        x = float(value) if ok else math.nan
    except ValueError:
        x = math.nan
    if not (math.isfinite(x) and lo <= x <= hi):
        raise InputError(f"{name} must be a number in {lo:g}..{hi:.10g}, got {value!r:.40}")
    return x


@dataclass(frozen=True)
class TransferRequest:
    """A transfer to simulate: a built-in core in a pre-transfer state (Eq. 6.7–6.10).

    Attributes:
        object_ref: Built-in core id 'o1'..'o37' (no file paths from a browser).
        face, conveyor, theta_deg: The pre-transfer state.
        seed: Seed of the placement perturbation.
        speed: Simulated seconds per wall second (0.1..4).
        dock_error: Docking error (x mm, y mm, θ deg) of the TU.
    """

    object_ref: str
    face: str
    conveyor: str
    theta_deg: int
    seed: int = 0
    speed: float = 1.0
    dock_error: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @classmethod
    def parse(cls, body: dict[str, Any]) -> TransferRequest:
        """The request in a JSON/form body; InputError with the reason if it is bad."""
        unknown = sorted(set(body) - _FIELDS)
        if unknown:
            raise InputError(f"unknown field(s): {', '.join(unknown)[:80]}")
        obj = body.get("object")
        if not is_builtin_id(obj):
            raise InputError(f"object must be a built-in core o1..o37, got {obj!r:.40}")
        seed = _number("seed", body.get("seed", 0), 0, 2**31 - 1)
        if seed != int(seed):
            raise InputError(f"seed must be an integer, got {body.get('seed')!r:.40}")
        err = body.get("dock_error", [0, 0, 0])
        if isinstance(err, str):
            err = [p for p in err.replace(";", ",").split(",") if p.strip()] or [0, 0, 0]
        if not isinstance(err, list | tuple) or len(err) != 3:
            raise InputError("dock_error must be three numbers: x mm, y mm, θ deg")
        dock = tuple(_number(f"dock_error[{i}]", v, -lim, lim)
                     for i, (v, lim) in enumerate(zip(err, _DOCK_LIMITS, strict=True)))  # fmt: skip
        return cls(obj, parse_face(body.get("face", "front")),
                   parse_conveyor(body.get("conveyor", "both")),
                   check_theta_deg(body.get("theta_deg", 0)), int(seed),
                   _number("speed", body.get("speed", 1.0), 0.1, 4.0), dock)  # fmt: skip

    def spec(self, scene: SceneConfig) -> ExperimentSpec:
        """The experiment E^V of this request."""
        x, y, th = self.dock_error
        return ExperimentSpec(self.object_ref, self.face, self.conveyor, self.theta_deg,
                              docking_error=DockingError(x / 1000, y / 1000, math.radians(th)),
                              scene=scene, seed=self.seed)  # fmt: skip


def _rect(x0: float, x1: float, y0: float, y1: float, pose=(0.0, 0.0, 0.0)) -> list[list[float]]:
    tx, ty, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    return [[round(tx + c * x - s * y, 5), round(ty + s * x + c * y, 5)]
            for x, y in ((x0, y0), (x1, y0), (x1, y1), (x0, y1))]  # fmt: skip


def scene_outline(layout: LayoutConfig, tu_pose: tuple[float, float, float]) -> dict[str, Any]:
    """Belts, light barriers and gap of TM and TU, top-down in F_T (m; pure).

    Args:
        layout: The units' geometry.
        tu_pose: The TU frame's (x m, y m, yaw rad) in F_T (docking error applied).

    Returns:
        ``{"belts": [{unit, belt, polygon}], "barriers": [{unit, which, segment}],
        "gap": polygon}``; polygons are lists of [x, y], a segment two points.
    """
    half_sep, w = 0.5 * layout.belt_separation_m, layout.belt_width_m
    span = {"tm": (-layout.tm_length_m, 0.0), "tu": (0.0, layout.tu_length_m)}
    pose = {"tm": (0.0, 0.0, 0.0), "tu": tu_pose}
    belts, barriers = [], []
    for unit, (x0, x1) in span.items():
        for belt, (y0, y1) in (("left", (half_sep, half_sep + w)),
                               ("right", (-half_sep - w, -half_sep))):  # fmt: skip
            belts.append({"unit": unit, "belt": belt, "polygon": _rect(x0, x1, y0, y1, pose[unit])})
        inset = layout.barrier_inset_m
        near, far = (x1 - inset, x0 + inset) if unit == "tm" else (x0 + inset, x1 - inset)
        for which, x in (("near", near), ("far", far)):
            seg = _rect(x, x, -half_sep - w, half_sep + w, pose[unit])
            barriers.append({"unit": unit, "which": which, "segment": [seg[0], seg[2]]})
    tu_end = _rect(0.0, 0.0, -half_sep - w, half_sep + w, tu_pose)
    gap = [[0.0, -half_sep - w], tu_end[0], tu_end[2], [0.0, half_sep + w]]
    return {"belts": belts, "barriers": barriers, "gap": gap}


def _hull_vertices(hulls: tuple[np.ndarray, ...]) -> np.ndarray:
    """The vertices (k, 3) of the convex hull of all of an object's hull vertices."""
    pts = np.concatenate([np.asarray(h, dtype=float) for h in hulls], axis=0)
    try:
        return pts[ConvexHull(pts).vertices]
    except QhullError:  # degenerate (flat) point set: keep them all
        return pts


def footprint(vertices: np.ndarray, pos: np.ndarray, rot: np.ndarray) -> list[list[float]]:
    """The object's outline on the belt plane: convex hull of its vertices (k, 3) in F_O
    moved by body position `pos` (3,) and rotation `rot` (3, 3), projected on xy (pure)."""
    xy = (vertices @ np.asarray(rot).T + np.asarray(pos))[:, :2]
    try:
        ring = xy[ConvexHull(xy).vertices]
    except QhullError:
        ring = xy
    return [[round(float(x), 5), round(float(y), 5)] for x, y in ring]


def _phase(tm: dict[str, float], tu: dict[str, float]) -> str:
    speeds = [*tm.values(), *tu.values()]
    if not any(speeds):
        return "belts stopped"
    return "TM → TU" if sum(speeds) > 0 else "TU → TM"


class LiveTransfer:
    """One simulated transfer at a time, its latest frame and its outcome (thread-safe)."""

    def __init__(self, scene: SceneConfig | None = None) -> None:
        self.scene = scene or SceneConfig()
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._cancel = threading.Event()
        self._ids = 0
        self.run: dict[str, Any] | None = None
        self.frame: dict[str, Any] | None = None
        self.geometry: dict[str, Any] | None = None
        self.seq = 0

    def snapshot(self) -> dict[str, Any]:
        """The current run, its geometry and latest frame (what the page draws)."""
        with self._lock:
            return {"seq": self.seq, "run": dict(self.run) if self.run else None,
                    "geometry": self.geometry, "frame": self.frame}  # fmt: skip

    def start(self, req: TransferRequest, client: str) -> dict[str, Any]:
        """Start simulating `req` in the background; TransferBusyError if one is running."""
        with self._lock:
            if self._thread is not None and self._thread.is_alive():
                raise TransferBusyError(f"transfer {self.run['id']} is still running")
            self._ids += 1
            self.run = {"id": f"t{self._ids}", "object": req.object_ref, "face": req.face,
                        "conveyor": req.conveyor, "theta_deg": req.theta_deg,
                        "seed": req.seed, "speed": req.speed, "dock_error": list(req.dock_error),
                        "state": "running", "outcome": None,
                        "started_utc": datetime.now(UTC).isoformat(timespec="seconds")}  # fmt: skip
            self.frame, self.geometry = None, None
            self.seq += 1
            run = dict(self.run)
            self._cancel.clear()
            self._thread = threading.Thread(target=self._simulate, args=(req,), daemon=True,
                                            name=f"tt-live-{run['id']}")  # fmt: skip
            self._thread.start()
        audit.info("transfer %s: %s %s/%s/%d° seed %d from %s", run["id"], req.object_ref,
                   req.face, req.conveyor, req.theta_deg, req.seed, client)  # fmt: skip
        return run

    def stop(self, timeout_s: float = 10.0) -> None:
        """Cancel a running transfer and wait for its thread."""
        self._cancel.set()
        thread = self._thread
        if thread is not None:
            thread.join(timeout_s)

    def _simulate(self, req: TransferRequest) -> None:
        spec = req.spec(self.scene)
        try:
            system = system_for(req.object_ref, "m", self.scene)
            vertices = _hull_vertices(load_object(req.object_ref).hulls)
        except Exception as exc:  # a core that cannot be built: the run's outcome
            self._finish("error", {"status": "error", "message": f"{type(exc).__name__}"})
            return
        wall0 = time.monotonic()
        listener = self._listener(system, vertices, req.speed, wall0)
        system.step_listeners.append(listener)
        try:
            result = run_experiment(spec, system=system)
        except _Cancelled:
            self._finish("cancelled", None)
            return
        finally:
            system.step_listeners.remove(listener)
        with contextlib.suppress(_Cancelled):
            listener()  # the final pose
        outcome = {k: getattr(result, k) for k in ("status", "y1", "y2", "success", "message")}
        outcome["t_end_s"] = result.t_end_s if math.isfinite(result.t_end_s) else None
        self._finish("finished", outcome)
        audit.info("transfer %s finished: %s success=%s", self.run["id"], result.status,
                   result.success)  # fmt: skip

    def _finish(self, state: str, outcome: dict[str, Any] | None) -> None:
        with self._lock:
            if self.run is not None:
                self.run.update(state=state, outcome=outcome)
            self.seq += 1

    def _listener(self, system: VirtualTransferSystem, vertices: np.ndarray, speed: float,
                  wall0: float):  # fmt: skip
        layout = self.scene.layout
        last_pose: list[tuple[float, float, float] | None] = [None]

        def on_step() -> None:
            if self._cancel.is_set():
                raise _Cancelled
            pos, rot = system.object_pose()
            tm = {b: system.tm.belt_speed(b) for b in ("left", "right")}
            tu = {b: system.tu.belt_speed(b) for b in ("left", "right")}
            state = system.observe()
            frame = {
                "t_s": round(float(system.data.time), 4),
                "polygon": footprint(vertices, pos, rot),
                "centre": [round(float(state[1]), 5), round(float(state[2]), 5)],
                "theta_deg": round(math.degrees(float(state[7])), 2),
                "possessed_by": "TU" if state[0] >= 0.5 else "TM",
                "barriers": {"tm": system.tm.barriers(), "tu": system.tu.barriers()},
                "belts": {"tm": tm, "tu": tu}, "phase": _phase(tm, tu),
            }  # fmt: skip
            geometry = None
            if system.tu_pose != last_pose[0]:
                last_pose[0] = system.tu_pose
                geometry = scene_outline(layout, system.tu_pose)
            with self._lock:
                self.frame = frame
                if geometry is not None:
                    self.geometry = geometry
                self.seq += 1
            # keep pace: simulated time / speed should equal the wall time since the start
            ahead = float(system.data.time) / speed - (time.monotonic() - wall0)
            if ahead > 0 and self._cancel.wait(ahead):
                raise _Cancelled

        return on_step
