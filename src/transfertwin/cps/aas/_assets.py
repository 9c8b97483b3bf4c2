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
    """

    asset_id: str
    kind: AssetKind
    asset_class: str
    physical_type: PhysicalType | None = None
    capabilities: tuple[Capability, ...] = ()
    station: str | None = None
    models: str | None = None
    extra: dict[str, str] = field(default_factory=dict)

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
    def properties(self) -> TypeProperties | None:
        """Table 3.1 properties of its physical type."""
        return TYPE_PROPERTIES[self.physical_type] if self.physical_type else None
