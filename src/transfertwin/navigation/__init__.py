"""The transport module's navigation and docking on a 2-D shop floor (Sec. 5.4.1, 5.5, 6.1.2).

Occupancy grid with four stations, a differential-drive robot with a laser scanner at its
front-left corner, Hybrid A* planning under a curvature limit, split-and-merge line
segmentation, docking-pose estimation from a station's outer edge, a final-approach
controller, and the ChArUco measurement of the resulting docking error (Eq. 6.11).
"""

from typing import TYPE_CHECKING

from transfertwin._lazy import lazy_exports

if TYPE_CHECKING:
    from transfertwin.navigation._approach import ApproachConfig, ApproachResult, approach
    from transfertwin.navigation._charuco import CharucoRig, MeasuredPose, planar_to_se3
    from transfertwin.navigation._compare import (
        ComponentComparison,
        compare_with_real,
        real_errors_by_unit,
    )
    from transfertwin.navigation._dock_pose import DockEstimate, estimate_dock_pose
    from transfertwin.navigation._docking import (
        DockingConfig,
        DockingRun,
        dock_runs,
        simulate_docking,
    )
    from transfertwin.navigation._dubins import DubinsPath, dubins_shortest, sample_segments
    from transfertwin.navigation._floor import (
        MOUNTS,
        STATION_NAMES,
        ShopFloor,
        Station,
        default_floor,
    )
    from transfertwin.navigation._follow import FollowConfig, FollowResult, follow_path, localise
    from transfertwin.navigation._geometry import (
        Rect,
        compose,
        invert,
        relative,
        to_world,
        wrap_angle,
    )
    from transfertwin.navigation._laser import LaserConfig, Scan, cast_rays, scan
    from transfertwin.navigation._lines import (
        LineSegment,
        SegmentationConfig,
        fit_line,
        split_and_merge,
    )
    from transfertwin.navigation._planner import Path, PlannerConfig, collision_free, plan_path
    from transfertwin.navigation._robot import MotionNoise, RobotConfig, drive
    from transfertwin.navigation._table import (
        TABLE_COLUMNS,
        DockingRecord,
        emergent_docking_errors,
        records_csv,
    )

__all__ = [
    "MOUNTS",
    "STATION_NAMES",
    "TABLE_COLUMNS",
    "ApproachConfig",
    "ApproachResult",
    "CharucoRig",
    "ComponentComparison",
    "DockEstimate",
    "DockingConfig",
    "DockingRecord",
    "DockingRun",
    "DubinsPath",
    "FollowConfig",
    "FollowResult",
    "LaserConfig",
    "LineSegment",
    "MeasuredPose",
    "MotionNoise",
    "Path",
    "PlannerConfig",
    "Rect",
    "RobotConfig",
    "Scan",
    "SegmentationConfig",
    "ShopFloor",
    "Station",
    "approach",
    "cast_rays",
    "collision_free",
    "compare_with_real",
    "compose",
    "default_floor",
    "dock_runs",
    "drive",
    "dubins_shortest",
    "emergent_docking_errors",
    "estimate_dock_pose",
    "fit_line",
    "follow_path",
    "invert",
    "localise",
    "plan_path",
    "planar_to_se3",
    "real_errors_by_unit",
    "records_csv",
    "relative",
    "sample_segments",
    "scan",
    "simulate_docking",
    "split_and_merge",
    "to_world",
    "wrap_angle",
]

__getattr__, __dir__ = lazy_exports(__name__, __file__)
