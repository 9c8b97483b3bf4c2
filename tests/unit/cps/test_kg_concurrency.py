"""Several threads joining, updating, leaving and querying leave a consistent graph."""

from __future__ import annotations

import threading
from collections import Counter

from rdflib import Graph, Literal, URIRef

from transfertwin.cps.aas._assets import AssetDescriptor, AssetKind, Capability, PhysicalType
from transfertwin.cps.kg._graph import KnowledgeGraph
from transfertwin.cps.kg._validate import first_violation

TT = "https://transfertwin.dev/ontology#"
WRITERS, MODULES, READERS, REJOINS = 4, 6, 2, 3


def _unit(w: int) -> AssetDescriptor:
    return AssetDescriptor(
        f"TU_{w}",
        AssetKind.PHYSICAL,
        "transfer_unit",
        PhysicalType.D_E,
        (Capability.TRANSFER,),
        station=f"S{w}",
    )


def _writer(kg: KnowledgeGraph, w: int, start: threading.Barrier) -> None:
    start.wait()
    for m in range(MODULES):
        tm = f"TM_{w}_{m}"
        kg.join(
            AssetDescriptor(
                tm, AssetKind.PHYSICAL, "transport_module", PhysicalType.E, (Capability.TRANSFER,)
            ),
            endpoint=f"opc.tcp://127.0.0.1:{5000 + 10 * w + m}",
            state="idle",
        )
        kg.set_docked(tm, f"TU_{w}")
        kg.set_state(tm, "busy")
        if m % 2 == 0:  # even modules leave again
            kg.leave(tm)
    for _ in range(REJOINS):  # the unit reconnects; a rejoin replaces it atomically
        kg.join(_unit(w))


def _reader(kg: KnowledgeGraph, stop: threading.Event, errors: list[BaseException]) -> None:
    """Never sees a half-written asset: every row has a kind, a class and a status."""
    while not stop.wait(0.002):  # yield to the writers between rounds
        try:
            rows = kg.assets()
            for row in rows:
                if row["kind"] is None or row["class"] is None or row["status"] is None:
                    raise AssertionError(f"half-written asset seen: {row}")
            units = [row["id"] for row in rows if row["class"] == "transfer_unit"]
            if len(units) != WRITERS:
                raise AssertionError(f"a rejoining unit went missing: {units}")
            kg.receivers_at("S0")
            kg.query("SELECT ?a ?s WHERE { ?a tt:status ?s }")
            kg.to_turtle()
        except BaseException as exc:  # collected and reported by the test
            errors.append(exc)
            return


def test_concurrent_join_update_leave_is_consistent() -> None:
    kg = KnowledgeGraph()
    for w in range(WRITERS):
        kg.join(_unit(w))
    events: Counter[str] = Counter()
    event_lock = threading.Lock()

    def count(kind: str, asset: str) -> None:
        with event_lock:
            events[kind] += 1

    kg.subscribe(count)
    start, stop, errors = threading.Barrier(WRITERS), threading.Event(), []
    readers = [threading.Thread(target=_reader, args=(kg, stop, errors)) for _ in range(READERS)]
    writers = [threading.Thread(target=_writer, args=(kg, w, start)) for w in range(WRITERS)]
    for t in readers + writers:
        t.start()
    for t in writers:
        t.join(timeout=60)
    stop.set()
    for t in readers:
        t.join(timeout=60)

    assert errors == []
    n = WRITERS * MODULES
    assert events == {"join": n + WRITERS * REJOINS, "update": 2 * n, "leave": n // 2}
    rows = {row["id"]: row for row in kg.assets() if row["id"].startswith("TM_")}
    assert len(rows) == n
    for w in range(WRITERS):
        stayed = [f"TM_{w}_{m}" for m in range(MODULES) if m % 2 == 1]
        assert kg.receivers_at(f"S{w}") == sorted([*stayed, f"TU_{w}"])
        for m in range(MODULES):
            row = rows[f"TM_{w}_{m}"]
            expected = ("offline", None) if m % 2 == 0 else ("online", "busy")
            assert (row["status"], row["state"]) == expected

    # every asset still has exactly one id and one status, and the graph conforms
    graph = Graph().parse(data=kg.to_turtle(), format="turtle")
    for node in set(graph.subjects(URIRef(TT + "assetId"), None)):
        assert len(list(graph.objects(node, URIRef(TT + "status")))) == 1
        assert len(list(graph.objects(node, URIRef(TT + "dockedAt")))) <= 1
    assert first_violation(graph) is None
    assert (None, URIRef(TT + "status"), Literal("online")) in graph
