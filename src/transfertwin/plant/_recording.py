"""What a plant experiment E^P looks like from outside: a camera's and a controller's record.

A real plant's experiment is replayed from what was recorded of it: a camera (or motion
capture) over the units saw the object's pose, the light barriers switched, the controller
commanded the belts and started its clock, and the log has the outcome. `PlantRecording` is
that record of one `EmulatedPlant` experiment and nothing more: the object's pose at the
camera's resolution (1 mm, 10⁻³ of a quaternion component, 1 ms), the four barriers, the
commanded (not the actual) belt speeds, the controller's clock starts, and the plant's
logged row. It holds no hidden parameter: not the object's features, mass or centre of
mass, not the plant's friction, gap, belt-speed error, TU height step or pitch, placement
noise or outcome-flip probability. What the motion shows of them is what a video of a real
plant shows (the object's speed on a belt is that belt's actual speed).

`_CameraTrack` records it: `EmulatedPlant.observe` runs the experiment again in freshly
compiled plant systems whose clock (`SimClock`, so the physics is the same, bit for bit) notes
a sample after every controller wait; the attempt that made the row is the one kept.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from transfertwin.sim import TrackingClock, VirtualTransferSystem

__all__ = ["CAMERA_RESOLUTION", "PlantRecording"]

#: The camera's resolution: position (m), quaternion component, time (s).
CAMERA_RESOLUTION = {"position_m": 1e-3, "quaternion": 1e-3, "time_s": 1e-3}


@dataclass(frozen=True)
class PlantRecording:
    """One plant experiment as recorded (see the module doc).

    Attributes:
        row: The plant's logged row (`PLANT_COLUMNS`, plus ``transfer_time_s``: the time
            the transfer there and back took on the plant's clock, NaN when the object
            never reached a valid pre-transfer state; to 1 ms).
        t_s: Time of each sample since the object was placed (s, to 1 ms), (n,).
        pose: The object's pose in F_T as the camera saw it, (n, 7): position of its frame
            F_O (m, to 1 mm) and quaternion (w, x, y, z, each to 10⁻³).
        barriers: Whether each light barrier (tm_near, tm_far, tu_near, tu_far) is
            interrupted, (n, 4).
        belts: The commanded surface speed of each belt (tm_left, tm_right, tu_left,
            tu_right; m/s), (n, 4).
        starts: When the controller started its clock (s since placing, to 1 ms): the
            check of S_pre after settling, then each transfer forming its OTS.
        attempts: How often the object was placed (an invalid settled state or a diverged
            run is placed again, as an operator would).
    """

    row: dict[str, object]
    t_s: np.ndarray
    pose: np.ndarray
    barriers: np.ndarray
    belts: np.ndarray
    starts: tuple[float, ...]
    attempts: int


def _quantize(values: np.ndarray, step: float) -> np.ndarray:
    # Rounding to decimals (not multiplying back) keeps the shortest decimal form.
    return np.round(np.asarray(values, dtype=float), round(-np.log10(step)))


class _CameraTrack:
    """Builds recording plant systems (`systems`, in `_run_job`'s place of the cache) and
    keeps the samples of the last run (each attempt starts afresh)."""

    def __init__(self, build: Callable[..., VirtualTransferSystem]) -> None:
        self._build = build
        self.placements = 0
        self.starts: list[float] = []
        self.rows: list[tuple[float, ...]] = []

    def systems(self, obj, scene, refine: int = 0, mismatch=None) -> VirtualTransferSystem:
        system = self._build(obj, scene, refine, mismatch)
        system.clock = TrackingClock(system, self)
        self.placements += refine == 0  # a finer re-run is the same placement
        self.starts, self.rows = [], []
        return system

    def sample(self, system: VirtualTransferSystem) -> None:
        tm, tu = system.tm.barriers(), system.tu.barriers()
        self.rows.append((
            float(system.data.time), *system.object_qpos().tolist(),
            float(tm["near"]), float(tm["far"]), float(tu["near"]), float(tu["far"]),
            system.tm.belt_speed("left"), system.tm.belt_speed("right"),
            system.tu.belt_speed("left"), system.tu.belt_speed("right"),
        ))  # fmt: skip

    def recording(self, row: dict[str, object], transfer_time_s: float) -> PlantRecording:
        if not self.rows:
            raise RuntimeError("the plant's camera saw no sample of the experiment")
        data = np.array(self.rows)
        res = CAMERA_RESOLUTION
        t = float(transfer_time_s)
        return PlantRecording(
            row={**row, "transfer_time_s": t if np.isnan(t) else round(t, 3)},
            t_s=_quantize(data[:, 0], res["time_s"]),
            pose=np.hstack([_quantize(data[:, 1:4], res["position_m"]),
                            _quantize(data[:, 4:8], res["quaternion"])]),
            barriers=data[:, 8:12] > 0.5,
            belts=data[:, 12:16].copy(),
            starts=tuple(float(v) for v in _quantize(np.array(self.starts), res["time_s"])),
            attempts=self.placements,
        )  # fmt: skip
