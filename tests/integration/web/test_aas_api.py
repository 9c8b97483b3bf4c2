"""The floor's AAS HTTP API as the console serves it (`transfertwin web --cps`), checked by
the IDTA's own test engine (`aas-test-engines`) for every profile it claims, with values
read live from the assets' OPC UA servers; and the console's query box asking the knowledge
graph (slow: a floor, a console, ~1.5 min)."""

from __future__ import annotations

import json
import urllib.error
import urllib.parse
import urllib.request

import pytest
from aas_test_engines import api, config, http

from tests.integration.web.conftest import save_screenshot, wait_for
from transfertwin.web._aas_model import PROFILES, b64url

pytestmark = pytest.mark.slow

PREFIX = "/aas-api/v3.0"
ID = "https://transfertwin.dev/ids"


def _get(url: str):
    with urllib.request.urlopen(url, timeout=30) as res:
        return json.loads(res.read())


def _failures(result, path=()) -> list[str]:
    """The failed checks of a test engine result, each as the chain of its steps."""
    here = (*path, result.message.strip()[:120])
    failed = [s for s in result.sub_results if not s.ok()]
    if not result.ok() and not failed:
        return [" > ".join(here)]
    return [line for s in failed for line in _failures(s, here)]


def test_the_idta_test_engine_passes_every_claimed_profile_with_live_values(
    cps_workdir, console_factory
):
    console = console_factory("--cps", str(cps_workdir))

    def online():
        assets = _get(f"{console.base}/api/assets")["assets"]
        return all(a["reachable"] for a in assets) and assets

    assets = wait_for(online, 120, "every asset online")
    base = console.base + PREFIX
    assert _get(f"{base}/description")["profiles"] == list(PROFILES)
    for suite in PROFILES:
        result, _ = api.execute_tests(http.HttpClient(base), config.CheckApiConfig(suite=suite))
        assert _failures(result) == [], suite

    shells = _get(f"{base}/shells")["result"]
    assert sorted(s["idShort"] for s in shells) == sorted(a["id"] for a in assets)
    # values come from the servers: the graph's triple count (0 in its description), the
    # endpoint each asset serves at
    kg = _get(f"{base}/submodels/{b64url(ID + '/sm/KG/OperationalData')}/$value")
    assert kg["Triples"] > 0
    # the console's AAS panel names the shell's address in the API
    panel = _get(f"{console.base}/api/assets/TU_A/aas")
    assert panel["aas_api"] == f"{PREFIX}/shells/{b64url(ID + '/aas/TU_A')}"
    assert _get(console.base + panel["aas_api"])["idShort"] == "TU_A"
    # the console's query box asks the graph: rows, an update refused with the reason
    q = urllib.parse.quote("SELECT ?id WHERE { ?a a tt:TransferUnit ; tt:assetId ?id }")
    rows = _get(f"{console.base}/api/query?q={q}")["rows"]
    assert {r["id"] for r in rows} == {"TU_A", "TU_B", "TU_C", "TU_D"}
    with pytest.raises(urllib.error.HTTPError) as refused:
        _get(f"{console.base}/api/query?q={urllib.parse.quote('DELETE WHERE { ?s ?p ?o }')}")
    assert refused.value.code == 422
    assert "the graph is read-only" in json.loads(refused.value.read())["error"]
    ident = _get(f"{base}/submodels/{b64url(ID + '/sm/TU_A/Identification')}/$value")
    assert ident["Endpoint"] == next(a["endpoint"] for a in assets if a["id"] == "TU_A")


def test_browser_shows_the_api_address_and_answers_a_query(
    cps_workdir, console_factory, page, tmp_path
):
    from playwright.sync_api import expect

    console = console_factory("--cps", str(cps_workdir))
    page.goto(console.url)
    page.wait_for_selector("#asset-TU_A td.c-reachable.on", timeout=120_000)
    page.click("#asset-TU_A")
    link = page.locator("#aas-api a")
    expect(link).to_have_text(
        f"{console.base}{PREFIX}/shells/{b64url(ID + '/aas/TU_A')}", timeout=30_000
    )
    page.fill("#query-text", "SELECT ?id WHERE { ?a a tt:TransferUnit ; tt:assetId ?id }")
    page.click("#query-form button")
    expect(page.locator("#query-table tr")).to_have_count(5, timeout=30_000)  # header + 4
    assert page.inner_text("#query-table tr:nth-child(2) td") in {"TU_A", "TU_B", "TU_C", "TU_D"}
    page.fill("#query-text", "DELETE WHERE { ?s ?p ?o }")
    page.click("#query-form button")
    expect(page.locator("#query-result .error")).to_contain_text("the graph is read-only")
    save_screenshot(page, tmp_path, "web-console-query")
