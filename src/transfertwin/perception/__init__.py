"""The transport module's vision skills (Sec. 5.4.2–5.4.4, 5.5) on a simulated depth camera.

A virtual RGB-D camera on the TM's servo (frames of Table 5.1) renders depth from the MuJoCo
scene with a seeded noise and dropout model; the detector of Fig. 5.14 turns frames into
one AABB per object; the tracker (Sec. 5.4.3) carries identities through missed frames with
a Kalman filter driven by the belt speed; visual servoing (Eq. 5.12–5.14) keeps the camera
on the object. The same code would run on a physical robot's frames.
"""

from transfertwin.perception._aabb import AABB, ground_truth_aabb
from transfertwin.perception._camera import CameraIntrinsics, DepthCamera, View, depth_to_points
from transfertwin.perception._detector import Detection, DetectorConfig, detect
from transfertwin.perception._frames import ServoRig, camera_pose, t_ac, t_sa, t_ts
from transfertwin.perception._loop import PerceptionConfig, open_sensor
from transfertwin.perception._noise import DepthNoise, apply_depth_noise
from transfertwin.perception._pair import PairScene, pair_scene
from transfertwin.perception._plane import fit_plane, ransac_plane
from transfertwin.perception._plot import plot_detection
from transfertwin.perception._possession import (
    Possession,
    PossessionMatch,
    PossessionReport,
    footprint_over_yaw,
    match_possessions,
    size_distance,
    unit_by_gap,
)
from transfertwin.perception._scan import SCAN_ANGLES_DEG, Look, look, workspace_scan
from transfertwin.perception._sensor import PerceptionSensor
from transfertwin.perception._separation import (
    SeparationResult,
    aim_point_x,
    min_separation,
    told_apart,
)
from transfertwin.perception._servo import eq_5_14, servo_angle, servo_chain_2d
from transfertwin.perception._tracker import Track, Tracker, TrackerConfig
from transfertwin.perception._workspace import Workspace

__all__ = [
    "AABB",
    "SCAN_ANGLES_DEG",
    "CameraIntrinsics",
    "DepthCamera",
    "DepthNoise",
    "Detection",
    "DetectorConfig",
    "Look",
    "PairScene",
    "PerceptionConfig",
    "PerceptionSensor",
    "Possession",
    "PossessionMatch",
    "PossessionReport",
    "SeparationResult",
    "ServoRig",
    "Track",
    "Tracker",
    "TrackerConfig",
    "View",
    "Workspace",
    "aim_point_x",
    "apply_depth_noise",
    "camera_pose",
    "depth_to_points",
    "detect",
    "eq_5_14",
    "fit_plane",
    "footprint_over_yaw",
    "ground_truth_aabb",
    "look",
    "match_possessions",
    "min_separation",
    "open_sensor",
    "pair_scene",
    "plot_detection",
    "ransac_plane",
    "servo_angle",
    "servo_chain_2d",
    "size_distance",
    "t_ac",
    "t_sa",
    "t_ts",
    "told_apart",
    "unit_by_gap",
    "workspace_scan",
]
