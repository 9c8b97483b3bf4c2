"""PropS in the loop at a docking (docs/architecture.md, "PropS in the loop"): what a
module senses when it docks (its own localisation fix, the unit camera's ChArUco
measurement of the docking error: `observe_docking`) reported to PropS, and the docking
error taken from PropS's fused estimate (`props_docking_estimate`)."""

from __future__ import annotations

import asyncio
import functools
import json
import logging
import math
from typing import Any

import numpy as np

from transfertwin.cps.aas import Capability
from transfertwin.cps.node import find_partner_ids
from transfertwin.sim import DockingError

__all__ = ["CAMERA_SIGMA_THETA_RAD", "CAMERA_SIGMA_XY_M", "observe_docking",
           "props_docking_estimate"]  # fmt: skip

log = logging.getLogger("transfertwin.cps")


#: Standard deviations PropS is told for a unit camera's ChArUco docking measurement:
#: about twice the spread measured on this rig with 3 grey levels of pixel noise (0.05 mm,
#: 0.2 mrad; docs/architecture.md, "PropS in the loop").
CAMERA_SIGMA_XY_M = 1e-4
CAMERA_SIGMA_THETA_RAD = 5e-4


@functools.cache
def _charuco_rig():
    from transfertwin.navigation import CharucoRig

    return CharucoRig(pixel_noise_sd=3.0)


def observe_docking(robot, error, seed: int):
    """What is sensed at a docking: the module's own localisation fix of its world pose
    (x, y, θ, σ_xy, σ_θ) and the unit camera's ChArUco measurement of the docking error
    (x, y, θ; None when the board is not found)."""
    from transfertwin.navigation import localise

    rng = np.random.default_rng(np.random.SeedSequence([seed, 11]))
    noise = robot.cfg.noise
    own = localise(robot.pose, noise, rng)
    truth = np.array([error.x_m, error.y_m, error.theta_rad])
    seen = _charuco_rig().measure_error(truth, rng)
    return ((*(float(v) for v in own), noise.loc_xy_sd_m, noise.loc_theta_sd_rad),
            None if seen is None else tuple(float(v) for v in seen))  # fmt: skip


def _mm_deg(x: float, y: float, theta: float) -> dict[str, float]:
    return {"x_mm": round(x * 1e3, 4), "y_mm": round(y * 1e3, 4),
            "theta_deg": round(math.degrees(theta), 4)}  # fmt: skip


async def props_docking_estimate(role, unit: str, error, observed,
                                  measured: str = "true"):  # fmt: skip
    """PropS in the loop: report the module's pose and the unit camera's observation
    (`observed()`, run in a worker thread: (x, y, θ, σ_xy, σ_θ), and (x, y, θ) or None) to
    PropS, and take the docking error from its fused estimate (with its uncertainty). On
    the emulated plant the physics docks with the true error (it is the reality; the
    estimate is what the twin knows). Without PropS on the floor, or when it does not
    answer, `error` (recorded as `measured`: the true one, or the module's localisation's
    on real hardware), and why. PropS is the asset that realises FusePoses
    (`find_partner_ids`: the graph's answer, offline ones too: one that is away is said to
    be; or the floor file's while the graph is away)."""
    tm = role.aid
    fusers = await find_partner_ids(role.node, Capability.FUSE_POSES, online=False)
    if not fusers:  # no pose fuser on the floor
        return error, None
    props = fusers[0]
    own, seen = await asyncio.to_thread(observed)
    info: dict[str, Any] = {measured: _mm_deg(error.x_m, error.y_m, error.theta_rad),
                            "camera": seen is not None}  # fmt: skip
    try:
        await asyncio.wait_for(role.node.peers.call(props, "ReportPose", tm, tm, *own), 10.0)
        if seen is not None:
            await asyncio.wait_for(role.node.peers.call(
                props, "ReportRelativePose", f"{unit}/camera", tm, unit, *seen,
                CAMERA_SIGMA_XY_M, CAMERA_SIGMA_THETA_RAD), 10.0)  # fmt: skip
        est = json.loads(await asyncio.wait_for(
            role.node.peers.call(props, "DockingError", tm, unit), 10.0))  # fmt: skip
        fused = DockingError(est["x_m"], est["y_m"], est["theta_rad"])
    except Exception as exc:  # PropS away, or an estimate outside the dockable range
        log.info("%s: docking error from PropS not available (%s); the %s one", tm, exc,
                 measured)  # fmt: skip
        return error, {**info, "used": measured, "why": f"{type(exc).__name__}: {exc}"}
    info["fused"] = {**_mm_deg(fused.x_m, fused.y_m, fused.theta_rad),
                     "sd_x_mm": round(est["sd_x_m"] * 1e3, 4),
                     "sd_y_mm": round(est["sd_y_m"] * 1e3, 4),
                     "sd_theta_deg": round(math.degrees(est["sd_theta_rad"]), 4)}  # fmt: skip
    if role.node.cfg.hal.kind == "plant":
        return error, {**info, "used": "true (the plant's physics)"}
    return fused, {**info, "used": "fused"}
