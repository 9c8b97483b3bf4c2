"""MuJoCo virtual models of the belt transfer system and their virtual HAL (Sec. 5.2.1)."""

from transfertwin.sim._config import (
    MULTICCD_HULLS,
    PROFILES,
    DockingError,
    LayoutConfig,
    PhysicsConfig,
    PlacementConfig,
    SceneConfig,
    scene_profile,
)
from transfertwin.sim._docking import tu_pose_in_tip_frame
from transfertwin.sim._gap import (
    GapAreaLayout,
    conveyor_span,
    gap_area_m2,
    gap_areas_cm2,
    gap_width_m,
)
from transfertwin.sim._names import (
    OBJECT_BODY,
    OBJECT_JOINT,
    TU_BODY,
    barrier_sensor,
    belt_geom,
    object_hull,
)
from transfertwin.sim._render import group_frames, render_strip, strip_camera, strip_pixels
from transfertwin.sim._scene import BARRIERS, BELTS, UNITS, UnitGeometry, build_spec, unit_layout
from transfertwin.sim._system import (
    UNIT_LOAD_X_M,
    MujocoUnitHAL,
    SimClock,
    SimulationUnstable,
    TrackingClock,
    VirtualTransferSystem,
    object_quat,
    outer_vertices,
    tu_quat,
)

__all__ = [
    "BARRIERS",
    "BELTS",
    "MULTICCD_HULLS",
    "OBJECT_BODY",
    "OBJECT_JOINT",
    "PROFILES",
    "TU_BODY",
    "UNITS",
    "UNIT_LOAD_X_M",
    "DockingError",
    "GapAreaLayout",
    "LayoutConfig",
    "MujocoUnitHAL",
    "PhysicsConfig",
    "PlacementConfig",
    "SceneConfig",
    "SimClock",
    "SimulationUnstable",
    "TrackingClock",
    "UnitGeometry",
    "VirtualTransferSystem",
    "barrier_sensor",
    "belt_geom",
    "build_spec",
    "conveyor_span",
    "gap_area_m2",
    "gap_areas_cm2",
    "gap_width_m",
    "group_frames",
    "object_hull",
    "object_quat",
    "outer_vertices",
    "render_strip",
    "scene_profile",
    "strip_camera",
    "strip_pixels",
    "tu_pose_in_tip_frame",
    "tu_quat",
    "unit_layout",
]
