"""Floor files read and written (the format: `transfertwin.cps.floor._floor_file`):
`parse_floor` and `load_floor` check a document at the edge and give the frozen
`FloorSpec`; `floor_toml` writes one back (what `load_floor` reads to an equal spec)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

from transfertwin._errors import InputError
from transfertwin.cps.aas import Capability
from transfertwin.cps.floor._floor_file import (
    LOGICAL_ASSETS,
    FloorSpec,
    ModuleSpec,
    OperationSpec,
    StationSpec,
)
from transfertwin.cps.floor._toml import finite, nonempty, read_toml

__all__ = ["floor_toml", "load_floor", "parse_floor"]


def parse_floor(doc: dict, name: str) -> FloorSpec:
    """A `FloorSpec` from a parsed floor document (see the module docstring)."""
    known = {"name", "size_m", "station", "module", "object", "logical", "operation", "hal",
             "bind"}
    if unknown := sorted(set(doc) - known):
        raise InputError(f"floor {name}: unknown key {unknown[0]!r}; known: "
                         f"{', '.join(sorted(known))}")  # fmt: skip
    name = str(doc.get("name", name))
    size = doc.get("size_m", [12.0, 8.0])
    if not isinstance(size, list) or len(size) != 2:
        raise InputError(f"floor {name}: size_m must be [width, height] in metres")
    size_m = (finite({"w": size[0]}, "w", f"floor {name}: size_m"),
              finite({"h": size[1]}, "h", f"floor {name}: size_m"))  # fmt: skip
    hal = doc.get("hal", "virtual")
    if hal not in ("virtual", "plant"):
        raise InputError(f"floor {name}: hal must be virtual or plant, got {hal!r} (a remote "
                         "HAL is set per station, with its gateway)")  # fmt: skip
    stations = []
    for i, t in enumerate(doc.get("station", [])):
        where = f"floor {name}: station {i + 1}"
        gateway = t.get("gateway")
        stations.append(StationSpec(nonempty(t, "name", where), finite(t, "x_m", where),
                                    finite(t, "y_m", where), finite(t, "yaw_deg", where),
                                    nonempty(t, "mount", where), str(t.get("hal", hal)),
                                    None if gateway is None else str(gateway),
                                    **_own_class(t, where, StationSpec)))  # fmt: skip
    modules = []
    for i, t in enumerate(doc.get("module", [])):
        where = f"floor {name}: module {i + 1}"
        gateway = t.get("gateway")
        modules.append(ModuleSpec(nonempty(t, "id", where), finite(t, "x_m", where),
                                  finite(t, "y_m", where), float(t.get("theta_deg", 0.0)),
                                  bool(t.get("standby", False)), str(t.get("hal", hal)),
                                  None if gateway is None else str(gateway),
                                  **_own_class(t, where, ModuleSpec)))  # fmt: skip
    objects = []
    for i, t in enumerate(doc.get("object", [])):
        where = f"floor {name}: object {i + 1}"
        objects.append((nonempty(t, "id", where), nonempty(t, "at", where)))
    logical = doc.get("logical", list(LOGICAL_ASSETS))
    if not isinstance(logical, list) or not all(isinstance(a, str) for a in logical):
        raise InputError(f"floor {name}: logical must be a list of asset ids")
    bind = doc.get("bind", {})
    if not isinstance(bind, dict) or not all(isinstance(v, str) for v in bind.values()):
        raise InputError(f"floor {name}: [bind] must map an asset id to \"ADDRESS[:PORT]\"")
    return FloorSpec(name, size_m, tuple(stations), tuple(modules), tuple(objects),
                     tuple(logical), _operation(doc.get("operation", {}), name),
                     tuple(bind.items()))  # fmt: skip


def _own_class(t: dict, where: str, spec: type[StationSpec | ModuleSpec]) -> dict:
    """A station's or module's ``class``, ``capabilities`` and ``[constraints]`` (each
    optional: the generic class's by default) as keyword arguments of `spec`."""
    out: dict = {}
    if "class" in t:
        cls = t["class"]
        if not isinstance(cls, str) or not cls.replace("_", "").isalnum():
            raise InputError(f"{where}: class must be letters, digits or '_', got {cls!r}")
        out["asset_class"] = cls
    if "capabilities" in t:
        caps = t["capabilities"]
        known = [c.value for c in Capability]
        if not isinstance(caps, list) or not all(c in known for c in caps):
            raise InputError(f"{where}: capabilities must be a list of {', '.join(known)}; "
                             f"got {caps!r}")  # fmt: skip
        out["capabilities"] = tuple(Capability(c) for c in caps)
    if "constraints" in t:
        table = t["constraints"]
        ok = isinstance(table, dict) and all(
            isinstance(v, str) or (isinstance(v, int | float) and not isinstance(v, bool))
            for v in table.values())  # fmt: skip
        if not ok:
            raise InputError(f"{where}: [constraints] must map a constraint's idShort to a "
                             "number or a text, e.g. ObjectMassMax = 3.0")  # fmt: skip
        out["constraints"] = tuple((k, v if isinstance(v, str) else float(v))
                                   for k, v in table.items())  # fmt: skip
    return out


def _operation(table: object, name: str) -> OperationSpec:
    where = f"floor {name}: [operation]"
    if not isinstance(table, dict):
        raise InputError(f"{where} must be a table")
    known = {"policy", "study", "runs", "groups", "capacity", "sensor", "learn", "twin",
             "sampling"}
    if unknown := sorted(set(table) - known):
        raise InputError(f"{where}: unknown key {unknown[0]!r}; known: {', '.join(sorted(known))}")
    study = table.get("study")
    if study is not None and (not isinstance(study, str) or not study):
        raise InputError(f"{where}: study must be the path of a study store")
    runs, capacity = table.get("runs", 4), table.get("capacity", 0)
    for key, value in (("runs", runs), ("capacity", capacity)):
        if isinstance(value, bool) or not isinstance(value, int):
            raise InputError(f"{where}: {key} must be an integer, got {value!r}")
    groups = table.get("groups", {})
    if not isinstance(groups, dict) or not all(
            isinstance(v, list) and all(isinstance(u, str) for u in v) for v in groups.values()):
        raise InputError(f"{where}: groups must map a name to a list of unit ids")  # fmt: skip
    learn, twin = table.get("learn", True), table.get("twin", True)
    for key, value in (("learn", learn), ("twin", twin)):
        if not isinstance(value, bool):
            raise InputError(f"{where}: {key} must be true or false, got {value!r}")
    return OperationSpec(str(table.get("policy", "predictive")), study, runs,
                         tuple((g, tuple(u)) for g, u in groups.items()), capacity,
                         str(table.get("sensor", "truth")), learn, twin,
                         str(table.get("sampling", "adaptive")))  # fmt: skip


def load_floor(path: Path | str, *, check_cores: bool = True) -> FloorSpec:
    """Read a floor file; one `InputError` line for a missing, unreadable or invalid file.

    Args:
        path: The floor file.
        check_cores: Also check that every object is a built-in core (imports the mesh
            library; an asset process whose launcher checked it skips this).
    """
    path = Path(path)
    doc = read_toml(path, missing="no such floor file",
                    unreadable="not a readable TOML floor file")  # fmt: skip
    spec = parse_floor(doc, path.stem)
    study = spec.operation.study
    if study is not None and not Path(study).is_absolute():  # relative to the floor file
        op = replace(spec.operation, study=str((path.parent / study).resolve()))
        spec = replace(spec, operation=op)
    if not check_cores:
        return spec
    from transfertwin.objects import builtin_ids

    cores = set(builtin_ids())
    for obj, _ in spec.objects:
        if obj not in cores:
            raise InputError(f"{path}: object {obj!r} is not a built-in core (o1..o37)")
    return spec


def floor_toml(floor: FloorSpec) -> str:
    """`floor` as a floor file (what `load_floor` reads back to an equal `FloorSpec`)."""
    lines = [f"name = {json.dumps(floor.name)}",
             f"size_m = [{floor.size_m[0]!r}, {floor.size_m[1]!r}]",
             f"logical = [{', '.join(json.dumps(a) for a in floor.logical)}]"]  # fmt: skip
    for s in floor.stations:
        lines += ["", "[[station]]", f"name = {json.dumps(s.name)}", f"x_m = {s.x_m!r}",
                  f"y_m = {s.y_m!r}", f"yaw_deg = {s.yaw_deg!r}",
                  f"mount = {json.dumps(s.mount)}"]  # fmt: skip
        if s.hal != "virtual":
            lines.append(f"hal = {json.dumps(s.hal)}")
        if s.gateway is not None:
            lines.append(f"gateway = {json.dumps(s.gateway)}")
        lines += _own_class_lines(s, StationSpec(s.name, 0.0, 0.0, 0.0, "left"), "station")
    for m in floor.modules:
        lines += ["", "[[module]]", f"id = {json.dumps(m.asset_id)}", f"x_m = {m.x_m!r}",
                  f"y_m = {m.y_m!r}", f"theta_deg = {m.theta_deg!r}",
                  f"standby = {'true' if m.standby else 'false'}"]  # fmt: skip
        if m.hal != "virtual":
            lines.append(f"hal = {json.dumps(m.hal)}")
        if m.gateway is not None:
            lines.append(f"gateway = {json.dumps(m.gateway)}")
        lines += _own_class_lines(m, ModuleSpec(m.asset_id, 0.0, 0.0), "module")
    for obj, at in floor.objects:
        lines += ["", "[[object]]", f"id = {json.dumps(obj)}", f"at = {json.dumps(at)}"]
    op = floor.operation
    lines += ["", "[operation]", f"policy = {json.dumps(op.policy)}", f"runs = {op.runs}",
              f"capacity = {op.capacity}", f"sensor = {json.dumps(op.sensor)}",
              f"learn = {'true' if op.learn else 'false'}",
              f"twin = {'true' if op.twin else 'false'}",
              f"sampling = {json.dumps(op.sampling)}"]
    if op.study is not None:
        lines.append(f"study = {json.dumps(op.study)}")
    if op.groups:
        lines += ["", "[operation.groups]"]
        lines += [f"{json.dumps(g)} = [{', '.join(json.dumps(u) for u in units)}]"
                  for g, units in op.groups]  # fmt: skip
    if floor.bind:
        lines += ["", "[bind]", *(f"{json.dumps(a)} = {json.dumps(v)}" for a, v in floor.bind)]
    return "\n".join(lines) + "\n"


def _own_class_lines(spec: StationSpec | ModuleSpec, default: StationSpec | ModuleSpec,
                     table: str) -> list[str]:  # fmt: skip
    """The ``class``, ``capabilities`` and ``[<table>.constraints]`` lines of a station or
    module whose differ from the generic class's (`default`)."""
    lines = []
    if spec.asset_class != default.asset_class:
        lines.append(f"class = {json.dumps(spec.asset_class)}")
    if spec.capabilities != default.capabilities:
        caps = ", ".join(json.dumps(c.value) for c in spec.capabilities)
        lines.append(f"capabilities = [{caps}]")
    if spec.constraints:
        lines += ["", f"[{table}.constraints]"]
        lines += [f"{k} = {json.dumps(v) if isinstance(v, str) else repr(v)}"
                  for k, v in spec.constraints]  # fmt: skip
    return lines
