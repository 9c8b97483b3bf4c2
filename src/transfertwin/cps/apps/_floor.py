"""The transport module on the shop floor: its pose, and navigating and docking to a station
(Sec. 5.4.1, Fig. 5.9a, 5.10) with the skills of `transfertwin.navigation`.

The CPS's transfer units TU_A…TU_D stand at the floor stations A…D of
`navigation.default_floor` (a unit's AAS names its station; `Station.transfer_unit` is
'TU_' + the station's name). The robot starts parked at `HOME_POSE`, in the aisle between
the stations. A sub-operation's way to a station is:

* **leave** (only when docked): reverse straight out by the coarse distance at docking speed,
  then turn on the spot to face away from the station (wheel slip and scale errors apply);
* **navigate**: a global localisation fix, Hybrid A* from the believed pose to the station's
  coarse pose, pure pursuit along the path;
* **dock**: the laser-based final approach; the docking error ξ = pose of F_D in the goal
  F_D_G *emerges* from sensing and geometry (`navigation.approach`).

`FloorRobot.teleport_dock` is the sampled mode's counterpart: no driving, the robot is put at
the goal composed with a docking error drawn from the fitted generator, so the published pose
agrees with the error the simulation docks with in both modes.

Every draw of one leg comes from one generator seeded by the leg's seed; the robot's pose
carries over from leg to leg (a leg depends on where the previous one ended).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from transfertwin._errors import InputError
from transfertwin.navigation import (
    DockingConfig,
    Path,
    ShopFloor,
    approach,
    collision_free,
    compose,
    default_floor,
    drive,
    follow_path,
    localise,
    plan_path,
    relative,
)
from transfertwin.sim import DockingError

__all__ = ["HOME_POSE", "FloorRobot", "LegResult"]

#: Parking pose of the transport module when the CPS starts (x m, y m, θ rad): the aisle
#: between the stations, clear of the pillar.
HOME_POSE = (6.0, 5.2, 0.0)


@dataclass(frozen=True)
class LegResult:
    """How the robot got to a station.

    Attributes:
        station: Floor station ('A'..'D').
        status: 'ok', or why the robot did not dock: 'no_path', 'no_line', 'timeout',
            'out_of_range' (an error the transfer system cannot dock with).
        error: True docking error (x m, y m, θ rad), NaN when the robot never reached the
            approach.
        path_m: Length of the planned path, m (0 for a teleport).
        drive_s: Simulated time spent leaving, driving and approaching, s.
        reason: One line for a status other than 'ok'.
    """

    station: str
    status: str
    error: tuple[float, float, float]
    path_m: float = 0.0
    drive_s: float = 0.0
    reason: str = ""

    def docking_error(self) -> DockingError:
        """The error the simulation docks with (raises InputError when out of range)."""
        return DockingError(*self.error)

    def as_dict(self) -> dict[str, object]:
        """JSON-able: station, status, error in mm and degrees, path length, reason."""
        x, y, th = self.error
        return {
            "station": self.station,
            "status": self.status,
            "x_mm": round(x * 1000.0, 3),
            "y_mm": round(y * 1000.0, 3),
            "theta_deg": round(math.degrees(th), 4),
            "path_m": round(self.path_m, 3),
            "drive_s": round(self.drive_s, 2),
            "reason": self.reason,
        }


class FloorRobot:
    """One transport module's body on the shop floor (true pose, docked station).

    Args:
        floor: The shop floor (None: `default_floor()`).
        cfg: Robot, sensors, planner and controllers (None: the defaults).
        home: Start pose (x, y, θ).
    """

    def __init__(
        self,
        floor: ShopFloor | None = None,
        cfg: DockingConfig | None = None,
        home: tuple[float, float, float] = HOME_POSE,
    ) -> None:
        self.floor = default_floor() if floor is None else floor
        self.cfg = DockingConfig() if cfg is None else cfg
        self.pose = np.array(home, dtype=float)
        self.docked_at: str | None = None
        self._leg: tuple | None = None  # (station, rng, scale, belief, path_m, t) of navigate
        if not collision_free(self.floor, self.cfg.robot, self.pose, self.cfg.planner.margin_m):
            raise InputError(f"home pose {home} of the transport module is in collision")

    def _leave(self, rng: np.random.Generator, scale: np.ndarray) -> float:
        """Reverse out of the docked station and turn away; returns the time taken, s."""
        if self.docked_at is None:
            return 0.0
        cfg, robot = self.cfg, self.cfg.robot
        dt = cfg.follow.dt_s
        truth, odom = self.pose, self.pose.copy()
        v = robot.dock_speed_m_s
        t = 0.0
        for _ in range(round(cfg.coarse_distance_m / (v * dt))):
            truth, odom = drive(truth, odom, -v, 0.0, dt, robot, scale, rng, cfg.noise)
            t += dt
        w = 0.5
        for _ in range(round(math.pi / (w * dt))):
            truth, odom = drive(truth, odom, 0.0, w, dt, robot, scale, rng, cfg.noise)
            t += dt
        self.pose, self.docked_at = truth, None
        return t

    def navigate(self, station: str, seed: int) -> LegResult:
        """Leave the current station and drive to `station`'s coarse pose.

        The leg's draws (this and the following `dock`) come from one generator seeded by
        `seed`: a leg is a pure function of the robot's pose, `station` and `seed`.
        """
        cfg = self.cfg
        target = self.floor.station(station)
        rng = np.random.default_rng(np.random.SeedSequence([seed, 7]))
        scale = rng.normal(0.0, cfg.noise.wheel_scale_sd, 2)
        t = self._leave(rng, scale)
        belief = localise(self.pose, cfg.noise, rng)
        nan = (math.nan, math.nan, math.nan)
        try:
            path: Path = plan_path(
                self.floor, cfg.robot, belief, target.coarse_pose(cfg.coarse_distance_m),
                cfg.planner,
            )  # fmt: skip
        except InputError as exc:
            self._leg = None
            return LegResult(station, "no_path", nan, drive_s=t, reason=str(exc))
        driven = follow_path(path, self.pose, cfg.robot, cfg.noise, scale, rng, cfg.follow)
        t += (len(driven.trace) - 1) * cfg.follow.dt_s
        self.pose = driven.truth
        self._leg = (station, rng, scale, driven.belief, path.length_m, t)
        return LegResult(station, "ok", nan, path.length_m, t)

    def dock(self, station: str) -> LegResult:
        """The laser-based final approach at `station` after `navigate` brought the robot to
        its coarse pose; the docking error emerges. The robot ends where it stopped (docked
        when the status is 'ok')."""
        if self._leg is None or self._leg[0] != station:
            raise InputError(f"dock at {station}: the robot has not navigated there")
        _, rng, scale, belief, path_m, t = self._leg
        self._leg = None
        cfg = self.cfg
        target = self.floor.station(station)
        docked = approach(
            target, self.pose, belief, self.floor.segments, cfg.robot, cfg.laser,
            cfg.segmentation, cfg.noise, scale, rng, cfg.approach,
        )  # fmt: skip
        t += (len(docked.trace) - 1) * cfg.approach.dt_s
        self.pose = docked.truth
        error = tuple(float(v) for v in relative(target.goal_pose(), docked.truth))
        if docked.status != "ok":
            why = {"no_line": "the laser found no line matching the station's front face",
                   "timeout": "the final approach did not converge in time"}  # fmt: skip
            return LegResult(station, docked.status, error, path_m, t,
                             why.get(docked.status, docked.status))  # fmt: skip
        self.docked_at = station
        try:
            DockingError(*error)
        except InputError as exc:
            return LegResult(station, "out_of_range", error, path_m, t, str(exc))
        return LegResult(station, "ok", error, path_m, t)

    def teleport_dock(self, station: str, error: DockingError) -> LegResult:
        """Put the robot docked at `station` with a given error (the sampled mode)."""
        xi = (error.x_m, error.y_m, error.theta_rad)
        self.pose = compose(self.floor.station(station).goal_pose(), np.array(xi))
        self.docked_at = station
        return LegResult(station, "ok", xi)
