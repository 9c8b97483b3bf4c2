"""Object calibration without a scan: protrusion depth per face and the centre-of-mass shift
from real outcomes."""

from __future__ import annotations

import numpy as np

from transfertwin.data import calibration_csv_path
from transfertwin.objects import (
    Protrusion,
    ProxySpec,
    load_builtin,
    load_object,
    read_proxy,
    write_proxy,
)
from transfertwin.sim import SceneConfig
from transfertwin.store import read_results
from transfertwin.study.calibration import (
    JointCandidates,
    choose_joint,
    fit_proxy,
    fitted_candidates,
    load_candidates,
    save_candidates,
)
from transfertwin.study.calibration._replay import replay_specs
from transfertwin.study.experiment import run_rows


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
    assert face.positions is None and fit.spec.protrusions[0].x_frac == 0.5  # not searched
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


def test_the_fit_finds_a_planted_protrusion_position(tmp_path) -> None:
    """Synthetic 'real' rows from a proxy with a 20 mm feature at 25 % of the length; the
    fit, searching 0.25 beside the centre, reproduces them only at the planted position."""
    real = read_results(calibration_csv_path())
    back = [r for r in real if r["object_id"] == "o1" and r["face"] == "back"]
    rows = [back[i] for i in (2, 9, 1, 0)]
    truth = ProxySpec("o1", "o1", (Protrusion("back", 0.02, x_frac=0.25),))
    ref = str(write_proxy(truth, tmp_path / "truth.proxy.json"))
    specs = replay_specs(rows, scene=SceneConfig(), object_map={"o1": ref}, run=0, seed=0)
    planted = [int(r["status"] == "ok" and r["success"] == 1) for r in run_rows(specs, 1, None)]
    rows = [{**r, "success": s} for r, s in zip(rows, planted, strict=True)]
    fit = fit_proxy(rows, "o1", depths_m=[0.02], positions=[0.25], work_dir=tmp_path / "c",
                    scene=SceneConfig(), runs=1, workers=1, penalty=0.0,
                    position_penalty=0.0)  # fmt: skip
    (face,) = fit.faces
    assert list(face.depths_m) == [0.0, 0.02, 0.02] and list(face.positions) == [0.5, 0.5, 0.25]
    assert {p.name for p in (tmp_path / "c").iterdir()} == {
        "o1~back0.proxy.json", "o1~back20.proxy.json", "o1~back20~x0.25.proxy.json"}  # fmt: skip
    # common random numbers: the planted candidate repeats the rows exactly, the centred
    # one and the plain body do not
    assert list(face.probabilities[0, 2]) == planted
    assert list(face.probabilities[0, 1]) != planted and list(face.probabilities[0, 0]) != planted
    assert face.chosen == 2 and fit.spec.protrusions == truth.protrusions
    # the candidates file keeps the positions; `calibrate evaluate` repeats the choice
    ids = np.array([int(r["experiment_id"]) for r in real])
    joint, mask = load_candidates(save_candidates(fit, tmp_path / "o1.candidates.npz"), ids)["o1"]
    assert list(joint.positions["back"]) == [0.5, 0.5, 0.25]
    y = np.zeros(len(real), dtype=int)
    y[np.isin(ids, [int(r["experiment_id"]) for r in rows if r["success"] == 1])] = 1
    assert choose_joint(joint, y, np.flatnonzero(mask))["back"] == 2
    # a strong pull towards the centre: the data cannot pay for the move
    assert choose_joint(joint, y, np.flatnonzero(mask), position_penalty=1.0)["back"] != 2


def test_a_shipped_prior_is_kept_without_evidence_and_searched_around(tmp_path) -> None:
    """With the shipped features as the prior, a face with fewer than `min_rows` rows keeps
    its feature unsearched; a face with enough rows searches the prior's depth first, then
    the others by their distance from it (the penalty grows with that distance)."""
    import pytest

    from transfertwin._errors import InputError
    from transfertwin.objects import builtin_features

    prior = builtin_features("o1")  # front 4 mm, back 18 mm
    real = [r for r in read_results(calibration_csv_path()) if r["object_id"] == "o1"]
    rows = [r for r in real if r["face"] == "back"][:3] + [
        r for r in real if r["face"] == "front"][:1]  # fmt: skip
    fit = fit_proxy(rows, "o1", depths_m=[0.03], work_dir=tmp_path / "c", scene=SceneConfig(),
                    runs=1, workers=1, prior=prior, min_rows=2)  # fmt: skip
    (face,) = fit.faces  # front has one row: not searched
    assert face.face == "back" and list(face.depths_m) == [0.018, 0.03, 0.0]
    assert face.probabilities.shape == (1, 3, 3)
    depth = {p.face: p.depth_m for p in fit.spec.protrusions}
    assert depth["front"] == 0.004  # the prior, kept
    assert depth["back"] == face.depths_m[face.chosen]
    assert {p.name for p in (tmp_path / "c").iterdir()} == {
        "o1~back18.proxy.json", "o1~back30.proxy.json", "o1~back0.proxy.json"}  # fmt: skip
    # no face with enough rows: the proxy is the prior itself, nothing simulated
    none = fit_proxy(rows, "o1", depths_m=[0.03], work_dir=tmp_path / "d", scene=SceneConfig(),
                     runs=1, workers=1, prior=prior, min_rows=4)  # fmt: skip
    assert none.faces == () and none.spec.protrusions == tuple(sorted(prior, key=lambda p: p.face))
    with pytest.raises(InputError, match="not searched around a prior"):
        fit_proxy(rows, "o1", depths_m=[0.03], work_dir=tmp_path / "e", scene=SceneConfig(),
                  prior=prior, positions=(0.3, 0.5))  # fmt: skip
    with pytest.raises(InputError, match="min_rows"):
        fit_proxy(rows, "o1", depths_m=[0.03], work_dir=tmp_path / "e", scene=SceneConfig(),
                  prior=prior, min_rows=0)  # fmt: skip
