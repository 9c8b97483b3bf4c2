"""The static layout of a running floor for the console's 3-D floor view.

`floor_layout(workdir)` reads the floor file the floor's ``cps.json`` names (the
demonstration floor, `default_floor_spec`, without one): its size, the
stations with their transfer units, the transport modules' start poses and where each object
starts. What moves — the modules' poses, who holds each object, the orders — comes from the
console's live feed (``/api/live``), which the page follows.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from transfertwin._errors import InputError
from transfertwin.cps import FloorSpec, default_floor_spec, load_floor

__all__ = ["floor_layout", "layout_of"]


def layout_of(floor: FloorSpec) -> dict[str, Any]:
    """A floor's static layout as JSON-ready data (metres, degrees)."""
    return {
        "name": floor.name,
        "size_m": list(floor.size_m),
        "stations": [{"name": s.name, "unit": s.unit, "x_m": s.x_m, "y_m": s.y_m,
                      "yaw_deg": s.yaw_deg, "mount": s.mount} for s in floor.stations],
        "modules": [{"id": m.asset_id, "x_m": m.x_m, "y_m": m.y_m, "theta_deg": m.theta_deg,
                     "standby": m.standby} for m in floor.modules],
        "objects": [{"id": oid, "unit": unit} for oid, unit in floor.objects],
    }  # fmt: skip


def floor_layout(workdir: Path) -> dict[str, Any]:
    """The layout of the floor running in `workdir` (see the module doc)."""
    path = workdir / "cps.json"
    try:
        info = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise LookupError(f"the CPS is not running (no cps.json in {workdir})") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(f"{path}: unreadable ({exc})") from None
    floor_file = info.get("floor") if isinstance(info, dict) else None
    if floor_file is None and isinstance(info, dict) and info.get("graph"):
        raise LookupError("a floor reached by its knowledge graph (web --graph): its floor "
                          "file is on its hosts, its layout is not known here")  # fmt: skip
    floor = load_floor(floor_file, check_cores=False) if floor_file else default_floor_spec()
    return layout_of(floor)
