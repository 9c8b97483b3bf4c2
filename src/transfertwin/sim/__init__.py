"""MuJoCo virtual models of the belt transfer system and their virtual HAL (Sec. 5.2.1)."""

from transfertwin.sim._config import (
    DockingError,
    LayoutConfig,
    PhysicsConfig,
    PlacementConfig,
    SceneConfig,
)
from transfertwin.sim._docking import tu_pose_in_tip_frame
from transfertwin.sim._scene import build_spec
from transfertwin.sim._system import (
    MujocoUnitHAL,
    SimClock,
    SimulationUnstable,
    VirtualTransferSystem,
    object_quat,
)

__all__ = [
    "DockingError",
    "LayoutConfig",
    "MujocoUnitHAL",
    "PhysicsConfig",
    "PlacementConfig",
    "SceneConfig",
    "SimClock",
    "SimulationUnstable",
    "VirtualTransferSystem",
    "build_spec",
    "object_quat",
    "tu_pose_in_tip_frame",
]
