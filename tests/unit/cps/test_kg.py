"""Knowledge graph (Sec. 3.3): membership, named queries, read-only SPARQL, listeners."""

from __future__ import annotations

import pytest
from rdflib import Graph

from transfertwin import InputError
from transfertwin.cps.aas._assets import AssetDescriptor, AssetKind, Capability, PhysicalType
from transfertwin.cps.kg._graph import KnowledgeGraph

P, L, V = AssetKind.PHYSICAL, AssetKind.LOGICAL, AssetKind.VIRTUAL_MODEL
TU_CAPS = (Capability.TRANSFER, Capability.SENSE)
TM_CAPS = (Capability.TRANSPORT, Capability.TRANSFER, Capability.SENSE)


def _tu(asset_id: str, station: str, models: str | None = None) -> AssetDescriptor:
    kind = V if models else P
    return AssetDescriptor(
        asset_id, kind, "transfer_unit", PhysicalType.D_E, TU_CAPS, station=station, models=models
    )


def _tm(asset_id: str, models: str | None = None) -> AssetDescriptor:
    kind = V if models else P
    return AssetDescriptor(
        asset_id, kind, "transport_module", PhysicalType.E, TM_CAPS, models=models
    )


def build_demo() -> KnowledgeGraph:
    """Stations A–D, each with a physical unit TU_x_P and its virtual model TU_x;
    TM_1 (busy) docked at TU_C, its virtual model TM_V1 idle, TM_2 idle; TM_1 carries o5;
    the logical assets TMS, PropS and EM; and the graph itself, KG."""
    kg = KnowledgeGraph()
    for i, station in enumerate("ABCD"):
        kg.join(
            _tu(f"TU_{station}_P", station),
            endpoint=f"opc.tcp://127.0.0.1:{4841 + i}",
            security_policy="Basic256Sha256",
        )
        kg.join(_tu(f"TU_{station}", station, models=f"TU_{station}_P"))
    kg.join(_tm("TM_1"), endpoint="opc.tcp://127.0.0.1:4850", state="busy")
    kg.join(_tm("TM_V1", models="TM_1"), state="idle")
    kg.join(_tm("TM_2"), state="idle")
    kg.join(AssetDescriptor("o5", P, "object", PhysicalType.B))
    kg.join(AssetDescriptor("TMS", L, "transport_module_system", None, (Capability.ALLOCATE,)))
    kg.join(AssetDescriptor("PropS", L, "props", None, (Capability.FUSE_POSES,)))
    kg.join(AssetDescriptor("EM", L, "experiment_manager", None, (Capability.EXPERIMENT,)))
    kg.set_docked("TM_1", "TU_C")
    kg.set_possesses("TM_1", ["o5"])
    return kg


@pytest.fixture
def kg() -> KnowledgeGraph:
    return build_demo()


def _docked(kg: KnowledgeGraph) -> list[tuple[str, str]]:
    rows = kg.query(
        "SELECT ?tm ?tu WHERE { ?a tt:dockedAt ?b . ?a tt:assetId ?tm . ?b tt:assetId ?tu }"
    )
    return sorted((row["tm"], row["tu"]) for row in rows)


# --- the three named questions on the demo ---------------------------------------------
def test_receivers_at_station_c_are_its_units_and_the_docked_module(kg: KnowledgeGraph) -> None:
    assert kg.receivers_at("C") == ["TM_1", "TU_C", "TU_C_P"]


def test_receivers_at_station_without_docked_module(kg: KnowledgeGraph) -> None:
    assert kg.receivers_at("A") == ["TU_A", "TU_A_P"]
    assert kg.receivers_at("E") == []


def test_virtual_models_of(kg: KnowledgeGraph) -> None:
    assert kg.virtual_models_of("TU_C_P") == ["TU_C"]
    assert kg.virtual_models_of("TM_1") == ["TM_V1"]
    assert kg.virtual_models_of("TU_C") == []


def test_idle_transport_modules(kg: KnowledgeGraph) -> None:
    assert kg.idle_transport_modules() == ["TM_2", "TM_V1"]
    kg.set_state("TM_2", "busy")
    kg.set_state("TM_1", "idle")
    assert kg.idle_transport_modules() == ["TM_1", "TM_V1"]


def test_named_query_parameters_must_be_ids(kg: KnowledgeGraph) -> None:
    with pytest.raises(InputError):
        kg.receivers_at("C> . ?x ?y ?z } #")
    with pytest.raises(InputError):
        kg.virtual_models_of("TU C")


# --- assets() and leave ----------------------------------------------------------------
def test_assets_rows(kg: KnowledgeGraph) -> None:
    rows = {row["id"]: row for row in kg.assets()}
    assert set(rows) == {
        *(f"TU_{s}{p}" for s in "ABCD" for p in ("", "_P")),
        *("TM_1", "TM_V1", "TM_2", "o5", "TMS", "PropS", "EM", "KG"),
    }
    assert rows["TU_B_P"] == {
        "id": "TU_B_P",
        "kind": "physical",
        "class": "transfer_unit",
        "type": "D/E",
        "endpoint": "opc.tcp://127.0.0.1:4842",
        "status": "online",
        "state": "idle",
    }
    assert rows["TM_V1"]["kind"] == "virtual_model"
    assert rows["TM_V1"]["state"] == "idle"
    assert rows["KG"] == {
        "id": "KG",
        "kind": "logical",
        "class": "knowledge_graph",
        "type": None,
        "endpoint": None,
        "status": "online",
        "state": "idle",
    }


def test_joining_asset_is_idle_unless_told(kg: KnowledgeGraph) -> None:
    kg.join(_tm("TM_3"))
    kg.join(_tm("TM_4"), state=None)
    kg.join(_tm("TM_5"), state="charging")
    assert kg.idle_transport_modules() == ["TM_2", "TM_3", "TM_V1"]
    rows = {row["id"]: row["state"] for row in kg.assets()}
    assert (rows["TM_4"], rows["TM_5"]) == (None, "charging")


def test_leave_marks_offline_and_hides_from_queries(kg: KnowledgeGraph) -> None:
    kg.leave("TU_C_P")
    row = next(r for r in kg.assets() if r["id"] == "TU_C_P")
    assert row["status"] == "offline"
    assert "TU_C_P" not in {r["id"] for r in kg.assets(online_only=True)}
    assert kg.receivers_at("C") == ["TM_1", "TU_C"]
    kg.leave("TM_2")
    assert kg.idle_transport_modules() == ["TM_V1"]
    kg.leave("TU_C")
    assert kg.virtual_models_of("TU_C_P") == []


def test_leave_drops_dynamic_relations_both_ways(kg: KnowledgeGraph) -> None:
    assert _docked(kg) == [("TM_1", "TU_C")]
    kg.leave("TU_C")
    assert _docked(kg) == []
    assert kg.receivers_at("C") == ["TU_C_P"]
    kg.leave("TM_1")
    rows = kg.query("SELECT ?o WHERE { ?a tt:possesses ?o }")
    assert rows == []
    assert next(r for r in kg.assets() if r["id"] == "TM_1")["state"] is None


def test_offline_asset_cannot_be_updated_until_it_rejoins(kg: KnowledgeGraph) -> None:
    kg.leave("TM_2")
    with pytest.raises(InputError, match="offline"):
        kg.set_state("TM_2", "idle")
    with pytest.raises(InputError, match="offline"):
        kg.set_docked("TM_2", "TU_A")
    kg.join(_tm("TM_2"), state="idle")
    assert kg.idle_transport_modules() == ["TM_2", "TM_V1"]


def test_rejoin_replaces_own_description(kg: KnowledgeGraph) -> None:
    kg.join(_tm("TM_1"), endpoint="opc.tcp://127.0.0.1:4999", state="idle")
    row = next(r for r in kg.assets() if r["id"] == "TM_1")
    assert row["endpoint"] == "opc.tcp://127.0.0.1:4999"
    endpoints = kg.query(
        "SELECT ?url WHERE { ?a tt:assetId 'TM_1' ; tt:hasInterface/tt:endpointUrl ?url }"
    )
    assert endpoints == [{"url": "opc.tcp://127.0.0.1:4999"}]
    assert _docked(kg) == []


def test_leave_unknown_raises_and_leave_twice_is_a_no_op(kg: KnowledgeGraph) -> None:
    with pytest.raises(InputError, match="unknown"):
        kg.leave("TU_X")
    events: list[tuple[str, str]] = []
    kg.subscribe(lambda kind, asset: events.append((kind, asset)))
    kg.leave("TM_2")
    kg.leave("TM_2")
    assert events == [("leave", "TM_2")]


# --- dynamic relations -----------------------------------------------------------------
def test_docking_moves_a_module_between_stations(kg: KnowledgeGraph) -> None:
    kg.set_docked("TM_2", "TU_B_P")
    assert kg.receivers_at("B") == ["TM_2", "TU_B", "TU_B_P"]
    kg.set_docked("TM_2", "TU_D")
    assert kg.receivers_at("B") == ["TU_B", "TU_B_P"]
    assert kg.receivers_at("D") == ["TM_2", "TU_D", "TU_D_P"]
    kg.set_docked("TM_2", None)
    assert _docked(kg) == [("TM_1", "TU_C")]


def test_docking_needs_a_module_and_a_unit(kg: KnowledgeGraph) -> None:
    with pytest.raises(InputError, match="TransferUnit"):
        kg.set_docked("TM_2", "TM_1")
    with pytest.raises(InputError, match="TransportModule"):
        kg.set_docked("TU_A", "TU_B")
    with pytest.raises(InputError, match="unknown"):
        kg.set_docked("TM_2", "TU_Z")


def test_possession(kg: KnowledgeGraph) -> None:
    kg.set_possesses("TU_C", ["o5", "o7"])
    rows = kg.query("SELECT ?o WHERE { ?a tt:assetId 'TU_C' ; tt:possesses/tt:assetId ?o }")
    assert rows == [{"o": "o5"}]  # o7 has not joined, so it has no tt:assetId
    count = kg.query("SELECT (COUNT(?o) AS ?n) WHERE { ?a tt:assetId 'TU_C' ; tt:possesses ?o }")
    assert count == [{"n": "2"}]
    with pytest.raises(InputError, match="not an object"):
        kg.set_possesses("TU_C", ["TM_2"])
    with pytest.raises(InputError):
        kg.set_possesses("TU_C", ["o 5"])


def test_object_location_is_one_shacl_valid_triple(kg: KnowledgeGraph) -> None:
    from transfertwin.cps.kg._validate import first_violation

    kg.set_location("o5", "TU_A")
    kg.set_location("o5", "TM_1")  # a transfer moved it: the location is replaced
    assert kg.locations() == {"o5": "TM_1"}
    rows = kg.query("SELECT ?h WHERE { ?o tt:assetId 'o5' ; tt:locatedAt/tt:assetId ?h }")
    assert rows == [{"h": "TM_1"}]
    whole = Graph().parse(data=kg.to_turtle(), format="turtle")
    assert first_violation(whole) is None
    with pytest.raises(InputError, match="not an object"):
        kg.set_location("TM_2", "TU_A")
    with pytest.raises(InputError, match="unknown asset"):
        kg.set_location("o9", "TU_A")
    kg.leave("TU_D")
    with pytest.raises(InputError, match="offline"):
        kg.set_location("o5", "TU_D")
    kg.leave("TM_1")  # the holder leaves: the object has not moved
    assert kg.locations() == {"o5": "TM_1"}
    kg.leave("o5")
    assert kg.locations() == {}


def test_shape_kg8_refuses_two_locations() -> None:
    from transfertwin.cps.kg._describe import TT, asset_iri
    from transfertwin.cps.kg._validate import first_violation

    data = KnowledgeGraph.describe(AssetDescriptor("o5", P, "object", PhysicalType.B))
    data.add((asset_iri("o5"), TT.locatedAt, asset_iri("TU_A")))
    assert first_violation(data) is None
    data.add((asset_iri("o5"), TT.locatedAt, asset_iri("TU_B")))
    assert "KG-8" in first_violation(data)


def test_state_must_be_a_token(kg: KnowledgeGraph) -> None:
    with pytest.raises(InputError):
        kg.set_state("TM_2", "Idle!")


def test_listeners_see_join_leave_update(kg: KnowledgeGraph) -> None:
    events: list[tuple[str, str]] = []
    unsubscribe = kg.subscribe(lambda kind, asset: events.append((kind, asset)))
    kg.join(_tm("TM_3"), state="idle")
    kg.set_state("TM_3", "busy")
    kg.set_docked("TM_3", "TU_A")
    kg.leave("TM_3")
    unsubscribe()
    kg.join(_tm("TM_4"))
    assert events == [("join", "TM_3"), ("update", "TM_3"), ("update", "TM_3"), ("leave", "TM_3")]


def test_a_failing_listener_does_not_undo_the_change(kg: KnowledgeGraph) -> None:
    def boom(kind: str, asset: str) -> None:
        raise RuntimeError("listener bug")

    kg.subscribe(boom)
    kg.set_state("TM_2", "busy")
    assert kg.idle_transport_modules() == ["TM_V1"]


# --- read-only SPARQL and serialisation ------------------------------------------------
def test_select_query_answers_with_ontology(kg: KnowledgeGraph) -> None:
    rows = kg.query(
        "SELECT DISTINCT ?id WHERE { ?a a/rdfs:subClassOf* tt:LogicalAsset ; tt:assetId ?id } "
        "ORDER BY ?id"
    )
    expected = ["EM", "KG", "PropS", "TMS", "TM_V1", "TU_A", "TU_B", "TU_C", "TU_D"]
    assert [row["id"] for row in rows] == expected


@pytest.mark.parametrize(
    "text",
    [
        "INSERT DATA { tt:a tt:b tt:c }",
        "DELETE WHERE { ?s ?p ?o }",
        "DELETE { ?s tt:status ?o } INSERT { ?s tt:status 'x' } WHERE { ?s tt:status ?o }",
        "CLEAR DEFAULT",
        "LOAD <http://example.org/x.ttl>",
    ],
)
def test_update_queries_are_refused(kg: KnowledgeGraph, text: str) -> None:
    before = kg.triples()
    with pytest.raises(InputError, match="read-only"):
        kg.query(text)
    assert kg.triples() == before


@pytest.mark.parametrize(
    "text",
    [
        "CONSTRUCT { ?s ?p ?o } WHERE { ?s ?p ?o }",
        "ASK { ?s ?p ?o }",
        "SELECT * WHERE { SERVICE <http://example.org/sparql> { ?s ?p ?o } }",
        "SELECT ?x WHERE { ?x",
    ],
)
def test_non_select_queries_are_refused(kg: KnowledgeGraph, text: str) -> None:
    with pytest.raises(InputError):
        kg.query(text)


def test_turtle_round_trip(kg: KnowledgeGraph) -> None:
    parsed = Graph().parse(data=kg.to_turtle(), format="turtle")
    assert len(parsed) == kg.triples()
