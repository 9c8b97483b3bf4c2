"""Virtual representations of assets as Asset Administration Shells (Sec. 3.1–3.2, 5.3).

`build_representation` turns an `AssetDescriptor` into one AAS with up to four submodels:

* ``Identification``: who the asset is and where it lives (Sec. 3.1, the AAS "header").
* ``Capabilities``: one Capability element per `Capability` (semantic ids, Sec. 3.3), and
  beside it ``<name>Relations``: the operations (or properties) that realise it and its
  constraints (the IDTA capability pattern; `CAPABILITY_SPECS`).
* ``OperationalData``: the dynamic state, typed Properties with units (Table 3.1 sync).
* ``ControlInterface``: Operations, only for types D, D/E, E and logical assets (Table 3.1).

A virtual model and its physical twin get the same structure (Sec. 3.2, Fig. 3.3b): only the
provenance elements of Identification differ, which `wire_signature` leaves out.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from basyx.aas import model

from transfertwin._errors import InputError
from transfertwin.cps.aas._assets import AssetDescriptor, AssetKind, Capability, PhysicalType
from transfertwin.cps.aas._elements import (
    SYNC_QUALIFIER,
    asset_iri,
    capability,
    capability_relations,
    operation,
    property_,
    semantic,
    shell_iri,
    submodel_iri,
    text_property,
)
from transfertwin.cps.aas._spec import (
    CONTROL_INTERFACE,
    LOGICAL_CLASSES,
    OPERATIONAL_DATA,
    PHYSICAL_CLASSES,
    capability_specs,
)

__all__ = [
    "PROVENANCE_ELEMENTS",
    "AssetRepresentation",
    "build_representation",
    "capability_id_short",
    "externally_synced",
    "wire_signature",
]

# Identification elements that say where an asset lives and what it mirrors, not what it
# offers: the only place a virtual model may differ from its physical twin (Sec. 3.2).
PROVENANCE_ELEMENTS = frozenset({"Provenance", "ModelOf", "Endpoint"})
_PROVENANCE = {
    AssetKind.PHYSICAL: "physical",
    AssetKind.VIRTUAL_MODEL: "virtual",
    AssetKind.LOGICAL: "logical",
}


@dataclass(frozen=True, eq=False)
class AssetRepresentation:
    """The AAS of one asset: shell plus submodels (basyx objects, built once, not shared).

    Attributes:
        descriptor: The asset it represents.
        shell: The AssetAdministrationShell, referencing every submodel.
        submodels: Identification, Capabilities, OperationalData[, ControlInterface].
    """

    descriptor: AssetDescriptor
    shell: model.AssetAdministrationShell
    submodels: tuple[model.Submodel, ...]

    def object_store(self) -> model.DictIdentifiableStore:
        """A fresh store holding the shell and its submodels (for the basyx adapters)."""
        return model.DictIdentifiableStore([self.shell, *self.submodels])

    def submodel(self, id_short: str) -> model.Submodel:
        """The submodel named `id_short`; InputError if it has none of that name."""
        for sm in self.submodels:
            if sm.id_short == id_short:
                return sm
        names = ", ".join(sm.id_short for sm in self.submodels)
        raise InputError(f"{self.descriptor.asset_id} has no submodel {id_short!r} ({names})")

    def property(self, submodel: str, id_short: str) -> model.Property:
        """The Property `id_short` of a submodel; InputError if absent or not a Property."""
        element = self._element(submodel, id_short)
        if not isinstance(element, model.Property):
            raise InputError(f"{submodel}.{id_short} is a {type(element).__name__}")
        return element

    def operation(self, id_short: str) -> model.Operation:
        """The Operation `id_short` of the ControlInterface submodel."""
        element = self._element("ControlInterface", id_short)
        if not isinstance(element, model.Operation):
            raise InputError(f"ControlInterface.{id_short} is a {type(element).__name__}")
        return element

    def _element(self, submodel: str, id_short: str) -> model.SubmodelElement:
        try:
            return self.submodel(submodel).get_referable(id_short)
        except KeyError:
            raise InputError(
                f"{self.descriptor.asset_id}.{submodel} has no element {id_short!r}"
            ) from None


def capability_id_short(cap: Capability) -> str:
    """idShort of a capability: ``fuse_poses`` → ``FusePoses``."""
    return "".join(part.capitalize() for part in cap.value.split("_"))


def build_representation(
    desc: AssetDescriptor, *, endpoint: str | None = None, provenance: str | None = None
) -> AssetRepresentation:
    """Build the AAS of an asset (Sec. 3.1; Table 3.1 decides sync and control interface).

    Args:
        desc: The asset.
        endpoint: Its OPC UA endpoint URL, recorded as ``Identification.Endpoint``.
        provenance: Free-text origin (e.g. ``'mujoco; calibration run 7'``), recorded as the
            description of ``Identification.Provenance``; that property's value is always
            'physical', 'virtual' or 'logical' from `desc.kind`.

    Raises:
        InputError: Type A asset (no representation, Table 3.1), unknown asset class, a
            class that does not fit the kind, or an asset id that is no valid idShort.
    """
    _check(desc)
    sync = desc.properties.sync if desc.properties else None
    data = _submodel(desc.asset_id, "OperationalData", _operational_data(desc.role_class, sync))
    control = None
    if desc.kind is AssetKind.LOGICAL or (desc.properties and desc.properties.control_interface):
        ops = [
            operation(spec)
            for spec in CONTROL_INTERFACE[desc.role_class]
            if not spec.external_sync or sync in ("external", "mixed")
        ]
        control = _submodel(desc.asset_id, "ControlInterface", ops)
    targets = {
        (sm.id_short, el.id_short): type(el)
        for sm in (data, control)
        if sm is not None
        for el in sm.submodel_element
    }
    submodels = [
        _submodel(desc.asset_id, "Identification", _identification(desc, endpoint, provenance)),
        _submodel(desc.asset_id, "Capabilities", _capabilities(desc, targets)),
        data,
        *([control] if control is not None else []),
    ]
    shell = model.AssetAdministrationShell(
        model.AssetInformation(model.AssetKind.INSTANCE, global_asset_id=asset_iri(desc.asset_id)),
        shell_iri(desc.asset_id),
        id_short=desc.asset_id,
        submodel={model.ModelReference.from_referable(sm) for sm in submodels},
    )
    return AssetRepresentation(desc, shell, tuple(submodels))


def _capabilities(
    desc: AssetDescriptor, targets: dict[tuple[str, str], type[model.SubmodelElement]]
) -> list[model.SubmodelElement]:
    """Per capability its Capability element and, where its class says how it is realised
    (`CAPABILITY_SPECS`, with the asset's own constraint values: `capability_specs`), its
    ``<name>Relations`` collection."""
    elements: list[model.SubmodelElement] = []
    specs = capability_specs(desc)
    for cap in desc.capabilities:
        name = capability_id_short(cap)
        elements.append(capability(name))
        if cap in specs:
            elements.append(capability_relations(desc.asset_id, name, specs[cap], targets))
    return elements


def _check(desc: AssetDescriptor) -> None:
    if desc.physical_type is PhysicalType.A:
        raise InputError(f"{desc.asset_id}: type A assets have no virtual representation")
    logical = desc.kind is AssetKind.LOGICAL
    classes = LOGICAL_CLASSES if logical else PHYSICAL_CLASSES
    try:  # a class the code does not know: the generic one its capabilities name
        role = desc.role_class
    except InputError:
        role = None
    if role not in classes:
        raise InputError(
            f"{desc.asset_id}: asset class {desc.asset_class!r} does not fit kind "
            f"{desc.kind.value} (one of {', '.join(sorted(classes))}; a class of its own "
            "runs as the one its capabilities name)"
        )
    try:
        model.Referable.validate_id_short(desc.asset_id)
    except (model.AASConstraintViolation, ValueError) as exc:
        raise InputError(f"{desc.asset_id!r} is no valid AAS idShort (AASd-002): {exc}") from None


def _submodel(
    asset_id: str, id_short: str, elements: Iterable[model.SubmodelElement]
) -> model.Submodel:
    return model.Submodel(
        submodel_iri(asset_id, id_short),
        id_short=id_short,
        semantic_id=semantic(id_short),
        submodel_element=elements,
    )


def _identification(
    desc: AssetDescriptor, endpoint: str | None, provenance: str | None
) -> list[model.Property]:
    props = [
        text_property("AssetId", desc.asset_id),
        text_property("AssetClass", desc.asset_class),
        text_property("AssetKind", desc.kind.value),
    ]
    if desc.physical_type is not None:
        props.append(text_property("PhysicalType", desc.physical_type.value, "Table 3.1 type."))
    if desc.station is not None:
        # tt:Station is the class of stations; the property names the asset's station
        props.append(text_property("Station", desc.station, concept="StationId"))
    if provenance is not None and not provenance.strip():
        raise InputError(f"{desc.asset_id}: provenance, when given, must not be blank")
    props.append(text_property("Provenance", _PROVENANCE[desc.kind], provenance or ""))
    if desc.kind is AssetKind.VIRTUAL_MODEL:
        props.append(text_property("ModelOf", str(desc.models), "Id of the physical twin."))
    if endpoint is not None:
        if not endpoint.startswith("opc.tcp://"):
            raise InputError(f"{desc.asset_id}: endpoint must be opc.tcp://…, got {endpoint!r}")
        props.append(text_property("Endpoint", endpoint, "OPC UA endpoint URL."))
    return props


def _operational_data(asset_class: str, sync: str | None) -> list[model.Property]:
    def synced_by(mixed_external: bool) -> str | None:
        if sync == "mixed":
            return "external" if mixed_external else "internal"
        return sync  # 'internal', 'external', or None for logical assets

    return [
        property_(spec, synced_by(spec.mixed_external)) for spec in OPERATIONAL_DATA[asset_class]
    ]


def externally_synced(rep: AssetRepresentation) -> frozenset[str]:
    """idShorts of the OperationalData properties that other assets keep current (Table 3.1).

    These are the variables an OPC UA server should make client-writable.
    """
    return frozenset(
        p.id_short
        for p in rep.submodel("OperationalData").submodel_element
        if any(q.type == SYNC_QUALIFIER and q.value == "external" for q in p.qualifier)
    )


def wire_signature(rep: AssetRepresentation | Iterable[model.Submodel]) -> tuple:
    """The structure others program against: submodels, element kinds, idShorts, value types,
    units, semantic ids and operation arguments, without identifiers, values or the
    `PROVENANCE_ELEMENTS` (Sec. 3.2). Equal for a virtual model and its physical twin.

    Args:
        rep: A representation, or the submodels of one (e.g. read back from a file).
    """
    submodels = rep.submodels if isinstance(rep, AssetRepresentation) else tuple(rep)
    return tuple(sorted(_submodel_signature(sm) for sm in submodels))


def _submodel_signature(sm: model.Submodel) -> tuple:
    shown = (
        el
        for el in sm.submodel_element
        if sm.id_short != "Identification" or el.id_short not in PROVENANCE_ELEMENTS
    )
    return (sm.id_short, _semantic_key(sm), tuple(sorted(map(_element_signature, shown))))


def _semantic_key(obj: model.HasSemantics) -> str:
    return obj.semantic_id.key[0].value if obj.semantic_id else ""


def _element_signature(el: model.SubmodelElement) -> tuple:
    head = (type(el).__name__, el.id_short, _semantic_key(el))
    if isinstance(el, model.Property):
        quals = tuple(sorted((q.type, str(q.value)) for q in el.qualifier))
        return (*head, model.datatypes.XSD_TYPE_NAMES[el.value_type], quals)
    if isinstance(el, model.Operation):
        return (
            *head,
            tuple(_element_signature(v) for v in el.input_variable),
            tuple(_element_signature(v) for v in el.output_variable),
            tuple(_element_signature(v) for v in el.in_output_variable),
        )
    if isinstance(el, model.SubmodelElementCollection):
        return (*head, tuple(sorted(map(_element_signature, el.value))))
    if isinstance(el, model.RelationshipElement):
        return (*head, el.first.key[-1].value, el.second.key[-1].value)
    return head
