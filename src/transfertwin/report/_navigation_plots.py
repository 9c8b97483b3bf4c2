"""Drawing one docking run (Fig. 5.10): the occupancy grid, the planned and driven path, and
the laser scan with the chosen line at the docked pose. Data first: everything drawn is read
from the `DockingRun` and the `ShopFloor`; this module only draws."""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Polygon

from transfertwin.navigation import DockingRun, RobotConfig, ShopFloor, compose, to_world

__all__ = ["plot_docking_run"]


def _robot(ax: Axes, pose: np.ndarray, robot: RobotConfig, color: str) -> None:
    ax.add_patch(Polygon(to_world(pose, robot.footprint()), closed=True, fill=False, ec=color))
    ax.plot(*to_world(pose, np.array([robot.laser_xy_m])).T, "o", color=color, ms=4)


def _draw(ax: Axes, floor: ShopFloor, run: DockingRun, robot: RobotConfig) -> None:
    w, h = floor.size_m
    ax.imshow(floor.grid, origin="lower", extent=(0, w, 0, h), cmap="Greys", vmin=0, vmax=1.6)
    for s in floor.stations:
        c = s.rect
        ax.text(c.cx_m, c.cy_m, f"{s.name} ({s.mount})", ha="center", va="center", fontsize=8)
    ax.plot(*run.path.poses[:, :2].T, "-", color="#2ca02c", lw=1.5, label="planned path")
    ax.plot(*run.trace[:, :2].T, "-", color="#1f77b4", lw=0.8, label="driven (truth)")
    pts = run.approach.last_scan.points()
    world = to_world(run.approach.laser_pose, pts[np.isfinite(pts[:, 0])])
    ax.plot(*world.T, ".", color="#d62728", ms=1.5, label="laser scan (docked)")
    est = run.approach.estimate
    if est is not None:
        # the estimate is in the robot's believed frame; draw it from the true pose
        ends = to_world(run.trace[-1], np.stack([est.line.start, est.line.end]))
        ax.plot(*ends.T, "-", color="#ff7f0e", lw=2.5, label="chosen line")
        edge = compose(run.trace[-1], est.edge)
        ax.plot(edge[0], edge[1], "x", color="#ff7f0e", ms=8)
    _robot(ax, run.start, robot, "#7f7f7f")
    _robot(ax, run.trace[-1], robot, "#1f77b4")
    ax.set_aspect("equal")
    ax.set_xlabel("x / m")
    ax.set_ylabel("y / m")


def plot_docking_run(
    floor: ShopFloor, run: DockingRun, robot: RobotConfig | None = None, fig: Figure | None = None
) -> Figure:
    """The whole floor (left) and the docking area (right) of one run."""
    robot = RobotConfig() if robot is None else robot
    fig = Figure(figsize=(13.0, 5.5)) if fig is None else fig
    left, right = fig.subplots(1, 2)
    fig.subplots_adjust(left=0.06, right=0.98, wspace=0.2)
    _draw(left, floor, run, robot)
    left.set_title(f"station {run.station}, run {run.run}: path and scan")
    left.legend(loc="upper right", fontsize=7)
    _draw(right, floor, run, robot)
    goal = floor.station(run.station).goal_pose()
    right.set_xlim(goal[0] - 1.2, goal[0] + 1.2)
    right.set_ylim(goal[1] - 1.2, goal[1] + 1.2)
    x, y, t = run.error * np.array([1000.0, 1000.0, 180.0 / np.pi])
    right.set_title(f"docked: ξ = ({x:.1f} mm, {y:.1f} mm, {t:.2f}°), {run.status}")
    return fig
