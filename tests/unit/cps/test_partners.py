"""Partners found by meaning (issue 39, item 5): an asset class the code has never seen runs
as the generic class its capabilities name, its own constraint values reach its AAS and the
knowledge graph, and the capability query (`partners_query`) answers who realises what,
with which constraints, online or not."""

from __future__ import annotations

import asyncio
import json
import tomllib

import pytest

from transfertwin._errors import InputError
from transfertwin.cps.aas import (
    AssetDescriptor,
    AssetKind,
    Capability,
    PhysicalType,
    build_representation,
    capability_specs,
)
from transfertwin.cps.floor import parse_floor
from transfertwin.cps.floor._floor_io import floor_toml
from transfertwin.cps.kg import CAPABILITY_IRIS, TT, KnowledgeGraph
from transfertwin.cps.node import (
    Partner,
    capability_name,
    find_partner_ids,
    find_partners,
    partners_from_rows,
    partners_query,
)

_TM_CAPS = (Capability.TRANSPORT, Capability.TRANSFER, Capability.SENSE)

FLOOR = """
name = "makes"
logical = ["KG", "TMS"]

[[station]]
name = "A"
x_m = 2.6
y_m = 6.6
yaw_deg = 90.0
mount = "left"

[[station]]
name = "B"
x_m = 7.6
y_m = 6.6
yaw_deg = 90.0
mount = "right"
class = "buffer_station"

[[module]]
id = "TM_1"
x_m = 6.0
y_m = 5.2

[[module]]
id = "TM_L"
x_m = 6.0
y_m = 3.0
class = "light_transport_module"

[module.constraints]
ObjectMassMax = 3.0

[[object]]
id = "o6"
at = "TU_A"
"""


def _module(cls: str, caps=_TM_CAPS, constraints=()) -> AssetDescriptor:
    return AssetDescriptor("TM_L", AssetKind.VIRTUAL_MODEL, cls, physical_type=PhysicalType.E,
                           capabilities=caps, models="TM_L_P",
                           constraints=constraints)  # fmt: skip


def test_a_class_the_code_has_never_seen_runs_as_the_generic_class_its_capabilities_name():
    assert _module("light_transport_module").role_class == "transport_module"
    unit = AssetDescriptor("TU_X", AssetKind.VIRTUAL_MODEL, "buffer_station",
                           physical_type=PhysicalType.D_E, station="X", models="TU_X_P",
                           capabilities=(Capability.TRANSFER, Capability.SENSE))  # fmt: skip
    assert unit.role_class == "transfer_unit"
    assert _module("transport_module").role_class == "transport_module"  # known: itself
    for caps in ((), (Capability.SENSE,), (Capability.TRANSFER,)):  # no station: no unit
        with pytest.raises(InputError, match="name no generic class"):
            _module("crane", caps).role_class  # noqa: B018


def test_its_own_constraint_values_replace_its_generic_classs_in_its_aas():
    desc = _module("light_transport_module",
                   constraints=((Capability.TRANSPORT, "ObjectMassMax", 3.0),))  # fmt: skip
    transport = capability_specs(desc)[Capability.TRANSPORT].constraints
    bounds = {c.id_short: c.initial for c in transport}
    assert bounds["ObjectMassMax"] == 3.0 and bounds["ObjectMassMin"] == 2.2
    transfer = capability_specs(desc)[Capability.TRANSFER].constraints
    assert {c.id_short: c.initial for c in transfer}["ObjectMassMax"] == 4.9  # not bound there
    rep = build_representation(desc)
    caps = next(sm for sm in rep.submodels if sm.id_short == "Capabilities")
    constraints = caps.get_referable("TransportRelations").get_referable("Constraints")
    assert constraints.get_referable("ObjectMassMax").value == 3.0
    ident = next(sm for sm in rep.submodels if sm.id_short == "Identification")
    assert ident.get_referable("AssetClass").value == "light_transport_module"


def test_a_constraint_its_class_does_not_have_is_refused():
    with pytest.raises(InputError, match="no constraint 'PayloadMax'"):
        capability_specs(_module("x_module", constraints=((Capability.TRANSPORT, "PayloadMax",
                                                            1.0),)))  # fmt: skip


def test_a_floor_file_names_a_class_of_its_own_and_its_constraints_and_writes_them_back():
    floor = parse_floor(tomllib.loads(FLOOR), "makes")
    by_id = {d.asset_id: d for d in floor.descriptors()}
    assert by_id["TM_L"].asset_class == "light_transport_module"
    assert (Capability.TRANSPORT, "ObjectMassMax", 3.0) in by_id["TM_L"].constraints
    assert by_id["TU_B"].role_class == "transfer_unit"
    assert parse_floor(tomllib.loads(floor_toml(floor)), "makes") == floor
    bad = FLOOR.replace("ObjectMassMax = 3.0", "PayloadMax = 3.0")
    with pytest.raises(InputError, match="floor makes: TM_L: no capability of it has"):
        parse_floor(tomllib.loads(bad), "makes")
    lost = FLOOR.replace('class = "light_transport_module"',
                         'class = "crane"\ncapabilities = ["sense"]')  # fmt: skip
    with pytest.raises(InputError, match=r"floor makes: .*'crane' is unknown"):
        parse_floor(tomllib.loads(lost), "makes")


def test_capability_names_are_the_ontologys_individuals():
    for cap, iri in CAPABILITY_IRIS.items():
        assert TT[capability_name(cap)] == iri


@pytest.fixture
def graph() -> KnowledgeGraph:
    floor = parse_floor(tomllib.loads(FLOOR), "makes")
    kg = KnowledgeGraph()
    for d in floor.descriptors():
        if d.asset_id != "KG":
            kg.join(d, endpoint="opc.tcp://127.0.0.1:4840")
    return kg


def test_the_capability_query_finds_each_make_of_module_with_its_constraints(graph):
    movers = partners_from_rows(graph.query(partners_query(Capability.TRANSPORT)))
    assert [p.asset_id for p in movers] == ["TM_1", "TM_L"]
    tm_1, tm_l = movers
    assert tm_1.constraints["ObjectMassMax"] == 4.9 and tm_l.constraints["ObjectMassMax"] == 3.0
    assert tm_l.constraints["AcceptedFaces"] == "front,back"
    heavy, light = {"ObjectMass": 4.5}, {"ObjectMass": 2.5}
    assert tm_1.admits(heavy) and not tm_l.admits(heavy) and tm_l.admits(light)
    assert not tm_l.admits({"ObjectMass": 2.0})  # below ObjectMassMin
    allocators = partners_from_rows(graph.query(partners_query(Capability.ALLOCATE)))
    assert allocators == (Partner("TMS", True, {}),)
    receivers = partners_from_rows(graph.query(partners_query(Capability.TRANSFER)))
    assert {p.asset_id for p in receivers} == {"TM_1", "TM_L", "TU_A", "TU_B"}


def test_the_capability_query_says_who_is_offline_and_forgets_old_values_on_rejoin(graph):
    graph.leave("TM_L")
    movers = {p.asset_id: p for p in partners_from_rows(
        graph.query(partners_query(Capability.TRANSPORT)))}  # fmt: skip
    assert movers["TM_1"].online and not movers["TM_L"].online
    floor = parse_floor(tomllib.loads(FLOOR.replace("ObjectMassMax = 3.0",
                                                    "ObjectMassMax = 2.5")), "makes")  # fmt: skip
    graph.join(next(d for d in floor.descriptors() if d.asset_id == "TM_L"),
               endpoint="opc.tcp://127.0.0.1:4841")  # fmt: skip
    rows = graph.query(partners_query(Capability.TRANSPORT))
    assert [r["value"] for r in rows if r["id"] == "TM_L" and r["name"] == "ObjectMassMax"] == [
        "2.5"]  # fmt: skip


def test_a_description_may_not_state_another_assets_constraints(graph):
    from rdflib import Literal, URIRef

    desc = graph.describe(_module("light_transport_module"),
                          endpoint="opc.tcp://127.0.0.1:4840")  # fmt: skip
    other = URIRef("https://transfertwin.dev/ids/asset/TM_1/capability/transport/ObjectMassMax")
    desc.add((other, TT.value, Literal(9.0)))
    with pytest.raises(InputError, match="may state only the asset"):
        graph.join_graph(desc)


def test_kg_11_a_constraint_value_names_a_constraint_of_the_ontology(graph):
    from rdflib import URIRef

    desc = graph.describe(_module("light_transport_module"),
                          endpoint="opc.tcp://127.0.0.1:4840")  # fmt: skip
    own = URIRef("https://transfertwin.dev/ids/asset/TM_L/capability/transport/ObjectMassMax")
    desc.set((own, TT.constraint, TT.PayloadMax))  # no such concept
    with pytest.raises(InputError, match="KG-11"):
        graph.join_graph(desc)


class _Node:
    """An asset node as `find_partners` sees it: its floor's assets, and a graph that
    answers `rows` (or does not answer: None)."""

    def __init__(self, rows, floor_text: str = FLOOR) -> None:
        descs = parse_floor(tomllib.loads(floor_text), "makes").descriptors()
        self.descriptors = {d.asset_id: d for d in descs}
        self.desc = self.descriptors["TM_L"]
        self.rows = rows
        self.asked: list[tuple] = []
        self.peers = self

    async def call(self, aid: str, op: str, *args):
        self.asked.append((aid, op))
        if self.rows is None:
            raise ConnectionError("the graph is away")
        return json.dumps(self.rows)


def test_partners_are_asked_of_the_graph_and_of_the_floor_file_while_it_is_away():
    rows = [{"id": "TMS", "status": "online"}, {"id": "TMS_2", "status": "offline"}]
    node = _Node(rows)
    assert asyncio.run(find_partner_ids(node, Capability.ALLOCATE)) == ["TMS"]
    assert asyncio.run(find_partner_ids(node, Capability.ALLOCATE, online=False)) == [
        "TMS", "TMS_2"]  # fmt: skip
    assert node.asked[0] == ("KG", "Query")  # the graph, found through its seed
    away = _Node(None)
    assert asyncio.run(find_partners(away, Capability.ALLOCATE)) is None
    # by what the floor file's assets offer, never their class; not the asking asset itself
    assert asyncio.run(find_partner_ids(away, Capability.TRANSPORT)) == ["TM_1"]
    assert asyncio.run(find_partner_ids(away, Capability.ALLOCATE)) == ["TMS"]
