"""`transfertwin perceive`: what the transport module's camera detects (Sec. 5.4.3, 5.5)."""

from __future__ import annotations

import argparse
import json
import math

from rich.console import Console
from rich.table import Table

from transfertwin._errors import InputError
from transfertwin.cli._common import add_state_args
from transfertwin.cli._paths import out_file

__all__ = ["register"]


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise InputError(f"--size expects WIDTHxHEIGHT, e.g. 320x240, got {text!r}") from None
    return w, h


def cmd_perceive(args: argparse.Namespace) -> int:
    """Place the object, scan the workspace from two viewpoints, servo onto the object and
    detect again; print the detected AABBs beside the true one."""
    from transfertwin.ots import POSITIONS, check_theta_deg, parse_conveyor, parse_face
    from transfertwin.perception import (
        SCAN_ANGLES_DEG,
        CameraIntrinsics,
        DepthCamera,
        DepthNoise,
        Workspace,
        ground_truth_aabb,
        look,
        plot_detection,
        workspace_scan,
    )
    from transfertwin.sim import DockingError, SceneConfig
    from transfertwin.study.experiment import system_for

    face, conveyor = parse_face(args.face), parse_conveyor(args.conveyor)
    theta = check_theta_deg(args.theta)
    dock = DockingError.from_text(args.dock_error)
    if args.seed < 0:
        raise InputError(f"--seed must be a non-negative integer, got {args.seed}")
    intrinsics = CameraIntrinsics(*_size(args.size))
    image = out_file(args.image, (".png",)) if args.image else None
    scene = SceneConfig()
    system = system_for(args.object, args.units, scene)
    system.reset(dock)
    x, y = POSITIONS[conveyor]
    system.place(face, math.radians(theta), x, y)
    system.clock.wait(scene.placement.settle_time_s)
    truth = ground_truth_aabb(system)
    noise = DepthNoise.clean() if args.clean else DepthNoise()
    workspace = Workspace.for_layout(scene.layout, scene.gap_m, docked=True)
    with DepthCamera(system.model, system.data, intrinsics=intrinsics, noise=noise) as cam:
        scan, views = workspace_scan(cam, workspace, seed=args.seed)
        target = min(scan.boxes, key=lambda b: math.dist(b.centre[:2], (x, y)), default=truth)
        seen = look(cam, workspace, target, seed=args.seed + len(views))
    nearest = seen.nearest(truth)
    out = {
        "object": args.object, "face": face, "conveyor": conveyor, "theta_deg": theta,
        "dock_error": dict(zip(("x_mm", "y_mm", "theta_deg"), dock.as_mm_deg(), strict=True)),
        "seed": args.seed, "noise": "clean" if args.clean else "default",
        "truth": truth.as_dict(),
        "scan": {"angles_deg": list(SCAN_ANGLES_DEG), "boxes": [b.as_dict() for b in scan.boxes]},
        "servo": {"alpha_deg": round(math.degrees(seen.alpha_rad), 3),
                  "boxes": [b.as_dict() for b in seen.detection.boxes]},
        "error_mm": round(1000 * nearest.corner_error(truth), 2) if nearest else None,
    }  # fmt: skip
    if image is not None:
        title = (f"{args.object} {face} {conveyor} θ = {theta}°: servo look at "
                 f"α = {math.degrees(seen.alpha_rad):.1f}° (dashed: true AABB)")  # fmt: skip
        plot_detection(seen.detection, [*views, seen.view], image, truth=truth, title=title)
        out["image"] = str(image)
    if args.json:
        print(json.dumps(out))
    else:
        _print(out)
    return 0


def _print(out: dict) -> None:
    table = Table(title=f"{out['object']}: detected vs true AABB in F_T (m)")
    for col in ("source", "x", "y", "z", "s_x", "s_y", "s_z", "points"):
        table.add_column(col)

    def row(label: str, box: dict) -> None:
        values = [f"{box[k]:.4f}" for k in ("x", "y", "z", "s_x", "s_y", "s_z")]
        table.add_row(label, *values, str(box["n_points"] or "-"))

    row("truth (hulls)", out["truth"])
    for i, box in enumerate(out["scan"]["boxes"], start=1):
        row(f"scan {i}", box)
    for i, box in enumerate(out["servo"]["boxes"], start=1):
        row(f"servo {i} (α = {out['servo']['alpha_deg']:.1f}°)", box)
    console = Console()
    console.print(table)
    console.print(f"largest face error of the servoed box: {out['error_mm']} mm")


def register(sub: argparse._SubParsersAction) -> None:
    """Add `perceive`."""
    p = sub.add_parser("perceive", help="detect an object with the TM's simulated depth camera")
    add_state_args(p)
    p.add_argument("--seed", type=int, default=0, help="seed of the noise and RANSAC draws")
    p.add_argument("--size", default="320x240", help="depth image WIDTHxHEIGHT (320x240)")
    p.add_argument("--clean", action="store_true", help="no depth noise, no dropout")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--image", help="draw the cloud, the clusters and the boxes to this PNG")
    p.set_defaults(func=cmd_perceive)
