"""Nested CV of the twin beside the baselines (issue 29): the choice among candidate folders
happens inside the training rows, the figures come out where the answer is known."""

from __future__ import annotations

import numpy as np
import pytest

from transfertwin.study.calibration import (
    PREDICTORS,
    Variant,
    fidelity_report,
    held_out,
    leave_cell_out,
    rate_table,
    report_lines,
    select_variant,
)


def _rows(n_per_cell: int = 20, seed: int = 0) -> tuple[list[dict[str, object]], np.ndarray]:
    """Rows over 2 objects x 2 faces x 2 conveyors whose success depends on the yaw (which
    no rate table sees): q = 0.95 for sin(theta) > 0, else 0.1; o2's cells succeed more."""
    rng = np.random.default_rng(seed)
    rows, truth = [], []
    for obj in ("o1", "o2"):
        for face in ("front", "back"):
            for conveyor in ("left", "right"):
                for _ in range(n_per_cell):
                    theta = float(rng.uniform(-180, 180))
                    q = 0.95 if np.sin(np.radians(theta)) > 0 else (0.1 if obj == "o1" else 0.4)
                    rows.append({"object_id": obj, "face": face, "conveyor": conveyor,
                                 "theta_deg": theta, "success": int(rng.random() < q),
                                 "dock_err_x_mm": float(rng.normal()),
                                 "dock_err_y_mm": float(rng.normal()),
                                 "dock_err_theta_deg": float(rng.normal())})  # fmt: skip
                    truth.append(q)
    return rows, np.array(truth)


def _variants(rows, truth) -> list[Variant]:
    objects = np.array([str(r["object_id"]) for r in rows])
    rng = np.random.default_rng(5)
    noise = rng.random(len(rows))
    bad = Variant("bad", {o: noise[None, :] for o in ("o1", "o2")}, objects)
    good = Variant("good", {o: truth[None, :] for o in ("o1", "o2")}, objects)
    return [bad, good]


def test_the_folder_is_chosen_on_training_rows_and_blind_to_the_rest() -> None:
    rows, truth = _rows()
    y = np.array([int(r["success"]) for r in rows])
    variants = _variants(rows, truth)
    train = np.arange(0, len(y), 2)
    assert select_variant(variants, y, train, (0.0,)) == (1, 0.0)
    assert select_variant(variants[::-1], y, train, (0.0, 0.1)) == (0, 0.0)
    flipped = y.copy()
    flipped[1::2] = 1 - flipped[1::2]  # the rows outside `train`
    assert select_variant(variants, flipped, train, (0.0,)) == (1, 0.0)
    flipped_train = y.copy()
    flipped_train[train] = 1 - flipped_train[train]  # the truth is now backwards
    assert select_variant(variants, flipped_train, train, (0.0,)) == (0, 0.0)


def test_nested_cv_scores_every_predictor_on_the_same_folds_and_is_deterministic() -> None:
    rows, truth = _rows(n_per_cell=12)
    y = np.array([int(r["success"]) for r in rows])
    ho = held_out(rows, _variants(rows, truth), seeds=2, penalties=(0.0,))
    assert set(ho.p) == set(PREDICTORS) and ho.p["twin"].shape == (2, len(y))
    assert not np.isnan(ho.p["twin"]).any() and ho.folds == 5
    assert ho.chosen == {("good", 0.0): 10}
    f = {k: np.mean([np.mean(b == y) for b in ho.bits[k]]) for k in PREDICTORS}
    assert f["twin"] > f["table_object_face"] + 0.1  # the yaw signal only the twin knows
    assert np.all(ho.bits["always_success"])
    again = held_out(rows, _variants(rows, truth), seeds=2, penalties=(0.0,))
    for k in PREDICTORS:
        assert np.array_equal(ho.p[k], again.p[k])
    np.testing.assert_allclose(ho.twin_raw, np.tile(truth, (2, 1)))


def test_a_held_out_cell_falls_back_to_the_coarser_table_and_the_twin_still_knows_it() -> None:
    rows, truth = _rows()
    y = np.array([int(r["success"]) for r in rows])
    ho, cells = leave_cell_out(rows, _variants(rows, truth), ("object_id", "face", "conveyor"),
                               penalties=(0.0,))  # fmt: skip
    assert ho.folds == 8 and len(np.unique(cells)) == 8
    of = np.array([f"{r['object_id']}|{r['face']}" for r in rows])
    first = np.flatnonzero(cells == 0)
    expected = rate_table(of, y, np.flatnonzero(cells != 0))[first]
    np.testing.assert_allclose(ho.p["table_object_face_conveyor"][0, first], expected)
    np.testing.assert_allclose(ho.p["table_object_face"][0, first], expected)
    acc = {k: np.mean(ho.bits[k][0] == y) for k in PREDICTORS}
    assert acc["twin"] > acc["table_object_face"] + 0.1


def test_report_names_the_raw_share_outside_the_real_interval_and_what_was_chosen_on_all_rows(
) -> None:  # fmt: skip
    rows, truth = _rows(n_per_cell=12)
    objects = np.array([str(r["object_id"]) for r in rows])
    raw = np.where(objects == "o2", 1.0, truth)  # o2 always succeeds in 'simulation'
    variants = [Variant("one", {o: raw[None, :] for o in ("o1", "o2")}, objects)]
    report = fidelity_report(rows, variants, seeds=1, penalties=(0.0,), n_resamples=30)
    cores = report["raw_shares"]["cores"]
    assert cores["o2"]["held_out_raw"] == 1.0 and not cores["o2"]["held_out_inside"]
    assert cores["o2"]["real_ci"][1] < 1.0
    assert cores["o1"]["held_out_raw"] == pytest.approx(truth[objects == "o1"].mean())
    assert set(report["scores"]) == set(PREDICTORS)
    assert {"twin - table_object_face", "twin - always_success"} <= set(report["paired"])
    assert set(report["leave_cell_out"]) == {"object_face_conveyor", "object_face"}
    assert "1 scene variant(s) given" in report["made_on_all_rows"][0]
    assert report["chosen_in_folds"] == {"one penalty 0": 5}
    text = "\n".join(report_lines(report))
    assert "o2: real" in text and "OUTSIDE" in text and "made on all rows" in text
    lo, hi = report["scores"]["twin"]["f05_ci"]
    assert lo <= report["scores"]["twin"]["f05"] <= hi
