"""The assets of the demonstration CPS (Sec. 5.3, Fig. 5.8), all run as software here.

Naming follows the thesis' superscripts: the virtual models keep the plain ids
(``TU_A``…``TU_D``, ``TM_1``, ``o1``…``o5``) and each names its physical twin with the
suffix ``_P`` (``TU_A_P``, Eq. 5.1–5.3), which is absent from the demo but is the id a
physical deployment would use. The logical assets are ``TMS``, ``EM``, ``PropS`` and ``KG``.
"""

from __future__ import annotations

from dataclasses import replace

from transfertwin._errors import InputError
from transfertwin.cps.aas._assets import AssetDescriptor, AssetKind, Capability, PhysicalType

__all__ = ["DEMO_OBJECTS", "DEMO_PLACEMENT", "DEMO_STATIONS", "demo_descriptors", "physical_twin"]

DEMO_STATIONS = ("A", "B", "C", "D")
DEMO_OBJECTS = ("o1", "o2", "o3", "o4", "o5")
# Where the objects lie when the demo starts: in turn on TU_A, TU_B, TU_C, TU_D, TU_A.
DEMO_PLACEMENT = {
    o: f"TU_{DEMO_STATIONS[i % len(DEMO_STATIONS)]}" for i, o in enumerate(DEMO_OBJECTS)
}
PHYSICAL_SUFFIX = "_P"

_TU_CAPS = (Capability.TRANSFER, Capability.SENSE)
_TM_CAPS = (Capability.TRANSPORT, Capability.TRANSFER, Capability.SENSE)
_LOGICAL = (
    ("TMS", "transport_module_system", Capability.ALLOCATE),
    ("EM", "experiment_manager", Capability.EXPERIMENT),
    ("PropS", "props", Capability.FUSE_POSES),
    ("KG", "knowledge_graph", Capability.KNOWLEDGE),
)


def _virtual(
    asset_id: str,
    asset_class: str,
    ptype: PhysicalType,
    caps: tuple[Capability, ...] = (),
    station: str | None = None,
) -> AssetDescriptor:
    return AssetDescriptor(
        asset_id,
        AssetKind.VIRTUAL_MODEL,
        asset_class,
        physical_type=ptype,
        capabilities=caps,
        station=station,
        models=f"{asset_id}{PHYSICAL_SUFFIX}",
    )


def demo_descriptors() -> tuple[AssetDescriptor, ...]:
    """The demo CPS: 4 virtual transfer units (type D/E, Sec. 5.1.1), 1 virtual transport
    module (type E, Sec. 5.1.2), 5 virtual objects (type B, Sec. 5.1.3) and the 4 logical
    assets of Sec. 5.2 (14 assets)."""
    units = tuple(
        _virtual(f"TU_{s}", "transfer_unit", PhysicalType.D_E, _TU_CAPS, station=s)
        for s in DEMO_STATIONS
    )
    module = _virtual("TM_1", "transport_module", PhysicalType.E, _TM_CAPS)
    objects = tuple(_virtual(o, "object", PhysicalType.B) for o in DEMO_OBJECTS)
    logical = tuple(
        AssetDescriptor(aid, AssetKind.LOGICAL, cls, capabilities=(cap,))
        for aid, cls, cap in _LOGICAL
    )
    return (*units, module, *objects, *logical)


def physical_twin(desc: AssetDescriptor) -> AssetDescriptor:
    """The physical asset a virtual model mirrors: same class, type, capabilities and
    station, id `desc.models`, kind PHYSICAL."""
    if desc.kind is not AssetKind.VIRTUAL_MODEL:
        raise InputError(f"{desc.asset_id} is a {desc.kind.value} asset, not a virtual model")
    return replace(
        desc,
        asset_id=str(desc.models),
        kind=AssetKind.PHYSICAL,
        models=None,
        extra=dict(desc.extra),
    )
