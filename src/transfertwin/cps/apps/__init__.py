"""The logical assets' applications: TMS, Experiment Manager, PropS, virtual environment."""

from transfertwin.cps.apps._applications import AssetApplications
from transfertwin.cps.apps._environment import Environment, ScaledClock
from transfertwin.cps.apps._ledger import ObjectLedger
from transfertwin.cps.apps._props import (
    Pose2D,
    PoseGraph,
    PoseGraphSolution,
    PoseObservation,
    fuse_poses,
    wrap_angle,
)

__all__ = [
    "AssetApplications",
    "Environment",
    "ObjectLedger",
    "Pose2D",
    "PoseGraph",
    "PoseGraphSolution",
    "PoseObservation",
    "ScaledClock",
    "fuse_poses",
    "wrap_angle",
]
