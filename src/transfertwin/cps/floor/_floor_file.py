"""A shop floor as a file: stations, transport modules, objects, logical assets (Ch. 3).

A floor file (TOML) names every asset of one floor and where it stands, so that a launcher
can start one process per asset and any asset can be restarted by hand from its own
bundle ``assets/<id>/``. ``examples/floor-demo.toml`` is the demonstration floor of Sec. 5.3;
``examples/floor-large.toml`` has 3 modules, 8 units and 20 objects.

```toml
name = "demo"
size_m = [12.0, 8.0]                      # optional; walls around it
hal = "virtual"                           # optional: every unit's and module's HAL
                                          # (virtual | plant: needs cps up --plant-seed)

[[station]]                               # a station with its transfer unit TU_<name>
name = "A"
x_m = 2.6                                 # centre of the station's front face, m
y_m = 6.6
yaw_deg = 90                              # inward normal of the face (docked heading)
mount = "left"                            # mounting side of the unit (Fig. 5.16)
# class = "buffer_station"                # optional: a class of its own (see below)
hal = "remote"                            # optional: this unit's HAL (virtual|plant|remote)
gateway = "opc.tcp://192.168.10.21:4840"  # remote: its HAL gateway (OPC UA)

[[module]]                                # a transport module and its start pose
id = "TM_1"
x_m = 6.0
y_m = 5.2
theta_deg = 0
standby = false                           # true: prepared, started later by hand
hal = "plant"                             # optional: virtual | plant | remote
# gateway = "opc.tcp://192.168.10.31:4840"  # remote: its HAL gateway (OPC UA)
class = "light_transport_module"          # optional: a make of its own; what it runs as
capabilities = ["transport", "transfer", "sense"]  # follows from what it offers (these,
                                          # the default: a transport module's role)
[module.constraints]                      # optional: its own bounds of those capabilities,
ObjectMassMax = 3.0                       # by the constraint's idShort in its AAS (kg)

[[object]]                                # a built-in core id, and the unit it lies on
id = "o5"
at = "TU_A"

logical = ["TMS", "EM", "PropS", "KG"]    # optional; these four by default

[operation]                               # optional: how the TMS schedules (docs: Operation)
policy = "predictive"                     # the default; or "nearest-idle"
study = "out/quick.sqlite"                # a study store with the twin's per-state shares
runs = 4                                  # runs per state of on-the-fly virtual experiments
sampling = "adaptive"                     # the default: at most 28 x runs experiments in
                                          # all, where they can change the best state; or
                                          # "exhaustive": every state `runs` times
capacity = 1                              # objects a unit may hold (0, the default: no limit)
sensor = "camera"                         # the module's depth camera forms the OTS and feeds
                                          # the delivery's controller ("truth": the default)
learn = true                              # predictive: the floor's own outcomes update the
                                          # twin's shares (the default; false: the twin alone)
twin = true                               # predictive: rank with the twin's shares as the
                                          # prior (the default; false: learning alone, the
                                          # benchmark's baseline: every state from a flat prior)

[operation.groups]                        # destinations with a choice of unit
inspection = ["TU_C", "TU_D"]

[bind]                                    # optional: an asset on a host of its own
KG = "198.18.0.2"                         # listens on its host's address (port 4840; the
TU_A = "198.18.0.3:4841"                  # next free one for a second asset there), with
                                          # security always; the rest on loopback
```

Parsing happens here, at the edge; the rest of the runtime sees the frozen `FloorSpec`.
"""

from __future__ import annotations

import ipaddress
import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from transfertwin._errors import InputError
from transfertwin.cps.aas import (
    CAPABILITY_SPECS,
    DEMO_PLACEMENT,
    AssetDescriptor,
    AssetKind,
    Capability,
    PhysicalType,
    capability_specs,
    physical_twin,
)

if TYPE_CHECKING:
    from transfertwin.navigation import ShopFloor

__all__ = [
    "LOGICAL_ASSETS",
    "FloorSpec",
    "ModuleSpec",
    "OperationSpec",
    "StationSpec",
    "default_floor_spec",
]

#: The logical assets a floor may run, by id: (class, capability).
LOGICAL_ASSETS = {
    "TMS": ("transport_module_system", Capability.ALLOCATE),
    "EM": ("experiment_manager", Capability.EXPERIMENT),
    "PropS": ("props", Capability.FUSE_POSES),
    "KG": ("knowledge_graph", Capability.KNOWLEDGE),
}

#: The TMS's scheduling policies (docs/architecture.md, "Operation").
POLICIES = ("nearest-idle", "predictive")
#: What the transport modules see objects with: the simulation's truth, or their camera.
SENSORS = ("truth", "camera")
#: How the Experiment Manager samples an on-the-fly prediction's states: every state
#: ``runs`` times, or adaptively (runs where they can change the best state, at most as many
#: in all; `cps.dispatch.virtual_predictions`).
SAMPLINGS = ("exhaustive", "adaptive")

_TU_CAPS = (Capability.TRANSFER, Capability.SENSE)
_TM_CAPS = (Capability.TRANSPORT, Capability.TRANSFER, Capability.SENSE)


@dataclass(frozen=True)
class StationSpec:
    """A station module on the floor; its transfer unit is ``TU_<name>``."""

    name: str
    x_m: float
    y_m: float
    yaw_deg: float
    mount: str
    hal: str = "virtual"
    gateway: str | None = None
    asset_class: str = "transfer_unit"
    capabilities: tuple[Capability, ...] = _TU_CAPS
    constraints: tuple[tuple[str, float | str], ...] = ()

    @property
    def unit(self) -> str:
        """Id of the station's transfer unit."""
        return f"TU_{self.name}"


@dataclass(frozen=True)
class ModuleSpec:
    """A transport module and its start pose (x m, y m, θ deg)."""

    asset_id: str
    x_m: float
    y_m: float
    theta_deg: float = 0.0
    standby: bool = False
    hal: str = "virtual"
    gateway: str | None = None
    asset_class: str = "transport_module"
    capabilities: tuple[Capability, ...] = _TM_CAPS
    constraints: tuple[tuple[str, float | str], ...] = ()

    @property
    def home(self) -> tuple[float, float, float]:
        """Start pose (x m, y m, θ rad)."""
        return (self.x_m, self.y_m, math.radians(self.theta_deg))


@dataclass(frozen=True)
class OperationSpec:
    """How the TMS runs orders: its policy, where the twin's predictions come from, and
    the destinations that name a group of units (group -> units)."""

    policy: str = "predictive"
    study: str | None = None
    runs: int = 4
    groups: tuple[tuple[str, tuple[str, ...]], ...] = ()
    capacity: int = 0
    sensor: str = "truth"
    learn: bool = True
    twin: bool = True
    sampling: str = "adaptive"

    def group(self, name: str) -> tuple[str, ...] | None:
        """The units of destination group `name` (None: no such group)."""
        return dict(self.groups).get(name)


@dataclass(frozen=True)
class FloorSpec:
    """One shop floor: its size, stations, modules, objects (id -> unit) and logical assets."""

    name: str
    size_m: tuple[float, float]
    stations: tuple[StationSpec, ...]
    modules: tuple[ModuleSpec, ...]
    objects: tuple[tuple[str, str], ...]
    logical: tuple[str, ...] = tuple(LOGICAL_ASSETS)
    operation: OperationSpec = OperationSpec()
    #: (asset id, ``"ADDRESS"`` or ``"ADDRESS:PORT"``): where an asset listens when it runs
    #: on a host of its own (the floor file's ``[bind]``); the others get loopback addresses.
    bind: tuple[tuple[str, str], ...] = ()

    def __post_init__(self) -> None:
        _check(self)

    def bind_address(self, asset_id: str) -> tuple[str, int | None] | None:
        """(address, port or None) the floor file binds `asset_id` to; None: loopback."""
        value = dict(self.bind).get(asset_id)
        if value is None:
            return None
        host, _, port = value.partition(":")
        return host, int(port) if port else None

    @property
    def units(self) -> tuple[str, ...]:
        """Ids of the transfer units, in station order."""
        return tuple(s.unit for s in self.stations)

    def placement(self) -> dict[str, str]:
        """Object id -> the unit it lies on when the floor starts."""
        return dict(self.objects)

    def module(self, asset_id: str) -> ModuleSpec:
        """The module called `asset_id`."""
        for m in self.modules:
            if m.asset_id == asset_id:
                return m
        raise InputError(f"floor {self.name}: no transport module {asset_id!r}")

    def descriptors(self) -> tuple[AssetDescriptor, ...]:
        """Every asset of the floor: units, modules, objects, logical assets, and the
        physical twins of the units on the emulated plant (``TU_<name>_P``, kind physical:
        the plant's own units, beside their virtual models), in that order."""
        units = tuple(
            _virtual(s.unit, s.asset_class, PhysicalType.D_E, s.capabilities, s.name,
                     s.constraints)
            for s in self.stations
        )  # fmt: skip
        modules = tuple(
            _virtual(m.asset_id, m.asset_class, PhysicalType.E, m.capabilities,
                     constraints=m.constraints)
            for m in self.modules
        )  # fmt: skip
        objects = tuple(_virtual(o, "object", PhysicalType.B) for o, _ in self.objects)
        logical = tuple(
            AssetDescriptor(aid, AssetKind.LOGICAL, LOGICAL_ASSETS[aid][0],
                            capabilities=(LOGICAL_ASSETS[aid][1],))
            for aid in self.logical
        )
        plant = tuple(physical_twin(u) for u, s in zip(units, self.stations, strict=True)
                      if s.hal == "plant")  # fmt: skip
        return (*units, *modules, *objects, *logical, *plant)

    def hal_of(self, asset_id: str) -> tuple[str, str | None]:
        """(HAL kind, gateway endpoint or None) of a unit or module; virtual otherwise."""
        for s in self.stations:
            if s.unit == asset_id:
                return s.hal, s.gateway
            if s.hal == "plant" and asset_id == f"{s.unit}_P":
                return "plant", None
        for m in self.modules:
            if m.asset_id == asset_id:
                return m.hal, m.gateway
        return "virtual", None

    def with_hal(self, kind: str) -> FloorSpec:
        """This floor with every virtual unit and module on HAL `kind` (remote units and
        modules keep theirs)."""

        stations = tuple(s if s.hal == "remote" else replace(s, hal=kind) for s in self.stations)
        modules = tuple(m if m.hal == "remote" else replace(m, hal=kind) for m in self.modules)
        return replace(self, stations=stations, modules=modules)

    def uses_plant(self) -> bool:
        """Whether any asset runs on the emulated plant."""
        return any(s.hal == "plant" for s in self.stations) or any(
            m.hal == "plant" for m in self.modules)

    def standby(self) -> frozenset[str]:
        """Ids of the assets prepared but not started by the launcher."""
        return frozenset(m.asset_id for m in self.modules if m.standby)

    def shop_floor(self) -> ShopFloor:
        """The navigation floor: walls around `size_m` and the stations (the default floor's
        obstacles too when the stations are the default ones)."""
        from transfertwin.navigation import Rect, ShopFloor, Station, default_floor

        def wall(x0: float, y0: float, x1: float, y1: float) -> Rect:
            return Rect((x0 + x1) / 2, (y0 + y1) / 2, x1 - x0, y1 - y0, 0.0, "wall")

        base = default_floor()
        goal = {s.mount: s.goal_in_edge for s in base.stations}
        stations = tuple(
            Station(s.name, s.x_m, s.y_m, math.radians(s.yaw_deg), s.mount,
                    goal_in_edge=goal[s.mount])
            for s in self.stations
        )
        if stations == base.stations and self.size_m == base.size_m:
            return base
        w, h, t = self.size_m[0], self.size_m[1], 0.1
        walls = (wall(0.0, 0.0, w, t), wall(0.0, h - t, w, h), wall(0.0, 0.0, t, h),
                 wall(w - t, 0.0, w, h))  # fmt: skip
        return ShopFloor(self.size_m, walls, stations)


def _virtual(aid: str, cls: str, ptype: PhysicalType, caps: tuple[Capability, ...] = (),
             station: str | None = None,
             constraints: tuple[tuple[str, float | str], ...] = ()) -> AssetDescriptor:  # fmt: skip
    """A virtual model; each of `constraints` (idShort, value) binds every capability of the
    asset that has that constraint (`CAPABILITY_SPECS` of its generic class)."""
    desc = AssetDescriptor(aid, AssetKind.VIRTUAL_MODEL, cls, physical_type=ptype,
                           capabilities=caps, station=station,
                           models=f"{aid}_P")  # fmt: skip
    if not constraints:
        return desc
    specs = CAPABILITY_SPECS.get(desc.role_class, {})
    bound = []
    for name, value in constraints:
        caps_with = [c for c in caps if c.value in specs
                     and any(k.id_short == name for k in specs[c.value].constraints)]  # fmt: skip
        if not caps_with:
            raise InputError(f"{aid}: no capability of it has the constraint {name!r}")
        bound += [(c, name, value) for c in caps_with]
    return replace(desc, constraints=tuple(bound))


def _check(floor: FloorSpec) -> None:
    """Refuse a floor whose ids repeat, whose objects lie on no unit, or that lacks a
    knowledge graph or a TMS (InputError naming the floor and the first problem)."""
    where = f"floor {floor.name}"
    ids = [*floor.units, *(m.asset_id for m in floor.modules),
           *(o for o, _ in floor.objects), *floor.logical]  # fmt: skip
    seen: set[str] = set()
    for aid in ids:
        if aid in seen:
            raise InputError(f"{where}: asset id {aid!r} appears twice")
        seen.add(aid)
    for s in floor.stations:
        if s.mount not in ("left", "right"):
            raise InputError(f"{where}: station {s.name}: mount must be left or right, "
                             f"got {s.mount!r}")  # fmt: skip
    for s in floor.stations:
        if s.hal not in ("virtual", "plant", "remote"):
            raise InputError(f"{where}: station {s.name}: hal must be virtual, plant or remote, "
                             f"got {s.hal!r}")  # fmt: skip
        if (s.hal == "remote") != (s.gateway is not None):
            raise InputError(f"{where}: station {s.name}: a remote HAL needs gateway = "
                             "\"opc.tcp://HOST:PORT\" (and only a remote one has it)")  # fmt: skip
        if s.gateway is not None and not s.gateway.startswith("opc.tcp://"):
            raise InputError(f"{where}: station {s.name}: gateway must be an opc.tcp:// URL")
    for m in floor.modules:
        if m.hal not in ("virtual", "plant", "remote"):
            raise InputError(f"{where}: module {m.asset_id}: hal must be virtual, plant or "
                             f"remote, got {m.hal!r}")  # fmt: skip
        if (m.hal == "remote") != (m.gateway is not None) or not \
                (m.gateway or "opc.tcp://").startswith("opc.tcp://"):
            raise InputError(f"{where}: module {m.asset_id}: a remote HAL needs gateway = "
                             "\"opc.tcp://HOST:PORT\" (and only a remote one has it)")  # fmt: skip
    for obj, at in floor.objects:
        if at not in floor.units:
            raise InputError(f"{where}: object {obj} lies on {at!r}, which is no transfer unit "
                             f"of the floor ({', '.join(floor.units)})")  # fmt: skip
    for aid in floor.logical:
        if aid not in LOGICAL_ASSETS:
            raise InputError(f"{where}: unknown logical asset {aid!r}; "
                             f"known: {', '.join(LOGICAL_ASSETS)}")  # fmt: skip
    try:  # a class of its own: what it runs as (`role_class`), and its bounds
        for d in floor.descriptors():
            capability_specs(d)
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None
    for need in ("KG", "TMS"):
        if need not in floor.logical:
            raise InputError(f"{where}: a floor needs the logical asset {need}")
    if not floor.modules:
        raise InputError(f"{where}: no transport module")
    if len(floor.size_m) != 2 or min(floor.size_m) <= 0:
        raise InputError(f"{where}: size_m must be two positive lengths")
    op = floor.operation
    if op.policy not in POLICIES:
        raise InputError(f"{where}: operation.policy must be one of {', '.join(POLICIES)}, "
                         f"got {op.policy!r}")  # fmt: skip
    if not 1 <= op.runs <= 1000:
        raise InputError(f"{where}: operation.runs must be 1..1000, got {op.runs}")
    if op.capacity < 0:
        raise InputError(f"{where}: operation.capacity must be >= 0, got {op.capacity}")
    if not (op.twin or op.learn):
        raise InputError(f"{where}: operation.twin = false needs learn = true (without the "
                         "twin and without learning nothing ranks the states)")  # fmt: skip
    if op.sensor not in SENSORS:
        raise InputError(f"{where}: operation.sensor must be one of {', '.join(SENSORS)}, "
                         f"got {op.sensor!r}")  # fmt: skip
    if op.sampling not in SAMPLINGS:
        raise InputError(f"{where}: operation.sampling must be one of {', '.join(SAMPLINGS)}, "
                         f"got {op.sampling!r}")  # fmt: skip
    _check_bind(floor, where)
    for group, units in op.groups:
        if group in floor.units or group in seen:
            raise InputError(f"{where}: destination group {group!r} is also an asset id")
        if not units or any(u not in floor.units for u in units):
            raise InputError(f"{where}: destination group {group!r} must list transfer units "
                             f"of the floor, got {list(units)}")  # fmt: skip


def _check_bind(floor: FloorSpec, where: str) -> None:
    """Each ``[bind]`` entry names an asset of the floor and an IP address (an optional
    port 1..65535); no two assets share an address and port."""
    ids = {d.asset_id for d in floor.descriptors()}
    taken: set[tuple[str, int]] = set()
    for aid, value in floor.bind:
        if aid not in ids:
            raise InputError(f"{where}: [bind] {aid}: no such asset on the floor")
        if not isinstance(value, str) or value.count(":") > 1:
            raise InputError(f"{where}: [bind] {aid} must be \"ADDRESS\" or \"ADDRESS:PORT\" "
                             f"(IPv4), got {value!r}")  # fmt: skip
        host, _, port = value.partition(":")
        try:
            ipaddress.IPv4Address(host)
        except ValueError:
            raise InputError(f"{where}: [bind] {aid}: {host!r} is not an IPv4 address") from None
        if port and not (port.isdigit() and 0 < int(port) < 65536):
            raise InputError(f"{where}: [bind] {aid}: port must be 1..65535, got {port!r}")
        if port and (host, int(port)) in taken:
            raise InputError(f"{where}: [bind] {aid}: {value} is another asset's too")
        if port:
            taken.add((host, int(port)))


def default_floor_spec() -> FloorSpec:
    """The demonstration floor (Sec. 5.3): stations A–D of `navigation.default_floor` with
    TU_A…TU_D, TM_1 at the home pose, o1…o5 as `DEMO_PLACEMENT`, the four logical assets."""
    from transfertwin.cps.apps import HOME_POSE  # the navigation stack: not for every asset
    from transfertwin.navigation import default_floor

    base = default_floor()
    stations = tuple(
        StationSpec(s.name, s.face_x_m, s.face_y_m, math.degrees(s.yaw_rad), s.mount)
        for s in base.stations
    )
    x, y, th = HOME_POSE
    module = ModuleSpec("TM_1", x, y, math.degrees(th))
    return FloorSpec("demo", base.size_m, stations, (module,), tuple(DEMO_PLACEMENT.items()))
