"""Identifiers and basyx element builders for the virtual representations (Sec. 3.1).

Every identifiable gets a globally unique IRI under `ID_BASE`; every element a semantic id
(an ExternalReference) under `ONTOLOGY`, the vocabulary of the descriptive layer (Sec. 3.3).
"""

from __future__ import annotations

from basyx.aas import model

from transfertwin.cps.aas._spec import Arg, CapabilitySpec, OperationSpec, PropertySpec

__all__ = [
    "ID_BASE",
    "ONTOLOGY",
    "SYNC_QUALIFIER",
    "UNIT_QUALIFIER",
    "asset_iri",
    "capability",
    "capability_relations",
    "element_reference",
    "operation",
    "property_",
    "semantic",
    "shell_iri",
    "submodel_iri",
    "text_property",
]

ID_BASE = "https://transfertwin.dev/ids"
ONTOLOGY = "https://transfertwin.dev/ontology#"
UNIT_QUALIFIER = "Unit"
SYNC_QUALIFIER = "SyncedBy"  # 'internal' | 'external': who keeps the value current


def shell_iri(asset_id: str) -> str:
    """Id of the AssetAdministrationShell of an asset."""
    return f"{ID_BASE}/aas/{asset_id}"


def asset_iri(asset_id: str) -> str:
    """Global asset id of an asset."""
    return f"{ID_BASE}/asset/{asset_id}"


def submodel_iri(asset_id: str, id_short: str) -> str:
    """Id of one submodel of an asset."""
    return f"{ID_BASE}/sm/{asset_id}/{id_short}"


def semantic(name: str) -> model.ExternalReference:
    """Semantic id ``<ONTOLOGY><name>`` as an ExternalReference."""
    return model.ExternalReference(
        (model.Key(model.KeyTypes.GLOBAL_REFERENCE, f"{ONTOLOGY}{name}"),)
    )


def _xsd(name: str) -> model.DataTypeDefXsd:
    return model.datatypes.XSD_TYPE_CLASSES[name]


def _text(text: str) -> model.MultiLanguageTextType | None:
    return model.MultiLanguageTextType({"en": text}) if text else None


def _qualifiers(unit: str | None, synced_by: str | None) -> list[model.Qualifier]:
    quals = []
    if unit is not None:
        quals.append(model.Qualifier(UNIT_QUALIFIER, model.datatypes.String, unit))
    if synced_by is not None:
        quals.append(model.Qualifier(SYNC_QUALIFIER, model.datatypes.String, synced_by))
    return quals


def property_(spec: PropertySpec, synced_by: str | None) -> model.Property:
    """An OperationalData Property with unit and `SyncedBy` qualifiers.

    Args:
        spec: The row of `OPERATIONAL_DATA`.
        synced_by: 'internal' or 'external' (Table 3.1), or None for logical assets.
    """
    return model.Property(
        spec.id_short,
        _xsd(spec.xsd),
        spec.initial,
        description=_text(spec.description),
        semantic_id=semantic(spec.id_short),
        qualifier=_qualifiers(spec.unit, synced_by),
    )


def text_property(
    id_short: str, value: str, description: str = "", concept: str | None = None
) -> model.Property:
    """An xs:string Property (Identification submodel); its semantic id names `concept`
    (default: `id_short`)."""
    return model.Property(
        id_short,
        model.datatypes.String,
        value,
        description=_text(description),
        semantic_id=semantic(concept or id_short),
    )


def _variable(arg: Arg) -> model.Property:
    return model.Property(arg.id_short, _xsd(arg.xsd), qualifier=_qualifiers(arg.unit, None))


def operation(spec: OperationSpec) -> model.Operation:
    """A ControlInterface Operation; each variable is a typed Property (AAS OperationVariable)."""
    return model.Operation(
        spec.id_short,
        input_variable=[_variable(a) for a in spec.inputs],
        output_variable=[_variable(a) for a in spec.outputs],
        description=_text(spec.description),
        semantic_id=semantic(spec.id_short),
    )


def capability(name: str) -> model.Capability:
    """A Capability element with semantic id ``<ONTOLOGY><name>``."""
    return model.Capability(name, semantic_id=semantic(name))


_KEY_TYPES = {
    model.Capability: model.KeyTypes.CAPABILITY,
    model.Operation: model.KeyTypes.OPERATION,
    model.Property: model.KeyTypes.PROPERTY,
}


def element_reference(
    asset_id: str, submodel: str, id_short: str, kind: type[model.SubmodelElement]
) -> model.ModelReference:
    """A ModelReference to the element `id_short` of one of the asset's submodels."""
    keys = (
        model.Key(model.KeyTypes.SUBMODEL, submodel_iri(asset_id, submodel)),
        model.Key(_KEY_TYPES[kind], id_short),
    )
    return model.ModelReference(keys, kind)


def capability_relations(
    asset_id: str,
    name: str,
    spec: CapabilitySpec,
    targets: dict[tuple[str, str], type[model.SubmodelElement]],
) -> model.SubmodelElementCollection:
    """``<name>Relations``: what realises capability `name` and what binds it (the IDTA
    capability pattern): a ``RealizedBy<element>`` RelationshipElement from the Capability
    to each realising element, and a ``Constraints`` collection of constant properties.

    Args:
        asset_id: The asset (the references name its submodels).
        name: idShort of the Capability element (in the Capabilities submodel).
        spec: Its row of `CAPABILITY_SPECS`.
        targets: The elements the asset has, ``(submodel, idShort) -> element type``;
            a realising element it lacks is left out.
    """
    capability_ref = element_reference(asset_id, "Capabilities", name, model.Capability)
    elements: list[model.SubmodelElement] = [
        model.RelationshipElement(
            f"RealizedBy{element}",
            capability_ref,
            element_reference(asset_id, submodel, element, targets[(submodel, element)]),
            semantic_id=semantic("realizedBy"),
        )
        for submodel, element in spec.realized_by
        if (submodel, element) in targets
    ]
    if spec.constraints:
        elements.append(
            model.SubmodelElementCollection(
                "Constraints",
                [property_(c, None) for c in spec.constraints],
                semantic_id=semantic("CapabilityConstraints"),
            )
        )
    return model.SubmodelElementCollection(
        f"{name}Relations", elements, semantic_id=semantic("CapabilityRelations")
    )
