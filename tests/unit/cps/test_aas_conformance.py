"""The AAS of every asset conforms to the AAS 3.1 metamodel, checked by implementations
other than the one that writes it (basyx writes; aas-core 3.1 and the IDTA's test engine
judge).

* aas-core 3.1 (`aas_core3_1.verification`): every constraint of the 3.1 metamodel, e.g.
  AASd-002's idShort pattern, which in 3.1 needs at least two characters.
* The IDTA's `aas-test-engines` (`check_json_file`, `check_xml_file`, `check_aasx_file`):
  it supports metamodel 3.0 only. JSON carries no version and is checked as it is; the XML
  namespace names the version (``https://admin-shell.io/aas/3/1`` here, ``…/3/0`` for the
  engine), so the XML and the AASX's XML part are checked with that one name rewritten to
  3.0 and nothing else changed.

The assets are those the floors serve (the demo floor on the emulated plant, whose physical
units add `RunTransfer`, and the large floor), as each node builds them for its OPC UA
server, and the files `cps export --with-physical` writes.
"""

from __future__ import annotations

import io
import json
import zipfile
from pathlib import Path

import aas_core3_1.jsonization as aas_core_json
import aas_core3_1.verification as aas_core_verification
import aas_core3_1.xmlization as aas_core_xml
import pytest
from aas_test_engines import file as test_engine
from basyx.aas import model
from basyx.aas.adapter import json as aas_json
from basyx.aas.adapter import xml as aas_xml

from tests.unit.cps._served import FLOORS, served
from transfertwin.cli import main
from transfertwin.cps.aas import AssetRepresentation

XMLNS_31 = b"https://admin-shell.io/aas/3/1"
XMLNS_30 = b"https://admin-shell.io/aas/3/0"


def store_of(reps: list[AssetRepresentation]) -> model.DictIdentifiableStore:
    store: model.DictIdentifiableStore = model.DictIdentifiableStore()
    for rep in reps:
        for identifiable in (rep.shell, *rep.submodels):
            store.add(identifiable)
    return store


def basyx_json(reps: list[AssetRepresentation]) -> str:
    text = io.StringIO()
    aas_json.write_aas_json_file(text, store_of(reps))
    return text.getvalue()


def basyx_xml(reps: list[AssetRepresentation]) -> bytes:
    data = io.BytesIO()
    aas_xml.write_aas_xml_file(data, store_of(reps))
    return data.getvalue()


def errors_31(environment) -> list[str]:
    return [f"{e.path}: {e.cause}" for e in aas_core_verification.verify(environment)]


def errors_30(result) -> list[str]:
    """The test engine's failed checks: the messages of its failing leaves."""
    if not result.sub_results:
        return [] if result.ok() else [result.message]
    return [m for sub in result.sub_results for m in errors_30(sub)]


@pytest.fixture(scope="module", params=sorted(FLOORS))
def floor_reps(request) -> tuple[str, list[AssetRepresentation]]:
    return request.param, served(FLOORS[request.param]())


def test_the_floors_cover_every_asset_class_and_the_plant(floor_reps) -> None:
    name, reps = floor_reps
    classes = {r.descriptor.asset_class for r in reps}
    assert classes >= {"transfer_unit", "transport_module", "object", "knowledge_graph",
                       "transport_module_system"}  # fmt: skip
    if name == "demo-plant":
        assert any(r.descriptor.asset_id == "TU_A_P" for r in reps)


def test_every_served_aas_meets_the_aas_3_1_metamodel_json(floor_reps) -> None:
    _, reps = floor_reps
    env = aas_core_json.environment_from_jsonable(json.loads(basyx_json(reps)))
    assert len(env.asset_administration_shells) == len(reps)
    assert errors_31(env) == []


def test_every_served_aas_meets_the_aas_3_1_metamodel_xml(floor_reps) -> None:
    _, reps = floor_reps
    env = aas_core_xml.environment_from_str(basyx_xml(reps).decode())
    assert len(env.asset_administration_shells) == len(reps)
    assert errors_31(env) == []


def test_the_idta_test_engine_passes_the_served_aas(floor_reps) -> None:
    _, reps = floor_reps
    as_30 = basyx_xml(reps).replace(XMLNS_31, XMLNS_30)
    assert errors_30(test_engine.check_json_file(io.StringIO(basyx_json(reps)))) == []
    assert errors_30(test_engine.check_xml_file(io.BytesIO(as_30))) == []


def test_the_engine_knows_3_0_only_and_the_xml_names_3_1(floor_reps) -> None:
    """The reason for the rewrite: when the engine learns 3.1, check the files unchanged."""
    _, reps = floor_reps
    assert set(test_engine.supported_versions()) == {"3.0"}
    assert XMLNS_31 in basyx_xml(reps)
    assert not test_engine.check_xml_file(io.BytesIO(basyx_xml(reps))).ok()


@pytest.fixture(scope="module")
def exported(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("export")
    files = {}
    for suffix in ("json", "xml", "aasx"):
        files[suffix] = folder / f"demo.{suffix}"
        assert main(["cps", "export", "--out", str(files[suffix]), "--with-physical"]) == 0
    return files


def aasx_xml_part(path: Path) -> bytes:
    with zipfile.ZipFile(path) as package:
        parts = [n for n in package.namelist() if n.endswith(".xml") and "aasx/" in n]
        assert len(parts) == 1, package.namelist()
        return package.read(parts[0])


def test_cps_export_files_meet_the_aas_3_1_metamodel(exported) -> None:
    envs = {
        "json": aas_core_json.environment_from_jsonable(json.loads(exported["json"].read_text())),
        "xml": aas_core_xml.environment_from_str(exported["xml"].read_text()),
        "aasx": aas_core_xml.environment_from_str(aasx_xml_part(exported["aasx"]).decode()),
    }
    for suffix, env in envs.items():  # 14 assets and the 10 virtual models' physical twins
        assert len(env.asset_administration_shells) == 24, suffix
        assert errors_31(env) == [], suffix


def test_the_idta_test_engine_passes_cps_export_files(exported, tmp_path) -> None:
    with exported["json"].open() as f:
        assert errors_30(test_engine.check_json_file(f)) == []
    as_30 = exported["xml"].read_bytes().replace(XMLNS_31, XMLNS_30)
    assert errors_30(test_engine.check_xml_file(io.BytesIO(as_30))) == []
    package = tmp_path / "demo-3.0.aasx"
    with zipfile.ZipFile(exported["aasx"]) as src, zipfile.ZipFile(package, "w") as dst:
        for item in src.infolist():
            data = src.read(item)
            if item.filename.endswith(".xml") and "aasx/" in item.filename:
                data = data.replace(XMLNS_31, XMLNS_30)
            dst.writestr(item, data)
    with package.open("rb") as f:
        assert errors_30(test_engine.check_aasx_file(f)) == []
