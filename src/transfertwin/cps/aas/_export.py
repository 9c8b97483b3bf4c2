"""Write and strictly re-read AAS environments as JSON, XML or AASX (basyx adapters).

Writes are atomic: readers see the old file or the whole new one. Reading is strict
(basyx ``failsafe=False``): any defect raises instead of being logged and skipped.
"""

from __future__ import annotations

import datetime as dt
import io
import os
import uuid
from collections.abc import Sequence
from pathlib import Path

import pyecma376_2
from basyx.aas import model
from basyx.aas.adapter import aasx
from basyx.aas.adapter import json as aas_json
from basyx.aas.adapter import xml as aas_xml

from transfertwin._atomic import write_atomic
from transfertwin._errors import InputError
from transfertwin.cps.aas._representation import AssetRepresentation

__all__ = ["EXPORT_SUFFIXES", "export_aas", "read_export", "validate_export"]

EXPORT_SUFFIXES = (".json", ".xml", ".aasx")


def _suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in EXPORT_SUFFIXES:
        raise InputError(f"{path}: AAS export needs a suffix in {', '.join(EXPORT_SUFFIXES)}")
    return suffix


def _store(reps: Sequence[AssetRepresentation]) -> model.DictIdentifiableStore:
    if not reps:
        raise InputError("nothing to export: no asset representations given")
    store: model.DictIdentifiableStore = model.DictIdentifiableStore()
    for rep in reps:
        for identifiable in (rep.shell, *rep.submodels):
            if identifiable.id in store:
                raise InputError(f"duplicate AAS identifier {identifiable.id}")
            store.add(identifiable)
    return store


def export_aas(reps: Sequence[AssetRepresentation], path: str | Path) -> Path:
    """Write the shells and submodels of `reps` to one file, format by suffix.

    Args:
        reps: Representations to export (identifiers must be unique across them).
        path: ``*.json`` (AAS JSON), ``*.xml`` (AAS XML) or ``*.aasx`` (AASX package with
            an XML part and OPC core properties).

    Returns:
        The path written.

    Raises:
        InputError: Unknown suffix, missing folder, no representations, duplicate ids.
    """
    path = Path(path)
    suffix = _suffix(path)
    if not path.parent.is_dir():
        raise InputError(f"{path}: folder {path.parent} does not exist")
    store = _store(reps)
    if suffix == ".json":
        text = io.StringIO()
        aas_json.write_aas_json_file(text, store)
        return write_atomic(path, text.getvalue())
    if suffix == ".xml":
        data = io.BytesIO()
        aas_xml.write_aas_xml_file(data, store)
        return write_atomic(path, data.getvalue())
    return _write_aasx(path, store, [rep.shell.id for rep in reps])


def _write_aasx(path: Path, store: model.DictIdentifiableStore, shell_ids: list[str]) -> Path:
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex}.tmp")
    props = pyecma376_2.OPCCoreProperties()
    props.creator = "transfertwin"
    props.created = dt.datetime.now(dt.UTC)
    props.title = "transfertwin asset administration shells"
    try:
        with aasx.AASXWriter(tmp, failsafe=False) as writer:
            writer.write_aas(shell_ids, store, aasx.DictSupplementaryFileContainer())
            writer.write_core_properties(props)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def read_export(path: str | Path) -> model.DictIdentifiableStore:
    """Read a file written by `export_aas` strictly (basyx ``failsafe=False``).

    Raises:
        InputError: Unknown suffix, missing file, or any defect the basyx readers report.
    """
    path = Path(path)
    suffix = _suffix(path)
    if not path.is_file():
        raise InputError(f"{path}: no such file")
    try:
        if suffix == ".json":
            return aas_json.read_aas_json_file(path, failsafe=False)
        if suffix == ".xml":
            return aas_xml.read_aas_xml_file(path, failsafe=False)
        store: model.DictIdentifiableStore = model.DictIdentifiableStore()
        with aasx.AASXReader(path, failsafe=False) as reader:
            reader.read_into(store, aasx.DictSupplementaryFileContainer())
        return store
    except Exception as exc:  # the basyx readers raise many types (KeyError, lxml, …)
        first = (str(exc).strip().splitlines() or [""])[0]
        raise InputError(
            f"{path}: invalid AAS {suffix[1:]}: {type(exc).__name__}: {first}"
        ) from exc


def validate_export(path: str | Path) -> int:
    """Read an export back strictly and check that every shell's submodel references resolve.

    Returns:
        The number of identifiables (shells + submodels) in the file.

    Raises:
        InputError: Any reading defect, or a shell referencing a submodel not in the file.
    """
    store = read_export(path)
    for shell in store:
        if not isinstance(shell, model.AssetAdministrationShell):
            continue
        for ref in shell.submodel:
            target = ref.key[-1].value
            if target not in store:
                raise InputError(f"{path}: shell {shell.id} references missing submodel {target}")
    return len(store)
