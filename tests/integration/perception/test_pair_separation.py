"""Two cores in a row are told apart (Fig. 5.17): their flat tops are not belts."""

from __future__ import annotations

import dataclasses
import math

from transfertwin.objects import load_object
from transfertwin.perception import (
    CameraIntrinsics,
    DepthCamera,
    DepthNoise,
    DetectorConfig,
    Workspace,
    detect,
    pair_scene,
    told_apart,
)
from transfertwin.sim import SceneConfig


def test_two_o1_cores_40mm_apart_give_two_matching_boxes() -> None:
    """Crosswise, the two cores' tops lie in one horizontal plane spanning more than
    `plane_min_span_m`; only the height limit keeps RANSAC from removing it as a belt."""
    cfg = SceneConfig()
    scene = pair_scene(load_object("o1").hulls, cfg)
    ws = Workspace.for_layout(cfg.layout, cfg.gap_m)
    truth = scene.place("front", math.radians(90), -0.2, 0.04)
    with DepthCamera(scene.model, scene.data, intrinsics=CameraIntrinsics(160, 120),
                     noise=DepthNoise()) as cam:  # fmt: skip
        view = cam.capture(0.0, 1)
    det = detect([view], ws, seed=0)
    assert len(det.belt_z) >= 1 and max(abs(z) for z in det.belt_z) < 0.005
    assert told_apart(det.boxes, truth, 0.02)
    no_height_limit = dataclasses.replace(DetectorConfig(), plane_max_z_m=1.0)
    topless = detect([view], ws, no_height_limit, seed=0)
    assert max(topless.belt_z) > 0.05  # the tops went as a "belt"
    assert not told_apart(topless.boxes, truth, 0.02)
