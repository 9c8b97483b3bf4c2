"""The AAS HTTP API's answers (IDTA-01002 Part 2, SSP-002 read profiles) over the demo
floor's shells and submodels, without a floor running: identifiers base64url encoded,
paging, idShort paths, the $value/$metadata/$reference/$path forms, Part 2's error Result,
and the console's rules (read-only, its token off loopback)."""

from __future__ import annotations

import base64
import json

import pytest
from starlette.testclient import TestClient

from transfertwin.cps import build_representation, demo_descriptors
from transfertwin.web import WebConfig, create_app
from transfertwin.web._aas_model import (
    PROFILES,
    AasApiError,
    AasRepository,
    b64url,
    decode_b64url,
)

ID = "https://transfertwin.dev/ids"


@pytest.fixture(scope="module")
def repo() -> AasRepository:
    reps = [build_representation(d) for d in demo_descriptors()]
    return AasRepository([r.shell for r in reps], [s for r in reps for s in r.submodels])


def get(repo: AasRepository, path: str, **query: str | list[str]):
    q = {k: v if isinstance(v, list) else [v] for k, v in query.items()}
    answer = repo.answer(path, q)
    return answer.status, answer.body


def test_identifiers_are_base64url_with_or_without_padding() -> None:
    sm = f"{ID}/sm/TU_A/OperationalData"
    padded = base64.urlsafe_b64encode(sm.encode()).decode()
    assert "=" in padded and "=" not in b64url(sm)
    assert decode_b64url(padded, "id") == decode_b64url(b64url(sm), "id") == sm
    for bad in ("invalid-base64url=====", "a+b/", "%%%"):
        with pytest.raises(AasApiError) as exc:
            decode_b64url(bad, "id")
        assert exc.value.status == 400


def test_shells_are_paged_and_filtered_by_id_short_and_asset_id(repo) -> None:
    status, body = get(repo, "shells")
    assert status == 200 and len(body["result"]) == 14 and body["paging_metadata"] == {}
    _, first = get(repo, "shells", limit="5")
    _, rest = get(repo, "shells", limit="100", cursor=first["paging_metadata"]["cursor"])
    ids = [s["idShort"] for s in first["result"] + rest["result"]]
    assert ids == [s["idShort"] for s in body["result"]] and len(set(ids)) == 14
    assert [s["id"] for s in get(repo, "shells", idShort="TU_B")[1]["result"]] == [f"{ID}/aas/TU_B"]
    asset = b64url(json.dumps({"name": "globalAssetId", "value": f"{ID}/asset/KG"}))
    assert [s["idShort"] for s in get(repo, "shells", assetIds=asset)[1]["result"]] == ["KG"]
    assert get(repo, "shells", limit="-1")[0] == 400
    assert get(repo, "shells", cursor="x")[0] == 400
    assert get(repo, "shells", assetIds=b64url("not json"))[0] == 400


def test_a_shell_and_its_submodels_by_identifier(repo) -> None:
    shell = b64url(f"{ID}/aas/TU_A")
    status, body = get(repo, f"shells/{shell}")
    assert status == 200 and body["idShort"] == "TU_A"
    assert get(repo, f"shells/{shell}/asset-information")[1]["globalAssetId"] == f"{ID}/asset/TU_A"
    refs = get(repo, f"shells/{shell}/submodel-refs")[1]["result"]
    assert sorted(r["keys"][0]["value"].rsplit("/", 1)[1] for r in refs) == [
        "Capabilities", "ControlInterface", "Identification", "OperationalData"]  # fmt: skip
    data = b64url(f"{ID}/sm/TU_A/OperationalData")
    assert get(repo, f"shells/{shell}/submodels/{data}")[1]["idShort"] == "OperationalData"
    other = b64url(f"{ID}/sm/TU_B/OperationalData")  # a submodel of another shell
    assert get(repo, f"shells/{shell}/submodels/{other}")[0] == 404
    assert get(repo, f"shells/{b64url(ID + '/aas/TU_Z')}")[0] == 404
    status, body = get(repo, f"shells/{shell}/asset-information/thumbnail")
    assert status == 404 and body["messages"][0]["messageType"] == "Error"


def test_value_metadata_reference_and_path_forms(repo) -> None:
    caps = f"submodels/{b64url(ID + '/sm/TU_A/Capabilities')}"
    path = "TransferRelations.Constraints.BeltWidth"
    status, prop = get(repo, f"{caps}/submodel-elements/{path}")
    assert status == 200 and prop["modelType"] == "Property" and float(prop["value"]) > 0
    assert get(repo, f"{caps}/submodel-elements/{path}/$value")[1] == {
        "BeltWidth": pytest.approx(float(prop["value"]))}  # fmt: skip
    assert "value" not in get(repo, f"{caps}/submodel-elements/{path}/$metadata")[1]
    ref = get(repo, f"{caps}/submodel-elements/{path}/$reference")[1]
    assert [k["value"] for k in ref["keys"]] == [
        f"{ID}/sm/TU_A/Capabilities", "TransferRelations", "Constraints", "BeltWidth"]  # fmt: skip
    assert get(repo, f"{caps}/submodel-elements/{path}/$path")[0] == 400  # not a collection
    paths = get(repo, f"{caps}/submodel-elements/TransferRelations/$path")[1]
    assert paths[0] == "TransferRelations" and f"{path}" in paths
    values = get(repo, f"{caps}/$value")[1]
    assert "Transfer" not in values  # a Capability has no value
    assert values["TransferRelations"]["Constraints"]["BeltWidth"] == pytest.approx(
        float(prop["value"]))  # fmt: skip
    core = get(repo, caps, level="core")[1]
    relations = next(e for e in core["submodelElements"] if e["idShort"] == "TransferRelations")
    assert "value" not in relations  # core: the submodel's direct children only
    assert "submodelElements" not in get(repo, f"{caps}/$metadata")[1]
    assert get(repo, f"{caps}/submodel-elements/Transfer/$value")[0] == 400
    assert get(repo, f"{caps}/submodel-elements/Nope")[0] == 404
    assert get(repo, f"{caps}/submodel-elements/A..B")[0] == 400
    assert get(repo, caps, level="#####")[0] == 400


def test_serialization_description_and_unknown_resources(repo) -> None:
    env = get(repo, "serialization", aasIds=b64url(f"{ID}/aas/KG"),
              submodelIds=b64url(f"{ID}/sm/KG/OperationalData"))[1]  # fmt: skip
    assert [s["idShort"] for s in env["assetAdministrationShells"]] == ["KG"]
    assert [s["id"] for s in env["submodels"]] == [f"{ID}/sm/KG/OperationalData"]
    assert len(get(repo, "serialization")[1]["submodels"]) == len(repo.submodels)
    assert get(repo, "serialization", includeConceptDescriptions="invalid-bool")[0] == 400
    assert get(repo, "description")[1] == {"profiles": list(PROFILES)}
    assert get(repo, "registry")[0] == 404


def test_the_console_serves_it_read_only_with_its_token_off_loopback() -> None:
    cfg = WebConfig(host="0.0.0.0", token="correct-horse-battery")
    with TestClient(create_app(cfg), base_url="http://10.0.0.1",
                    raise_server_exceptions=False) as c:  # fmt: skip
        res = c.get("/aas-api/v3.0/shells")
        assert res.status_code == 401 and res.json()["messages"][0]["code"] == "401"
        auth = {"Authorization": "Bearer correct-horse-battery"}
        res = c.get("/aas-api/v3.0/shells", headers=auth)
        assert res.status_code == 404 and "no CPS" in res.json()["messages"][0]["text"]
        res = c.post("/aas-api/v3.0/shells", headers=auth, json={})
        assert res.status_code == 405 and res.headers["allow"] == "GET"
