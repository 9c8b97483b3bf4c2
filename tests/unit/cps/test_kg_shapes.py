"""SHACL shapes KG-1 … KG-7 and the scope rules guard what enters the knowledge graph."""

from __future__ import annotations

import pytest
from rdflib import RDF, Graph, Literal, URIRef

from transfertwin import InputError
from transfertwin.cps.aas._assets import AssetDescriptor, AssetKind, Capability, PhysicalType
from transfertwin.cps.kg._describe import describe
from transfertwin.cps.kg._graph import KnowledgeGraph

TT = "https://transfertwin.dev/ontology#"
IDS = "https://transfertwin.dev/ids/asset/"


def tt(name: str) -> URIRef:
    return URIRef(TT + name)


def asset(name: str) -> URIRef:
    return URIRef(IDS + name)


TU_X = AssetDescriptor(
    "TU_X",
    AssetKind.PHYSICAL,
    "transfer_unit",
    PhysicalType.D_E,
    (Capability.TRANSFER,),
    station="X",
)
TM_X = AssetDescriptor(
    "TM_X", AssetKind.PHYSICAL, "transport_module", PhysicalType.E, (Capability.TRANSPORT,)
)
VM_X = AssetDescriptor(
    "TM_XV", AssetKind.VIRTUAL_MODEL, "transport_module", PhysicalType.E, models="TM_X"
)


@pytest.fixture
def kg() -> KnowledgeGraph:
    graph = KnowledgeGraph()
    graph.join(TU_X, endpoint="opc.tcp://127.0.0.1:4840")
    graph.join(TM_X)
    return graph


def _rejected(kg: KnowledgeGraph, description: Graph, rule: str, name: str) -> None:
    """The description is refused with the rule id and the asset's name; nothing changes."""
    before_triples, before_assets = kg.triples(), kg.assets()
    with pytest.raises(InputError, match=rule) as info:
        kg.join_graph(description)
    assert f"asset {name}" in str(info.value)
    assert kg.triples() == before_triples
    assert kg.assets() == before_assets


def test_valid_descriptions_are_accepted(kg: KnowledgeGraph) -> None:
    before = kg.triples()
    kg.join(VM_X, endpoint="opc.tcp://127.0.0.1:4850", security_policy="Basic256Sha256")
    assert kg.triples() == before + len(
        describe(
            VM_X,
            endpoint="opc.tcp://127.0.0.1:4850",
            security_policy="Basic256Sha256",
            state="idle",
        )
    )


def test_kg1_asset_without_id(kg: KnowledgeGraph) -> None:
    g = describe(VM_X)
    g.remove((asset("TM_XV"), tt("assetId"), None))
    _rejected(kg, g, "KG-1", "TM_XV")


def test_kg1_asset_with_two_ids(kg: KnowledgeGraph) -> None:
    g = describe(VM_X)
    g.add((asset("TM_XV"), tt("assetId"), Literal("TM_XW")))
    _rejected(kg, g, "KG-1", "TM_XV")


def test_kg1_status_outside_online_offline(kg: KnowledgeGraph) -> None:
    g = describe(VM_X, status="sleeping")
    _rejected(kg, g, "KG-1", "TM_XV")


def test_kg2_asset_without_kind_class(kg: KnowledgeGraph) -> None:
    g = describe(AssetDescriptor("TM_Y", AssetKind.PHYSICAL, "transport_module", PhysicalType.E))
    g.remove((asset("TM_Y"), RDF.type, tt("PhysicalAsset")))
    _rejected(kg, g, "KG-2", "TM_Y")


def test_kg3_physical_asset_without_type(kg: KnowledgeGraph) -> None:
    g = describe(TM_X)
    g.remove((asset("TM_X"), tt("assetType"), None))
    _rejected(kg, g, "KG-3", "TM_X")


def test_kg3_virtual_model_with_two_types(kg: KnowledgeGraph) -> None:
    g = describe(VM_X)
    g.add((asset("TM_XV"), tt("assetType"), tt("TypeD")))
    _rejected(kg, g, "KG-3", "TM_XV")


def test_kg3_type_must_be_a_table_3_1_type(kg: KnowledgeGraph) -> None:
    g = describe(TM_X)
    g.set((asset("TM_X"), tt("assetType"), tt("Transfer")))
    _rejected(kg, g, "KG-3", "TM_X")


def test_kg4_virtual_model_without_original(kg: KnowledgeGraph) -> None:
    g = describe(VM_X)
    g.remove((asset("TM_XV"), tt("virtualModelOf"), None))
    _rejected(kg, g, "KG-4", "TM_XV")


def test_kg4_virtual_model_of_a_literal(kg: KnowledgeGraph) -> None:
    g = describe(VM_X)
    g.set((asset("TM_XV"), tt("virtualModelOf"), Literal("TM_X")))
    _rejected(kg, g, "KG-4", "TM_XV")


def test_kg5_transfer_unit_without_station(kg: KnowledgeGraph) -> None:
    unit = AssetDescriptor("TU_Y", AssetKind.PHYSICAL, "transfer_unit", PhysicalType.D_E)
    with pytest.raises(InputError, match="KG-5"):
        kg.join(unit)
    assert "TU_Y" not in {row["id"] for row in kg.assets()}


def test_kg5_transfer_unit_at_two_stations(kg: KnowledgeGraph) -> None:
    g = describe(
        AssetDescriptor("TU_Y", AssetKind.PHYSICAL, "transfer_unit", PhysicalType.D_E, station="Y")
    )
    other = URIRef("https://transfertwin.dev/ids/station/Z")
    g.add((asset("TU_Y"), tt("atStation"), other))
    g.add((other, RDF.type, tt("Station")))
    _rejected(kg, g, "KG-5", "TU_Y")


def test_kg6_docked_at_something_that_is_not_a_transfer_unit(kg: KnowledgeGraph) -> None:
    g = describe(VM_X)
    g.add((asset("TM_XV"), tt("dockedAt"), asset("TM_X")))  # a joined transport module
    _rejected(kg, g, "KG-6", "TM_XV")


def test_kg6_docked_at_two_units(kg: KnowledgeGraph) -> None:
    kg.join(
        AssetDescriptor("TU_Y", AssetKind.PHYSICAL, "transfer_unit", PhysicalType.D_E, station="Y")
    )
    g = describe(VM_X)
    g.add((asset("TM_XV"), tt("dockedAt"), asset("TU_X")))
    ok = Graph() + g
    g.add((asset("TM_XV"), tt("dockedAt"), asset("TU_Y")))
    _rejected(kg, g, "KG-6", "TM_XV")
    kg.join_graph(ok)  # docked at one unit is fine
    assert kg.receivers_at("X") == ["TU_X"]  # TM_XV cannot transfer (no capability)


def test_kg7_endpoint_must_be_opc_tcp(kg: KnowledgeGraph) -> None:
    g = describe(VM_X, endpoint="http://127.0.0.1:8080")
    _rejected(kg, g, "KG-7", "TM_XV")


def test_kg7_interface_with_two_urls(kg: KnowledgeGraph) -> None:
    g = describe(VM_X, endpoint="opc.tcp://127.0.0.1:4850")
    iface = URIRef(IDS + "TM_XV/interface/opcua")
    g.add((iface, tt("endpointUrl"), Literal("opc.tcp://127.0.0.1:4851")))
    _rejected(kg, g, "KG-7", "TM_XV")


# --- scope rules ---------------------------------------------------------------------
def test_description_may_not_touch_other_assets(kg: KnowledgeGraph) -> None:
    g = describe(VM_X)
    g.add((asset("TM_X"), tt("status"), Literal("offline")))
    _rejected(kg, g, "may state only", "TM_XV")


def test_description_iri_must_match_its_id(kg: KnowledgeGraph) -> None:
    g = Graph()
    for s, p, o in describe(VM_X):
        g.add((URIRef(IDS + "Other") if s == asset("TM_XV") else s, p, o))
    _rejected(kg, g, "IRI must be", "TM_XV")


def test_joining_asset_must_be_online(kg: KnowledgeGraph) -> None:
    _rejected(kg, describe(VM_X, status="offline"), "online", "TM_XV")


def test_description_of_two_assets_is_refused(kg: KnowledgeGraph) -> None:
    with pytest.raises(InputError, match="exactly one asset"):
        kg.join_graph(describe(VM_X) + describe(TM_X))
    with pytest.raises(InputError, match="exactly one asset"):
        kg.join_graph(Graph())


def test_unknown_asset_class_is_refused() -> None:
    odd = AssetDescriptor("R1", AssetKind.PHYSICAL, "robot_arm", PhysicalType.E)
    with pytest.raises(InputError, match="robot_arm"):
        describe(odd)
