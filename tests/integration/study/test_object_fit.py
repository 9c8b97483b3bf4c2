"""Object calibration without a scan: protrusion depth per face and the centre-of-mass shift
from real outcomes."""

from __future__ import annotations

import numpy as np

from transfertwin.data import calibration_csv_path
from transfertwin.objects import load_builtin, load_object, read_proxy
from transfertwin.sim import SceneConfig
from transfertwin.store import read_results
from transfertwin.study.calibration import (
    JointCandidates,
    fit_proxy,
    fitted_candidates,
    load_candidates,
    save_candidates,
)


def test_deep_protrusion_catches_in_the_gap_and_the_fit_round_trips(tmp_path) -> None:
    rows = [r for r in read_results(calibration_csv_path()) if r["object_id"] == "o1"]
    rows = [r for r in rows if r["face"] == "back"][:5]  # real: 0 of these 5 succeed
    fit = fit_proxy(rows, "o1", depths_m=[0.03], work_dir=tmp_path / "c", scene=SceneConfig(),
                    runs=1, workers=1, penalty=0.0)  # fmt: skip
    (face,) = fit.faces
    assert face.face == "back" and list(face.depths_m) == [0.0, 0.03]
    assert list(fit.shifts_m) == [0.0] and face.probabilities.shape == (1, 2, 5)
    # the plain core crosses every time; a 30 mm feature under the back face catches
    assert face.probabilities[0, 0].mean() > face.probabilities[0, 1].mean()
    assert face.chosen == 1 and fit.spec.protrusions[0].depth_m == 0.03
    assert fit.spec.com_shift_m == 0.0
    assert abs(fit.front_fraction - fit.uniform_front_fraction) < 1e-9
    ids = np.array([int(r["experiment_id"]) for r in read_results(calibration_csv_path())])
    cands = load_candidates(save_candidates(fit, tmp_path / "o1.candidates.npz"), ids)
    joint, mask = cands["o1"]
    assert isinstance(joint, JointCandidates) and mask.sum() == 5
    assert np.array_equal(joint.faces["back"][:, :, mask], face.probabilities)
    assert np.isnan(joint.faces["back"][:, :, ~mask]).all()
    spec = read_proxy(next((tmp_path / "c").glob("o1~back30.proxy.json")))
    assert len(load_object(str(tmp_path / "c" / "o1~back30.proxy.json")).hulls) == len(
        load_builtin("o1", features=False).hulls) + 1 and spec.base == "o1"  # fmt: skip


def test_the_mass_distribution_is_searched_jointly_with_the_depths(tmp_path) -> None:
    real = read_results(calibration_csv_path())
    rows = [r for r in real if r["object_id"] == "o1"]
    rows = [r for r in rows if r["face"] == "back"][:2] + [
        r for r in rows if r["face"] == "front"][:1]  # fmt: skip
    fit = fit_proxy(rows, "o1", depths_m=[0.03], shifts_m=[0.02], work_dir=tmp_path / "c",
                    scene=SceneConfig(), runs=1, workers=1, penalty=0.0,
                    shift_penalty=0.0)  # fmt: skip
    assert list(fit.shifts_m) == [0.0, 0.02]
    assert [f.probabilities.shape for f in fit.faces] == [(2, 2, 2), (2, 2, 1)]
    assert {p.name for p in (tmp_path / "c").iterdir()} >= {
        "o1~back30~com+20.proxy.json", "o1~front0~com+20.proxy.json"}  # fmt: skip
    shifted = load_object(str(tmp_path / "c" / "o1~back30~com+20.proxy.json"))
    assert abs(shifted.mass.com_m[0] - 0.02) < 1e-6
    assert fit.spec.com_shift_m == fit.shifts_m[fit.shift_chosen]
    save_candidates(fit, tmp_path / "o1.candidates.npz")
    subset = [r for r in real if r in rows]
    cands, groups = fitted_candidates(tmp_path, subset)
    assert list(cands) == ["o1"] and set(groups) == {"o1"}
