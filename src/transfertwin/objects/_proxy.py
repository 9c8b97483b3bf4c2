"""Calibrated proxy objects: a base object plus features below a face's resting plane.

A real starter-motor core rests on flange ears, bolt heads and terminal studs that can drop
into the gap between the docked belts and catch on the transfer unit's pulley. The built-in
procedural cores keep such features inside the can's radius, so nothing hangs below their
contact line. A proxy adds, per face, one `Protrusion`: a convex box whose bottom lies
`depth_m` below that face's resting plane. It is appended to the base object's convex hulls
(no CoACD run, deterministic); mass and inertia stay the base object's.

**A proxy is not a scan.** `transfertwin calibrate object` infers the protrusion depths of one
real object from its real outcomes; the result reproduces how often the object catches in the
gap, not its true shape. A proxy is saved as a small JSON file (suffix `.proxy.json`) that
`load_object` — and so every command that takes a mesh — accepts.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from transfertwin._errors import InputError
from transfertwin.objects._model import ObjectModel

__all__ = ["PROXY_SUFFIX", "Protrusion", "ProxySpec", "proxy_model", "read_proxy", "write_proxy"]

#: File suffix of a saved proxy object.
PROXY_SUFFIX = ".proxy.json"


@dataclass(frozen=True)
class Protrusion:
    """A box below the resting plane of one face (F_O, metres).

    Attributes:
        face: 'front' (below the lowest hull point in F_O) or 'back' (above the highest,
            which is the bottom once the object is turned over).
        depth_m: How far the box's bottom lies below the face's resting plane (0: none).
        x_frac: Axial centre as a fraction of the AABB's x range (0 rear, 1 pinion).
        y_frac: Lateral centre as a fraction of the AABB's y range.
        size_x_m: Extent along the object's x axis.
        size_y_m: Extent along its y axis.
        height_m: Extent from its bottom up into the body (None: depth + 15 mm).
    """

    face: str
    depth_m: float
    x_frac: float = 0.5
    y_frac: float = 0.5
    size_x_m: float = 0.006
    size_y_m: float = 0.03
    height_m: float | None = None

    def __post_init__(self) -> None:
        if self.face not in ("front", "back"):
            raise InputError(f"protrusion face must be 'front' or 'back', got {self.face!r}")
        if not (0.0 <= self.depth_m <= 0.1):
            raise InputError(f"protrusion depth must be in 0..0.1 m, got {self.depth_m!r}")
        if not (0.0 <= self.x_frac <= 1.0 and 0.0 <= self.y_frac <= 1.0):
            raise InputError("protrusion x_frac and y_frac must be in 0..1")

    def hull(self, model: ObjectModel) -> np.ndarray:
        """The 8 vertices (F_O) of this protrusion on `model`, (8, 3)."""
        verts = np.vstack(model.hulls)
        lo, hi = verts.min(axis=0), verts.max(axis=0)
        cx = lo[0] + self.x_frac * (hi[0] - lo[0])
        cy = lo[1] + self.y_frac * (hi[1] - lo[1])
        height = self.depth_m + 0.015 if self.height_m is None else self.height_m
        if self.face == "front":
            z0 = lo[2] - self.depth_m
            z1 = z0 + height
        else:
            z1 = hi[2] + self.depth_m
            z0 = z1 - height
        hx, hy = self.size_x_m / 2, self.size_y_m / 2
        return np.array(
            [[x, y, z] for x in (cx - hx, cx + hx) for y in (cy - hy, cy + hy) for z in (z0, z1)]
        )


@dataclass(frozen=True)
class ProxySpec:
    """A calibrated proxy: its id, base object reference and protrusions."""

    object_id: str
    base: str
    protrusions: tuple[Protrusion, ...]
    note: str = "calibrated proxy, not a scan"

    def to_dict(self) -> dict[str, object]:
        """JSON-ready description."""
        return {"object_id": self.object_id, "base": self.base, "note": self.note,
                "protrusions": [dataclasses.asdict(p) for p in self.protrusions]}  # fmt: skip


def proxy_model(base: ObjectModel, spec: ProxySpec) -> ObjectModel:
    """`base` with one extra box hull per protrusion of positive depth."""
    extra = tuple(p.hull(base) for p in spec.protrusions if p.depth_m > 0)
    return dataclasses.replace(
        base, object_id=spec.object_id, hulls=tuple(base.hulls) + extra,
        source=f"proxy of {base.source}", spec=None,
        feature_hulls=base.feature_hulls + len(extra),
    )  # fmt: skip


def write_proxy(spec: ProxySpec, path: str | Path) -> Path:
    """Save `spec` as JSON (`path` must end in `.proxy.json`)."""
    from transfertwin._atomic import write_atomic

    path = Path(path)
    if not path.name.endswith(PROXY_SUFFIX):
        raise InputError(f"{path}: a proxy file must end in {PROXY_SUFFIX}")
    return write_atomic(path, json.dumps(spec.to_dict(), indent=2) + "\n")


def read_proxy(path: str | Path) -> ProxySpec:
    """Read a proxy saved by `write_proxy`; InputError on anything malformed."""
    try:
        desc = json.loads(Path(path).read_text())
        prots = tuple(Protrusion(**p) for p in desc["protrusions"])
        return ProxySpec(str(desc["object_id"]), str(desc["base"]), prots,
                         str(desc.get("note", "")))  # fmt: skip
    except OSError as exc:
        raise InputError(f"{path}: cannot read: {exc.strerror}") from None
    except (ValueError, KeyError, TypeError) as exc:
        raise InputError(f"{path}: not a proxy object file ({exc})") from None
