"""The built-in cores' shipped resting features and the family prior they are drawn from."""

from __future__ import annotations

import json

import numpy as np
import pytest

from transfertwin.objects import (
    Protrusion,
    builtin_ids,
    features_document,
    features_version,
    load_builtin,
    prior_features,
)
from transfertwin.objects._builtin import cores_data_dir, load_builtin_from

SHIPPED = json.loads(cores_data_dir().joinpath("features.json").read_text())


def _deepest_below(model, face: str) -> float:
    """How far the lowest hull point lies below the plain body's resting plane on ``face``."""
    body = np.vstack(load_builtin(model.object_id, features=False).hulls)[:, 2]
    z = np.vstack(model.hulls)[:, 2]
    return float(body.min() - z.min()) if face == "front" else float(z.max() - body.max())


def test_every_core_lists_one_feature_per_face() -> None:
    assert sorted(SHIPPED["cores"], key=lambda k: int(k[1:])) == builtin_ids()
    for prots in SHIPPED["cores"].values():
        assert sorted(p["face"] for p in prots) == ["back", "front"]
    assert {k for k, v in SHIPPED["source"].items() if v == "calibrated"} >= {"o1", "o32"}


@pytest.mark.parametrize("object_id", ["o1", "o18", "o32", "o3"])
def test_a_loaded_core_hangs_its_features_below_each_face(object_id: str) -> None:
    model = load_builtin(object_id)
    for p in SHIPPED["cores"][object_id]:
        assert _deepest_below(model, p["face"]) == pytest.approx(p["depth_m"], abs=1e-9)
    body = load_builtin(object_id, features=False)
    extra = sum(p["depth_m"] > 0 for p in SHIPPED["cores"][object_id])
    assert len(model.hulls) == len(body.hulls) + extra
    assert model.mass.mass_kg == body.mass.mass_kg  # the features add no mass
    np.testing.assert_array_equal(model.mass.inertia_kg_m2, body.mass.inertia_kg_m2)
    assert model.spec == body.spec and model.source == "builtin"


def test_a_folder_without_features_gives_plain_bodies(tmp_path) -> None:
    import shutil

    src = cores_data_dir()
    for name in ("manifest.json", "o1.stl", "o1.hulls.npz"):
        shutil.copyfile(str(src.joinpath(name)), tmp_path / name)
    plain = load_builtin_from(tmp_path, "o1")
    assert len(plain.hulls) == len(load_builtin("o1", features=False).hulls)


def test_prior_resamples_calibrated_faces_deterministically() -> None:
    calibrated = {
        "o1": (Protrusion("back", 0.026), Protrusion("front", 0.0)),
        "o2": (Protrusion("back", 0.0), Protrusion("front", 0.012)),
    }
    draws = [prior_features(i, calibrated) for i in range(3, 40)]
    assert draws == [prior_features(i, calibrated) for i in range(3, 40)]
    fronts = {d[0].depth_m for d in draws}
    backs = {d[1].depth_m for d in draws}
    assert fronts == {0.0, 0.012} and backs == {0.026, 0.0}  # both values of each face occur
    doc = features_document(calibrated, ["o1", "o2", "o3"], note="n")
    assert doc["source"] == {"o1": "calibrated", "o2": "calibrated", "o3": "prior"}
    with pytest.raises(ValueError, match="calibrated"):
        prior_features(3, {})


def test_features_version_is_the_shipped_file_hash() -> None:
    import hashlib

    data = cores_data_dir().joinpath("features.json").read_bytes()
    assert features_version() == hashlib.sha256(data).hexdigest()[:16]
