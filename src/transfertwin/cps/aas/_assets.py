"""The asset model of the DT architecture (Ch. 3, Table 3.1, Fig. 3.2, Sec. 5.1–5.3).

Physical assets, logical assets and virtual models (a subset of the logical assets) stand
side by side; none is above another. A physical asset is of one of five types A–E by what
it can do itself: have a representation, synchronise its internal and external state, and
offer a control interface. Every asset is layered: hardware abstraction, control,
application.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

from transfertwin._errors import InputError

__all__ = [
    "GENERIC_CLASSES",
    "TYPE_PROPERTIES",
    "AssetDescriptor",
    "AssetKind",
    "Capability",
    "Layer",
    "PhysicalType",
]


class AssetKind(Enum):
    """Where an asset lives (Ch. 3)."""

    PHYSICAL = "physical"
    LOGICAL = "logical"
    VIRTUAL_MODEL = "virtual_model"  # a logical asset that models a physical one


class PhysicalType(Enum):
    """The five physical asset types of Table 3.1, plus the mixed type of Sec. 5.1.1."""

    A = "A"
    B = "B"
    C = "C"
    D = "D"
    E = "E"
    D_E = "D/E"


@dataclass(frozen=True)
class TypeProperties:
    """How an asset of a physical type relates to its virtual representation (Table 3.1).

    Attributes:
        representation: Has a virtual representation.
        sync: Who keeps its dynamic state current: 'internal' (the asset itself),
            'external' (other assets), 'mixed' (part of each), or None.
        control_interface: Offers an external control interface.
    """

    representation: bool
    sync: str | None
    control_interface: bool


# Table 3.1; D/E is the transfer unit of Sec. 5.1.1: it updates its belt speeds itself but
# others must tell it whether an object lies on its belts.
TYPE_PROPERTIES: dict[PhysicalType, TypeProperties] = {
    PhysicalType.A: TypeProperties(False, None, False),
    PhysicalType.B: TypeProperties(True, "external", False),
    PhysicalType.C: TypeProperties(True, "internal", False),
    PhysicalType.D: TypeProperties(True, "external", True),
    PhysicalType.D_E: TypeProperties(True, "mixed", True),
    PhysicalType.E: TypeProperties(True, "internal", True),
}


class Capability(Enum):
    """What an asset offers to others."""

    TRANSFER = "transfer"  # hand objects over to / take them from a docked partner
    TRANSPORT = "transport"  # move objects between stations
    SENSE = "sense"  # observe objects (camera, light barriers)
    ALLOCATE = "allocate"  # accept transport operations and allocate them
    EXPERIMENT = "experiment"  # plan and run transfer experiments
    FUSE_POSES = "fuse_poses"  # pose-graph estimation
    KNOWLEDGE = "knowledge"  # answer queries over the knowledge graph


#: The generic asset classes the code knows, by the capabilities an asset must offer to
#: run as one (the first that fits wins). An asset of a class the code has never seen
#: (a second make of transport module, a buffer station) runs as the generic class its
#: capabilities name (`AssetDescriptor.role_class`); it must offer some (an object is of
#: the class ``object``).
GENERIC_CLASSES: tuple[tuple[str, frozenset[Capability]], ...] = (
    ("knowledge_graph", frozenset({Capability.KNOWLEDGE})),
    ("transport_module_system", frozenset({Capability.ALLOCATE})),
    ("experiment_manager", frozenset({Capability.EXPERIMENT})),
    ("props", frozenset({Capability.FUSE_POSES})),
    ("transport_module", frozenset({Capability.TRANSPORT, Capability.TRANSFER})),
    ("transfer_unit", frozenset({Capability.TRANSFER})),
    ("object", frozenset()),
)
_GENERIC_NAMES = frozenset(name for name, _ in GENERIC_CLASSES)


class Layer(Enum):
    """The layers of an asset (Fig. 3.2); only HAL differs between a physical asset and
    its virtual model."""

    HAL = "hal"
    CONTROL = "control"
    APPLICATION = "application"


@dataclass(frozen=True)
class AssetDescriptor:
    """Identity and classification of one asset.

    Attributes:
        asset_id: Unique id, e.g. 'TU_A', 'TM_1', 'o5', 'TMS'.
        kind: Physical, logical or virtual model.
        asset_class: 'transfer_unit', 'transport_module', 'object', or a logical asset's
            class ('transport_module_system', 'experiment_manager', 'props',
            'knowledge_graph').
        physical_type: Table 3.1 type for physical assets and the virtual models of them.
        capabilities: What it offers.
        station: Station it belongs to (transfer units), if any.
        models: For a virtual model: the id of the physical asset it mirrors.
        constraints: What binds its capabilities where it differs from its generic class's
            (`CAPABILITY_SPECS`), as (capability, constraint idShort, value), e.g.
            ``(Capability.TRANSPORT, "ObjectMassMax", 3.0)`` for a module that carries
            objects of at most 3 kg.
    """

    asset_id: str
    kind: AssetKind
    asset_class: str
    physical_type: PhysicalType | None = None
    capabilities: tuple[Capability, ...] = ()
    station: str | None = None
    models: str | None = None
    extra: dict[str, str] = field(default_factory=dict)
    constraints: tuple[tuple[Capability, str, float | str], ...] = ()

    def __post_init__(self) -> None:
        if not self.asset_id or not self.asset_id.replace("_", "").isalnum():
            raise InputError(f"asset id must be alphanumeric/underscore, got {self.asset_id!r}")
        if self.kind is AssetKind.LOGICAL and self.physical_type is not None:
            raise InputError(f"{self.asset_id}: a logical asset has no physical type")
        if self.kind is not AssetKind.LOGICAL and self.physical_type is None:
            raise InputError(f"{self.asset_id}: physical assets and virtual models need a type")
        if self.kind is AssetKind.VIRTUAL_MODEL and not self.models:
            raise InputError(f"{self.asset_id}: a virtual model must name the asset it models")

    @property
    def role_class(self) -> str:
        """The generic class it runs as: its own class if the code knows it, else the first
        of `GENERIC_CLASSES` whose capabilities it offers (a transfer unit: at a station).

        Raises:
            InputError: A class the code does not know whose capabilities name none.
        """
        if self.asset_class in _GENERIC_NAMES:
            return self.asset_class
        offered = set(self.capabilities)
        for name, needs in GENERIC_CLASSES:
            if name == "transfer_unit" and self.station is None:
                continue
            if needs and needs <= offered:
                return name
        raise InputError(
            f"{self.asset_id}: asset class {self.asset_class!r} is unknown and its capabilities "
            f"({', '.join(c.value for c in self.capabilities) or 'none'}) name no generic "
            f"class ({', '.join(n for n, _ in GENERIC_CLASSES)}); a transfer unit needs a station"
        )

    @property
    def properties(self) -> TypeProperties | None:
        """Table 3.1 properties of its physical type."""
        return TYPE_PROPERTIES[self.physical_type] if self.physical_type else None
