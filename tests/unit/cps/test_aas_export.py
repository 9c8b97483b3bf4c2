"""Export to AAS JSON/XML/AASX and strict read-back by basyx (Sec. 3.1, 5.3)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from basyx.aas import model
from basyx.aas.adapter import aasx

from transfertwin._errors import InputError
from transfertwin.cps.aas._demo import demo_descriptors
from transfertwin.cps.aas._export import export_aas, read_export, validate_export
from transfertwin.cps.aas._representation import (
    AssetRepresentation,
    build_representation,
    wire_signature,
)

# 14 shells; 3 submodels each; a ControlInterface for 4 TUs, 1 TM and 4 logical assets.
DEMO_IDENTIFIABLES = 14 + 14 * 3 + 4 + 1 + 4


@pytest.fixture(scope="module")
def reps() -> list[AssetRepresentation]:
    return [
        build_representation(d, endpoint=f"opc.tcp://127.0.0.1:{4840 + i}/{d.asset_id}")
        for i, d in enumerate(demo_descriptors())
    ]


def values(submodels) -> dict[tuple[str, str], object]:
    return {
        (sm.id_short, el.id_short): el.value
        for sm in submodels
        for el in sm.submodel_element
        if isinstance(el, model.Property)
    }


def submodels_of(store: model.DictIdentifiableStore, shell) -> list[model.Submodel]:
    return [store.get_item(ref.key[-1].value) for ref in shell.submodel]


@pytest.mark.parametrize("suffix", [".json", ".xml", ".aasx", ".JSON"])
def test_export_reads_back_strictly_with_same_content(
    reps: list[AssetRepresentation], tmp_path: Path, suffix: str
) -> None:
    path = export_aas(reps, tmp_path / f"demo{suffix}")
    assert validate_export(path) == DEMO_IDENTIFIABLES
    store = read_export(path)
    expected = {i.id for rep in reps for i in (rep.shell, *rep.submodels)}
    assert {i.id for i in store} == expected
    for rep in reps:
        shell = store.get_item(rep.shell.id)
        assert isinstance(shell, model.AssetAdministrationShell)
        assert (
            shell.asset_information.global_asset_id == rep.shell.asset_information.global_asset_id
        )
        back = submodels_of(store, shell)
        assert wire_signature(back) == wire_signature(rep)
        assert values(back) == values(rep.submodels)


def test_export_overwrites_and_leaves_no_temp_files(
    reps: list[AssetRepresentation], tmp_path: Path
) -> None:
    for suffix in (".json", ".xml", ".aasx"):
        export_aas(reps[:1], tmp_path / f"a{suffix}")
        export_aas(reps, tmp_path / f"a{suffix}")
        assert validate_export(tmp_path / f"a{suffix}") == DEMO_IDENTIFIABLES
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.aasx", "a.json", "a.xml"]


def test_aasx_has_core_properties(reps: list[AssetRepresentation], tmp_path: Path) -> None:
    path = export_aas(reps, tmp_path / "demo.aasx")
    with aasx.AASXReader(path, failsafe=False) as reader:
        props = reader.get_core_properties()
    assert props.creator == "transfertwin"
    assert props.created is not None


@pytest.mark.parametrize("name", ["demo.txt", "demo", "demo.json.gz"])
def test_unknown_suffix_is_refused(
    reps: list[AssetRepresentation], tmp_path: Path, name: str
) -> None:
    with pytest.raises(InputError, match="suffix"):
        export_aas(reps, tmp_path / name)
    with pytest.raises(InputError, match="suffix"):
        validate_export(tmp_path / name)
    assert list(tmp_path.iterdir()) == []


def test_nothing_duplicate_or_missing_folder_is_refused(
    reps: list[AssetRepresentation], tmp_path: Path
) -> None:
    with pytest.raises(InputError, match="nothing to export"):
        export_aas([], tmp_path / "a.json")
    with pytest.raises(InputError, match="duplicate"):
        export_aas([reps[0], build_representation(reps[0].descriptor)], tmp_path / "a.json")
    with pytest.raises(InputError, match="does not exist"):
        export_aas(reps, tmp_path / "missing" / "a.json")
    assert list(tmp_path.iterdir()) == []


def test_strict_read_rejects_a_bad_value_type(
    reps: list[AssetRepresentation], tmp_path: Path
) -> None:
    path = export_aas(reps[:1], tmp_path / "tu.json")
    text = path.read_text().replace('"xs:double"', '"xs:real"', 1)
    path.write_text(text)
    with pytest.raises(InputError, match="invalid AAS json"):
        validate_export(path)


def test_validate_rejects_a_dangling_submodel_reference(
    reps: list[AssetRepresentation], tmp_path: Path
) -> None:
    path = export_aas(reps[:1], tmp_path / "tu.json")
    env = json.loads(path.read_text())
    env["submodels"] = [sm for sm in env["submodels"] if sm["idShort"] != "OperationalData"]
    path.write_text(json.dumps(env))
    with pytest.raises(InputError, match="references missing submodel"):
        validate_export(path)


@pytest.mark.parametrize("suffix", [".json", ".xml", ".aasx"])
def test_garbage_file_is_an_input_error(tmp_path: Path, suffix: str) -> None:
    path = tmp_path / f"junk{suffix}"
    path.write_bytes(b"not an aas file")
    with pytest.raises(InputError, match="invalid AAS"):
        validate_export(path)
