"""Identifiers and basyx element builders for the virtual representations (Sec. 3.1).

Every identifiable gets a globally unique IRI under `ID_BASE`; every element a semantic id
(an ExternalReference) under `ONTOLOGY`, the vocabulary of the descriptive layer (Sec. 3.3).
"""

from __future__ import annotations

from basyx.aas import model

from transfertwin.cps.aas._spec import Arg, OperationSpec, PropertySpec

__all__ = [
    "ID_BASE",
    "ONTOLOGY",
    "SYNC_QUALIFIER",
    "UNIT_QUALIFIER",
    "asset_iri",
    "capability",
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


def text_property(id_short: str, value: str, description: str = "") -> model.Property:
    """An xs:string Property (Identification submodel)."""
    return model.Property(
        id_short,
        model.datatypes.String,
        value,
        description=_text(description),
        semantic_id=semantic(id_short),
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
