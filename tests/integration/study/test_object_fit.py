"""Object calibration without a scan: protrusion depth per face from real outcomes."""

from __future__ import annotations

import numpy as np

from transfertwin.data import calibration_csv_path
from transfertwin.objects import load_builtin, load_object, read_proxy
from transfertwin.sim import SceneConfig
from transfertwin.store import read_results
from transfertwin.study.calibration import fit_proxy, load_candidates, save_candidates


def test_deep_protrusion_catches_in_the_gap_and_the_fit_round_trips(tmp_path) -> None:
    rows = [r for r in read_results(calibration_csv_path()) if r["object_id"] == "o1"]
    rows = [r for r in rows if r["face"] == "back"][:5]  # real: 0 of these 5 succeed
    fit = fit_proxy(rows, "o1", depths_m=[0.03], work_dir=tmp_path / "c", scene=SceneConfig(),
                    runs=1, workers=1, penalty=0.0)  # fmt: skip
    (face,) = fit.faces
    assert face.face == "back" and list(face.depths_m) == [0.0, 0.03]
    assert face.probabilities.shape == (2, 5)
    # the plain core crosses every time; a 30 mm feature under the back face catches
    assert face.probabilities[0].mean() > face.probabilities[1].mean()
    assert face.chosen == 1 and fit.spec.protrusions[0].depth_m == 0.03
    ids = np.array([int(r["experiment_id"]) for r in read_results(calibration_csv_path())])
    cands = load_candidates(save_candidates(fit, tmp_path / "o1.candidates.npz"), ids)
    pred, mask = cands["o1:back"]
    assert mask.sum() == 5 and np.array_equal(pred[:, mask], face.probabilities)
    assert np.isnan(pred[:, ~mask]).all()
    spec = read_proxy(next((tmp_path / "c").glob("o1~back30.proxy.json")))
    assert len(load_object(str(tmp_path / "c" / "o1~back30.proxy.json")).hulls) == len(
        load_builtin("o1", features=False).hulls) + 1 and spec.base == "o1"  # fmt: skip
