"""`transfertwin cps query 'SPARQL'` against the test run's one running floor (conftest.py:
`plant_cps`): the graph's answer as a table and as JSON, an update refused with one line
(exit 2), a malformed query's error line."""

from __future__ import annotations

import json

from tests.integration.cps._cli import RunningCps, run_main

UNITS = """SELECT ?id ?station WHERE {
  ?a a tt:TransferUnit ; tt:assetId ?id ; tt:atStation ?s .
  BIND(STRAFTER(STR(?s), "/station/") AS ?station)
} ORDER BY ?id"""


def test_query_answers_as_a_table_and_as_json(plant_cps: RunningCps, capfd) -> None:
    wd = str(plant_cps.wd)
    res = run_main(capfd, "cps", "query", UNITS, "--workdir", wd, "--json")
    assert res.returncode == 0, res.stderr
    rows = json.loads(res.stdout)
    assert {"id": "TU_A", "station": "A"} in rows and {"id": "TU_D", "station": "D"} in rows
    res = run_main(capfd, "cps", "query", UNITS, "--workdir", wd)
    lines = res.stdout.splitlines()
    assert res.returncode == 0 and lines[0].split() == ["id", "station"]
    assert [line.split() for line in lines[1:]] == [[r["id"], r["station"]] for r in rows]


def test_an_update_and_a_malformed_query_are_refused_in_one_line(plant_cps, capfd) -> None:
    wd = str(plant_cps.wd)
    res = run_main(capfd, "cps", "query", "DELETE WHERE { ?s ?p ?o }", "--workdir", wd)
    assert res.returncode == 2 and res.stdout == ""
    assert len(res.stderr.strip().splitlines()) == 1
    assert "refused the query: not a SPARQL SELECT query (the graph is read-only)" in res.stderr
    still = run_main(capfd, "cps", "query", UNITS, "--workdir", wd, "--json")
    assert len(json.loads(still.stdout)) >= 4  # the graph is untouched
    res = run_main(capfd, "cps", "query", "SELECT ?x WHERE { ?x", "--workdir", wd)
    assert res.returncode == 2 and len(res.stderr.strip().splitlines()) == 1
    assert "refused the query" in res.stderr
