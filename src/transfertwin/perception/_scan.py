"""Workspace scan and servoed look (Sec. 5.4, 5.5): what the TM sees of the belts.

Before a transfer the TM scans its own belts and the docked unit's from two viewpoints,
α₁ = 20° and α₂ = −30° (Sec. 5.5): one frame cannot hold the whole workspace. The two
clouds are merged in F_T and run through the detector once. `look` then turns the camera
onto a detected object (Eq. 5.14) and detects again from that single, centred frame.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from transfertwin.perception._aabb import AABB
from transfertwin.perception._camera import DepthCamera, View
from transfertwin.perception._detector import Detection, DetectorConfig, detect
from transfertwin.perception._servo import servo_angle
from transfertwin.perception._workspace import Workspace

__all__ = ["SCAN_ANGLES_DEG", "Look", "look", "workspace_scan"]

#: The scan's two viewpoints (Sec. 5.5), degrees.
SCAN_ANGLES_DEG: tuple[float, float] = (20.0, -30.0)


def workspace_scan(
    camera: DepthCamera,
    workspace: Workspace,
    *,
    angles_deg: Sequence[float] = SCAN_ANGLES_DEG,
    cfg: DetectorConfig | None = None,
    seed: int = 0,
) -> tuple[Detection, tuple[View, ...]]:
    """Capture one frame per angle (frame k seeded `seed + k`), merge, detect."""
    views = tuple(camera.capture(math.radians(a), seed + k) for k, a in enumerate(angles_deg))
    return detect(views, workspace, cfg, seed=seed), views


@dataclass(frozen=True)
class Look:
    """A servoed look at one object.

    Attributes:
        alpha_rad: Servo angle from Eq. 5.14 (clipped to the servo's range).
        detection: The detector's output for the centred frame.
        view: The frame.
    """

    alpha_rad: float
    detection: Detection
    view: View

    def nearest(self, target: AABB) -> AABB | None:
        """The detected box whose centre is nearest to `target`'s, or None."""
        if not self.detection.boxes:
            return None
        return min(self.detection.boxes, key=lambda b: math.dist(b.centre, target.centre))


def look(
    camera: DepthCamera,
    workspace: Workspace,
    target: AABB,
    *,
    cfg: DetectorConfig | None = None,
    seed: int = 0,
) -> Look:
    """Point the camera at `target`'s centre (Eq. 5.12–5.14), capture one frame, detect."""
    alpha, _ = servo_angle(camera.rig, target.centre[0], target.centre[2])
    alpha = camera.rig.clip(alpha)
    view = camera.capture(alpha, seed)
    return Look(alpha, detect([view], workspace, cfg, seed=seed), view)
