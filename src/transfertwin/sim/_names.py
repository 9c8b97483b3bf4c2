"""The names of the scene's MuJoCo elements: defined here once, used by the builder and read
back through `model.geom(name)`, `model.sensor(name)`, `model.body(name)`, `model.joint(name)`.
"""

from __future__ import annotations

__all__ = [
    "OBJECT_BODY",
    "OBJECT_JOINT",
    "TU_BODY",
    "barrier_sensor",
    "belt_geom",
    "object_hull",
]

#: The object's body and its free joint.
OBJECT_BODY = "object"
OBJECT_JOINT = "object_free"
#: The transfer unit's mocap body (its pose carries the docking error).
TU_BODY = "tu"


def belt_geom(unit: str, belt: str, part: str) -> str:
    """Geom of a belt part: `part` is 'deck', 'pulley_start' or 'pulley_end'."""
    return f"{unit}_{belt}_{part}"


def barrier_sensor(unit: str, which: str) -> str:
    """Rangefinder (and its site) of a light barrier, `which` 'near' or 'far'."""
    return f"{unit}_barrier_{which}"


def object_hull(k: int) -> str:
    """Mesh and geom of the object's k-th convex hull."""
    return f"object_hull_{k}"
