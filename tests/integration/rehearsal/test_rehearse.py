"""`rehearse` end to end on a tiny configuration; the twin's inputs are only plant rows."""

from __future__ import annotations

import csv
import json
import stat
from pathlib import Path

import pytest

from transfertwin.plant import PLANT_COLUMNS, EmulatedPlant
from transfertwin.rehearsal import REHEARSAL_KEYS, RehearsalConfig, rehearse
from transfertwin.rehearsal import _rehearse as module

TINY = RehearsalConfig(
    plant_seed=2, objects=("o3",), calibration_experiments=4, runs=1, validation_runs=1,
    theta_step=180, depths_mm=(16.0,), tune_trials=1,
)  # fmt: skip


@pytest.fixture(scope="module")
def tiny(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict, list]:
    out = tmp_path_factory.mktemp("rehearsal")
    seen: list[tuple[str, object]] = []
    mp = pytest.MonkeyPatch()
    for name in ("calibrate", "fit_proxy", "tune_tpe", "_docking_model"):
        original = getattr(module, name)

        def spy(*args, _name=name, _original=original, **kwargs):
            seen.append((_name, (args, kwargs)))
            return _original(*args, **kwargs)

        mp.setattr(module, name, spy)
    try:
        doc = rehearse(TINY, out)
    finally:
        mp.undo()
    return out, doc, seen


@pytest.mark.slow
def test_tiny_rehearsal_writes_every_key(tiny) -> None:
    out, doc, _ = tiny
    on_disk = json.loads((out / "rehearsal.json").read_text())
    assert set(REHEARSAL_KEYS) <= set(on_disk)
    with (out / "plant_validation.csv").open() as fh:
        validation = list(csv.DictReader(fh))
    assert on_disk["plant_experiments"] == 4 + len(validation) > 4
    assert 0.0 <= on_disk["f05_before"] <= 1.0 and 0.0 <= on_disk["f05_after"] <= 1.0
    assert set(on_disk["objects"]) == {"o3"}
    assert (out / "objects" / "o3.proxy.json").is_file()
    assert "x_frac" not in on_disk["objects"]["o3"]["calibration"]  # positions not searched
    assert doc["virtual_experiments"] > 0
    # The plant's seed is in the owner-only plant.secret beside the record, not in it.
    assert "plant_seed" not in on_disk["config"] and "plant_seed" not in doc["config"]
    secret = out / "plant.secret"
    assert secret.read_text() == f"{TINY.plant_seed}\n"
    assert stat.S_IMODE(secret.stat().st_mode) == 0o600
    tuned = on_disk["tuned_scene"]  # one TPE trial over mu and gap, inside their bounds
    assert set(tuned) == {"mu", "gap_mm", "f05"}
    assert 0.3 <= tuned["mu"] <= 0.7 and 8.0 <= tuned["gap_mm"] <= 18.0


@pytest.mark.slow
def test_the_twin_sees_only_plant_rows(tiny) -> None:
    out, _, seen = tiny
    with (out / "plant_calibration.csv").open() as fh:
        logged = [tuple(r.values()) for r in csv.DictReader(fh)]
    names = {name for name, _ in seen}
    assert {"calibrate", "fit_proxy", "tune_tpe", "_docking_model"} <= names
    for name, (args, kwargs) in seen:
        rows = args[0]
        assert rows, name
        for r in rows:
            assert tuple(r) == PLANT_COLUMNS, name  # exactly the real table's columns
            assert tuple(str(v) for v in r.values()) in logged, name
        for value in (*args, *kwargs.values()):
            assert not isinstance(value, EmulatedPlant), name


@pytest.mark.slow
def test_ablation_and_operations_on_a_tiny_rehearsal(tmp_path: Path) -> None:
    from dataclasses import replace

    cfg = replace(TINY, ablate=("mass", "compliance"), operations=2)
    doc = rehearse(cfg, tmp_path)
    assert doc["counter_measures"] == ["mass", "stability", "compliance"]
    assert set(doc["ablations"]) == {"mass", "compliance"}
    mass = doc["ablations"]["mass"]
    assert mass["counter_measures"] == ["stability", "compliance"]
    assert mass["delta_f05_after"] == pytest.approx(mass["f05_after"] - doc["f05_after"])
    assert (tmp_path / "ablate-mass" / "objects" / "o3.proxy.json").is_file()
    with_mass = json.loads((tmp_path / "objects" / "o3.proxy.json").read_text())
    without = json.loads((tmp_path / "ablate-mass" / "objects" / "o3.proxy.json").read_text())
    assert "mass_kg" in with_mass and "mass_kg" not in without
    ops = doc["operations"]
    assert ops["twin"]["n"] == ops["random"]["n"] == 2
    assert doc["plant_experiments"] > 4 + ops["plant_experiments"]
    assert json.loads((tmp_path / "operations.json").read_text())["orders"] == 2


@pytest.mark.slow
def test_separate_test_experiments_score_and_never_calibrate(tmp_path: Path) -> None:
    from dataclasses import replace

    seen: list[tuple[str, list]] = []
    mp = pytest.MonkeyPatch()
    for name in ("calibrate", "fit_proxy"):
        original = getattr(module, name)

        def spy(*args, _name=name, _original=original, **kwargs):
            seen.append((_name, list(args[0])))
            return _original(*args, **kwargs)

        mp.setattr(module, name, spy)
    try:
        doc = rehearse(replace(TINY, test_experiments=2), tmp_path)
    finally:
        mp.undo()
    assert (doc["held_out"], doc["training"]) == (2, 4)
    with (tmp_path / "plant_test.csv").open() as fh:
        test = [int(r["experiment_id"]) for r in csv.DictReader(fh)]
    with (tmp_path / "plant_calibration.csv").open() as fh:
        calibration = [int(r["experiment_id"]) for r in csv.DictReader(fh)]
    assert test == [0, 1] and calibration == [2, 3, 4, 5]  # test experiments run first
    fitted = {int(r["experiment_id"]) for name, rows in seen if name == "fit_proxy" for r in rows}
    assert fitted and fitted <= set(calibration)
    scored = [[int(r["experiment_id"]) for r in rows] for name, rows in seen if name == "calibrate"]
    assert scored == [test, test]  # before and after calibration, on the test experiments only
    assert doc["plant_experiments"] >= 6


@pytest.mark.slow
def test_proxy_positions_reach_the_object_calibration(tmp_path: Path) -> None:
    from dataclasses import replace

    from transfertwin.objects import read_proxy

    seen: list[dict] = []
    mp = pytest.MonkeyPatch()
    original = module.fit_proxy

    def spy(*args, **kwargs):
        seen.append(kwargs)
        return original(*args, **kwargs)

    mp.setattr(module, "fit_proxy", spy)
    try:
        doc = rehearse(replace(TINY, proxy_positions=(0.3, 0.7)), tmp_path)
    finally:
        mp.undo()
    assert [kw["positions"] for kw in seen] == [(0.3, 0.7)]
    fit = doc["objects"]["o3"]["calibration"]
    spec = read_proxy(tmp_path / fit["proxy"])
    assert fit["x_frac"] == {p.face: p.x_frac for p in spec.protrusions}
    assert all(p.x_frac in (0.3, 0.5, 0.7) for p in spec.protrusions)
