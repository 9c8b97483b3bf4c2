"""`cps up --plant-seed N`: the emulated plant as the CPS's physical assets (issue 12, item 1).

The test run's one `cps up --plant-seed` (conftest.py: `plant_cps`, shared with the CLI
tests; its start dominates, every test after it takes seconds). The Experiment Manager runs
E^P on the physical units over OPC UA; the same plant seed gives the same E^P rows as a
fresh plant fed the same requests; nothing the twin can reach — the physical servers'
address spaces, the knowledge graph, cps.json, the log, the AAS — holds a hidden parameter
of the plant, and the CPS touches the plant only through its public methods.
"""

from __future__ import annotations

import ast
import asyncio
import csv
import dataclasses
import json
import math
import re
from pathlib import Path

import pytest
from asyncua import ua

from tests.integration.cps._cli import PLANT_SEED as SEED
from tests.integration.cps._cli import RunningCps, run_main

PHYSICAL = ("TU_A_P", "TU_B_P", "TU_C_P", "TU_D_P")
SRC = Path(__file__).resolve().parents[3] / "src" / "transfertwin"


def _experiment(cps: RunningCps, capfd, *args: str) -> list[dict]:
    res = run_main(capfd, "cps", "experiment", "--workdir", str(cps.wd), *args)
    assert res.returncode == 0 and res.stderr == "", res.stderr
    return [json.loads(line) for line in res.stdout.splitlines()]


def test_plant_units_join_beside_the_virtual_models(plant_cps, capfd):
    assert plant_cps.first_line.startswith("CPS up: 18 assets"), plant_cps.first_line
    info = json.loads((plant_cps.wd / "cps.json").read_text())
    kinds = {a["id"]: (a["kind"], a["class"], a["type"]) for a in info["assets"]}
    for unit in PHYSICAL:
        assert kinds[unit] == ("physical", "transfer_unit", "D/E")
        assert kinds[unit.removesuffix("_P")][0] == "virtual_model"
    assert plant_cps.stderr_path.read_text() == ""
    st = run_main(capfd, "cps", "status", "--workdir", str(plant_cps.wd), "--json")
    assert st.returncode == 0, st.stderr
    rows = {a["id"]: a for a in json.loads(st.stdout)["assets"]}
    assert (rows["TU_C_P"]["kind"], rows["TU_C_P"]["class"]) == ("physical", "transfer_unit")
    assert rows["TU_C_P"]["online"] and rows["TU_C"]["kind"] == "virtual_model"
    # The TMS moves the floor's objects between its units; the plant's own unit is no place
    # in its ledger.
    res = run_main(capfd, *plant_cps.order_args("TU_A_P", "TU_C", "o1"))
    assert res.returncode == 2 and "TU_A_P" in res.stderr, res.stderr


def test_em_runs_e_p_over_opc_ua_in_the_e_v_record_shape(plant_cps, capfd):
    from transfertwin.cps import PHYSICAL_RECORD_EXTRA
    from transfertwin.store import RESULT_COLUMNS

    physical = _experiment(plant_cps, capfd, "--unit", "TU_A", "--physical", "--object", "o2",
                           "--face", "front", "--conveyor", "both", "--theta", "30",
                           "--runs", "2")  # fmt: skip
    physical += _experiment(plant_cps, capfd, "--unit", "TU_C_P", "--object", "o3", "--face",
                            "back", "--conveyor", "left", "--theta", "0")  # fmt: skip
    (virtual,) = _experiment(plant_cps, capfd, "--unit", "TU_A", "--object", "o2", "--face",
                             "front", "--conveyor", "both", "--theta", "30",
                             "--seed", "4")  # fmt: skip
    assert list(virtual) == list(RESULT_COLUMNS)  # E^V, unchanged by the plant
    assert virtual["y1"] in (0, 1) and virtual["state_pre"]
    # as `transfer --json` prints it: the state a list, the runs numbered 0..N-1
    assert isinstance(virtual["state_pre"], list) and virtual["run"] == 0
    assert [r["run"] for r in physical] == [0, 1, 0]
    for rec in physical:
        assert list(rec) == [*RESULT_COLUMNS, *PHYSICAL_RECORD_EXTRA]
        assert rec["kind"] == "physical" and rec["status"] == "ok"
        assert rec["success"] in (0, 1) and rec["y1"] is None and rec["state_pre"] is None
        assert math.isfinite(rec["dock_err_x_mm"]) and rec["t_end_s"] > 0
    assert [r["transfer_unit"] for r in physical] == ["TU_A", "TU_A", "TU_C"]
    ids = [r["experiment_id"] for r in physical]
    assert ids == sorted(ids) and len(set(ids)) == 3

    # Logged as a real calibration table that `calibrate --real` accepts.
    from transfertwin.store import read_results
    from transfertwin.study.calibration import check_real_rows

    rows = read_results(plant_cps.wd / "assets" / "EM" / "plant_experiments.csv")
    check_real_rows(rows, "plant_experiments.csv")
    logged = {int(r["experiment_id"]): r for r in rows}
    for rec in physical:
        row = logged[rec["experiment_id"]]
        assert (row["success"], row["dock_err_x_mm"]) == (rec["success"], rec["dock_err_x_mm"])


def test_the_same_plant_seed_gives_the_same_e_p_rows(plant_cps, capfd):
    from transfertwin.plant import PLANT_COLUMNS, EmulatedPlant, PlantRequest

    _experiment(plant_cps, capfd, "--unit", "TU_B_P", "--object", "o5", "--face", "front",
                "--conveyor", "right", "--theta", "0")  # fmt: skip
    with (plant_cps.wd / "assets" / "EM" / "plant_experiments.csv").open(newline="") as fh:
        reader = csv.DictReader(fh)
        assert tuple(reader.fieldnames or ()) == PLANT_COLUMNS
        rows = [{k: _typed(k, v) for k, v in r.items()} for r in reader]
    requests = [
        PlantRequest(r["object_id"], r["face"], r["conveyor"], r["theta_deg"], r["transfer_unit"])
        for r in rows
    ]
    # A fresh plant of the same seed, fed the CPS's requests in its order: the same rows.
    fresh = EmulatedPlant(SEED).run(requests)
    assert rows == fresh
    other = EmulatedPlant(SEED + 1).run(requests)  # the comparison can fail
    assert [r["dock_err_x_mm"] for r in other] != [r["dock_err_x_mm"] for r in fresh]


def _typed(column: str, text: str) -> object:
    if column in ("experiment_id", "theta_deg", "success"):
        return int(text)
    if column in ("transfer_unit", "object_id", "face", "conveyor"):
        return text
    return float(text)


def _hidden_numbers(seed: int, objects) -> list[float]:
    from transfertwin.plant._truth import draw_docking, draw_object, draw_scene

    out: list[float] = []

    def walk(v) -> None:
        if dataclasses.is_dataclass(v):
            v = dataclasses.asdict(v)
        if isinstance(v, dict):
            v = list(v.values())
        if isinstance(v, list | tuple):
            for x in v:
                walk(x)
        elif isinstance(v, float) and v != 0.0:
            out.append(v)

    walk([draw_scene(seed), draw_docking(seed), *(draw_object(seed, o) for o in objects)])
    return out


def _patterns(values: list[float]) -> re.Pattern:
    texts = set()
    for v in values:
        scaled = [v, v * 1000] + ([math.degrees(v)] if abs(v) < 0.05 else [])
        for s in scaled:
            texts |= {repr(s), f"{s:.4f}", f"{s:.5f}", f"{s:.6f}"}
    texts = {t for t in texts if len(t.split(".")[-1]) >= 3 and t.strip("-0.")}
    alternatives = "|".join(re.escape(t) for t in sorted(texts, key=len, reverse=True))
    return re.compile(rf"(?<![\d.])(?:{alternatives})(?!\d)")


_FORBIDDEN = {"mass", "friction", "mu", "com", "depth", "protrusion", "protrusions", "solref",
              "flip", "truth", "hidden", "seed", "pitch", "gap", "sigma", "offset", "compliance",
              "inertia", "scale"}  # fmt: skip


#: Capability constraints a unit advertises (the object mass range it accepts, from the
#: built-in cores' published models; its belts, from the twin's layout): no value of the
#: plant, though their names or round values may match the list above or a drawn value.
_PUBLIC_CONSTRAINTS = {"ObjectMassMin", "ObjectMassMax", "BeltLength", "BeltWidth"}


def _words(name: str) -> set[str]:
    return {w.lower() for w in re.findall(r"[A-Z]?[a-z]+|[A-Z]+(?![a-z])", name)}


async def _browse(node, found: dict, skip: set) -> None:
    """Every node under `node`: names, description, and the value of each variable. Level by
    level, each level's attributes, values and children in one request each (a node at a
    time took ~2,000 round trips per unit)."""
    ids = ua.AttributeIds
    client = node.session  # the client's UaClient
    level = [node.nodeid]
    while level:
        level = list(dict.fromkeys(n for n in level if n not in found and n not in skip))
        if not level:
            return
        names = [ids.BrowseName, ids.DisplayName, ids.Description, ids.NodeClass]
        attrs = await _read(client, [(n, a) for n in level for a in names])
        entries = {}
        for k, nid in enumerate(level):
            name, display, desc, cls = (v.Value.Value if v.Value else None
                                        for v in attrs[4 * k: 4 * k + 4])  # fmt: skip
            entries[nid] = (cls, {"name": name.Name, "display": display.Text or "",
                                  "description": (desc.Text or "") if desc else "",
                                  "value": None})  # fmt: skip
        variables = [n for n, (cls, _) in entries.items() if cls == ua.NodeClass.Variable]
        for nid, value in zip(variables, await _read(client, [(n, ids.Value) for n in variables]),
                              strict=True):  # fmt: skip
            entries[nid][1]["value"] = value.Value.Value if value.Value else None
        for nid, (_, entry) in entries.items():
            found[nid] = entry
        level = await _children(client, level)


async def _read(client, pairs: list) -> list:
    """DataValues of (NodeId, attribute) pairs, in one Read."""
    if not pairs:
        return []
    params = ua.ReadParameters()
    for nid, attr in pairs:
        rv = ua.ReadValueId()
        rv.NodeId, rv.AttributeId = nid, attr
        params.NodesToRead.append(rv)
    return await client.read(params)


async def _children(client, nodes: list) -> list:
    """The hierarchical forward references' targets of `nodes` (what Node.get_children
    gives), in one Browse (and BrowseNext while a node has more)."""
    params = ua.BrowseParameters()
    params.View = ua.ViewDescription()
    params.RequestedMaxReferencesPerNode = 0
    for nid in nodes:
        desc = ua.BrowseDescription()
        desc.NodeId = nid
        desc.BrowseDirection = ua.BrowseDirection.Forward
        desc.ReferenceTypeId = ua.NodeId(ua.ObjectIds.HierarchicalReferences)
        desc.IncludeSubtypes = True
        desc.NodeClassMask = ua.NodeClass.Unspecified
        desc.ResultMask = ua.BrowseResultMask.All
        params.NodesToBrowse.append(desc)
    out = []
    for result in await client.browse(params):
        refs = list(result.References)
        cont = result.ContinuationPoint
        while cont:
            (more,) = await client.browse_next(_next(cont))
            refs += more.References
            cont = more.ContinuationPoint
        out += [r.NodeId for r in refs]
    return out


def _next(continuation: bytes):
    params = ua.BrowseNextParameters()
    params.ReleaseContinuationPoints = False
    params.ContinuationPoints = [continuation]
    return params


def test_nothing_the_twin_can_reach_holds_a_hidden_parameter(plant_cps, capfd):
    from transfertwin.cps import plant_descriptors
    from transfertwin.cps.aas import build_representation, export_aas
    from transfertwin.cps.opcua import connect, load_credentials

    _experiment(plant_cps, capfd, "--unit", "TU_D_P", "--object", "o4", "--face", "back",
                "--conveyor", "both", "--theta", "60")  # fmt: skip
    wd = plant_cps.wd
    info = json.loads((wd / "cps.json").read_text())
    creds = load_credentials(wd / "credentials.json")
    objects = [f"o{i}" for i in range(1, 38)]
    hidden = _hidden_numbers(SEED, objects)
    assert len(hidden) > 300
    pattern = _patterns(hidden)
    from transfertwin.plant._truth import draw_object, draw_scene

    # The search finds the truth wherever it is written down (the test can fail).
    assert pattern.search(json.dumps(dataclasses.asdict(draw_scene(SEED))))
    assert pattern.search(f"depth {draw_object(SEED, 'o2').com_offset_m[0] * 1000:.4f} mm")
    seed_text = re.compile(rf"(?<![\d.]){SEED}(?![\d.])")

    async def browse_and_query() -> tuple[dict, list]:
        found: dict = {}
        for i, unit in enumerate(PHYSICAL):
            url = next(a["endpoint"] for a in info["assets"] if a["id"] == unit)
            async with connect(url, unit, credentials=creds, role="viewer",
                               cert_dir=wd / "certs") as session:  # fmt: skip
                objects = session.client.nodes.objects
                # the standard Server object once (it is the same on every unit)
                skip = {session.client.nodes.server.nodeid} if i else set()
                await _browse(objects, found, skip)
        kg_url = next(a["endpoint"] for a in info["assets"] if a["id"] == "KG")
        async with connect(kg_url, "KG", credentials=creds, cert_dir=wd / "certs") as kg:
            triples = json.loads(await kg.call("Query", "SELECT ?s ?p ?o WHERE { ?s ?p ?o }"))
        return found, triples

    found, triples = asyncio.run(browse_and_query())
    assert len(found) > 200 and len(triples) > 100
    own = [e for nid, e in found.items() if nid.NamespaceIndex != 0]
    assert {"RunTransfer", "BeltSpeedLeft", "DockedTransportModule"} <= {e["name"] for e in own}
    for e in own:  # the names of the units' own nodes say nothing of the truth
        if e["name"] in _PUBLIC_CONSTRAINTS:
            continue
        assert not (_words(e["name"]) | _words(e["display"])) & _FORBIDDEN, e
    # a capability's constraints are the twin's public layout and models (a belt 0.5 m
    # long): a round number the plant may draw too says nothing of it
    values = [e["value"] for e in found.values() if e["name"] not in _PUBLIC_CONSTRAINTS]
    for v in values:
        if isinstance(v, float) and v:
            assert all(abs(v - h) > 1e-9 * max(1.0, abs(h)) for h in hidden), v
    texts = {
        "address space": json.dumps(
            [str(v) for v in values] + [e["description"] for e in found.values()]
        ),
        "knowledge graph": json.dumps(triples),
        "cps.json": (wd / "cps.json").read_text(),
        "cps.log": (wd / "cps.log").read_text(),
        "plant log": (wd / "assets" / "EM" / "plant_experiments.csv").read_text(),
    }
    reps = [build_representation(d, endpoint="opc.tcp://h:1/x") for d in plant_descriptors()]
    texts["AAS"] = export_aas(reps, wd.parent / "physical.json").read_text()
    for where, text in texts.items():
        hit = pattern.search(text)
        assert hit is None, (where, hit and text[max(0, hit.start() - 80) : hit.end() + 80])
    for where in ("address space", "knowledge graph", "cps.json", "AAS"):
        assert not seed_text.search(texts[where]), where  # not even the plant seed


def test_the_cps_touches_the_plant_only_through_its_public_methods(monkeypatch):
    """Statically: only `cps.roles._plant_unit` names the plant, and there only `stations`
    and `operate` of it; only `cps.hal._local` names the plant's physics (a plant floor's
    module), and there only `PlantPhysics(seed).system` (and `check_camera`, which reads the
    plant's kind, a setting); at run time: a recording plant
    sees nothing else."""
    from transfertwin.cps.roles import _plant_unit
    from transfertwin.plant import EmulatedPlant, PlantRequest

    for path in [*(SRC / "cps").rglob("*.py"), *(SRC / "web").rglob("*.py"),
                 SRC / "cli" / "_cps.py"]:  # fmt: skip
        text = path.read_text()
        assert "_EmulatedPlant__" not in text and "plant._" not in text, path
        assert "_PlantPhysics__" not in text, path
        if path.relative_to(SRC).as_posix() == "cps/hal/_local.py":
            assert "EmulatedPlant" not in text
            tree = ast.parse(text)
            assert {a.name for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)
                    and n.module == "transfertwin.plant" for a in n.names} == {
                "PlantPhysics", "check_camera"}  # a kind's camera refused: no hidden value
            assert {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)
                    and isinstance(n.value, ast.Name) and n.value.id == "physics"} == {"system"}
        elif path.name != "_plant_unit.py":
            imported = {n.module for n in ast.walk(ast.parse(text))
                        if isinstance(n, ast.ImportFrom) and n.module}  # fmt: skip
            assert not any(m.startswith("transfertwin.plant") for m in imported), path
            assert "EmulatedPlant" not in text, path
    tree = ast.parse((SRC / "cps" / "roles" / "_plant_unit.py").read_text())
    used = {
        node.attr
        for node in ast.walk(tree)
        if isinstance(node, ast.Attribute)
        and isinstance(node.value, ast.Attribute)
        and node.value.attr == "__plant"
    }
    assert used == {"stations", "operate"}

    touched: list[str] = []

    class Recording:
        def __init__(self, seed: int, kind: str = "in-class", *,
                     mismatch_off: tuple[str, ...] = ()) -> None:  # fmt: skip
            self._real = EmulatedPlant(seed, kind, mismatch_off=mismatch_off)

        def __getattr__(self, name: str):
            touched.append(name)
            return getattr(self._real, name)

    monkeypatch.setattr("transfertwin.plant.EmulatedPlant", Recording)
    plant = _plant_unit.PhysicalPlant(SEED)
    assert "TU_A" in plant.stations
    row = plant.cycle(PlantRequest("o1", "front", "left", 0, "TU_A"))
    assert row["transfer_unit"] == "TU_A" and "transfer_time_s" in row
    assert set(touched) == {"stations", "operate"}
    with pytest.raises(TypeError):
        __import__("pickle").dumps(plant)


def test_experiment_on_a_physical_unit_needs_a_plant():
    from transfertwin._errors import InputError
    from transfertwin.cli._cps import _experiment_unit

    twin = {"assets": [{"id": u, "class": "transfer_unit"} for u in ("TU_A", "TU_B")]}
    with pytest.raises(InputError, match=r"no physical assets; start it with .*--plant-seed"):
        _experiment_unit(twin, "TU_A", physical=True)
    with_plant = {"assets": [*twin["assets"], {"id": "TU_A_P", "class": "transfer_unit"}]}
    assert _experiment_unit(with_plant, "TU_A", physical=True) == "TU_A_P"
    assert _experiment_unit(with_plant, "TU_A_P", physical=False) == "TU_A_P"
    with pytest.raises(InputError, match="no such transfer unit"):
        _experiment_unit(with_plant, "TU_B", physical=True)
