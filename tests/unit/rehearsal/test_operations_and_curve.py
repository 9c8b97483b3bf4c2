"""Operations with predictions (Sec. 7.2), ablation parsing and the experiments-needed curve,
on synthetic rows (no simulation)."""

from __future__ import annotations

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.rehearsal import (
    HANDLING_S,
    RECOVERY_S,
    best_station,
    curve_document,
    f05_intervals,
    operation_summary,
    parse_ablations,
    twin_scene,
)
from transfertwin.report import write_rehearsal_curve_report
from transfertwin.sim import SceneConfig


def _ops(k: int, n: int, t: float = 10.0) -> list[dict[str, object]]:
    return [{"success": int(i < k), "transfer_time_s": t} for i in range(n)]


def test_operation_summary_intervals_and_rates() -> None:
    s = operation_summary({"twin": _ops(18, 20), "random": _ops(8, 20)})
    twin, rand = s["twin"], s["random"]
    assert (twin["k"], twin["n"], rand["k"]) == (18, 20, 8)
    assert twin["success_low"] < 0.9 < twin["success_high"]
    assert round(twin["success_low"], 3) == 0.699  # Wilson 95 % of 18/20
    assert s["success_above_random"] and s["success_diff_low"] > 0
    hours = (20 * (HANDLING_S + 10.0) + 2 * RECOVERY_S) / 3600
    assert twin["ops_per_hour"] == pytest.approx(18 / hours)
    assert twin["ops_per_hour_low"] < twin["ops_per_hour"] < twin["ops_per_hour_high"]
    assert s["ops_per_hour_ratio"] > 1
    same = operation_summary({"twin": _ops(10, 20), "random": _ops(10, 20)})
    assert not same["success_significant"] and same["success_diff"] == 0


def test_a_never_valid_operation_costs_t_max() -> None:
    s = operation_summary({"twin": _ops(0, 1, float("nan")), "random": _ops(1, 1)})
    t_max = SceneConfig().t_max_s
    assert s["twin"]["hours"] == pytest.approx((HANDLING_S + t_max + RECOVERY_S) / 3600)


def test_the_station_with_the_smaller_gap_area_is_chosen() -> None:
    logged = (("TU_A", 30.0), ("TU_A", 10.0), ("TU_B", 15.0), ("TU_B", 16.0))
    rows = [{"transfer_unit": u, "gap_area_cm2": g, "success": 1} for u, g in logged]
    assert best_station(rows) == "TU_B"
    with pytest.raises(InputError):
        best_station([])


def test_ablations_parse_and_switch_the_scene() -> None:
    assert parse_ablations(["mass", "stability, compliance", "mass"]) == (
        "mass", "stability", "compliance",
    )  # fmt: skip
    with pytest.raises(InputError, match="unknown counter-measure"):
        parse_ablations(["gravity"])
    on = twin_scene(SceneConfig(), ("stability", "compliance"))
    assert on.physics.guard and on.physics.feature_solref is not None
    off = twin_scene(SceneConfig(), ("mass",))
    assert off == SceneConfig()


def test_the_curve_is_written_with_its_plot(tmp_path) -> None:
    docs = [
        {"config": {"calibration_experiments": k, "objects": ["o3"]}, "f05_before": 0.5,
         "f05_after": 0.5 + k / 400, "f05_base_rate": 0.6, "significant_best": b,
         "significant_worst": 0, "held_out": k // 3, "plant_experiments": k + 10}
        for k, b in ((100, 0), (25, 1))
    ]  # fmt: skip
    doc = curve_document(docs)
    assert doc["calibration_experiments"] == [25, 100]
    assert [p["significant_best"] for p in doc["curve"]] == [1, 0]
    page = write_rehearsal_curve_report(doc, tmp_path).read_text()
    assert "data:image/png;base64," in page and "K25/report.html" in page
    assert (tmp_path / "curve.png").read_bytes()[:4] == b"\x89PNG"


def test_f05_intervals_are_paired_and_hold_the_point_estimate() -> None:
    # 12 held-out rows as in the small configuration: one run of each twin.
    y = np.array([1, 1, 0, 1, 1, 1, 0, 1, 0, 1, 1, 1])
    before = np.array([[1, 1, 0, 1, 0, 0, 0, 1, 1, 1, 1, 0]])
    after = np.array([[1, 1, 1, 1, 1, 0, 0, 1, 1, 1, 1, 1]])
    ci = f05_intervals({"before": before, "after": after}, y)
    assert set(ci) == {"before", "after", "base_rate", "after_minus_before"}
    for name, pred in (("before", before), ("after", after), ("base_rate", np.ones((1, 12)))):
        tp = int(((pred[0] == 1) & (y == 1)).sum())
        fp = int(((pred[0] == 1) & (y == 0)).sum())
        fn = int(((pred[0] == 0) & (y == 1)).sum())
        point = 1.25 * tp / (1.25 * tp + 0.25 * fn + fp)
        low, high = ci[name]
        assert low <= point <= high and high - low > 0.1  # 12 rows: a wide interval
    low, high = ci["after_minus_before"]
    assert low < 0 < high  # the two twins are not distinguishable on 12 rows
    same = f05_intervals({"before": before, "after": before}, y)["after_minus_before"]
    assert same == [0.0, 0.0]  # paired: the same rows in every resample
    assert f05_intervals({"after": after}, y) == {k: ci[k] for k in ("after", "base_rate")}
    with pytest.raises(InputError):
        f05_intervals({"after": after[:, :5]}, y)
    # any paired difference: an oracle's F0.5 minus the twin's, the same resamples
    oracle = y[None, :]
    gap = f05_intervals({"oracle": oracle, "after": after}, y,
                        differences=[("oracle", "after")])  # fmt: skip
    assert gap["after"] == ci["after"] and gap["oracle"] == [1.0, 1.0]
    low, high = gap["oracle_minus_after"]
    # the twin: 9 true positives, 2 false positives, 1 false negative
    assert 0 <= low <= 1 - 11.25 / 13.5 <= high and high > 0.2
    with pytest.raises(InputError, match="differences name no predictor: twin"):
        f05_intervals({"after": after}, y, differences=[("after", "twin")])


def test_curve_points_carry_the_intervals(tmp_path) -> None:
    doc = {"config": {"calibration_experiments": 25, "objects": ["o3"]}, "f05_before": 0.5,
           "f05_after": 0.6, "f05_base_rate": 0.6, "significant_best": 0,
           "significant_worst": 0, "held_out": 8, "plant_experiments": 40,
           "f05_before_ci": [0.2, 0.8], "f05_after_ci": [0.3, 0.9],
           "f05_base_rate_ci": [0.4, 0.8], "f05_delta_ci": [-0.3, 0.4]}  # fmt: skip
    point = curve_document([doc])["curve"][0]
    assert point["f05_after_ci"] == [0.3, 0.9] and point["f05_delta_ci"] == [-0.3, 0.4]
    page = write_rehearsal_curve_report(curve_document([doc]), tmp_path).read_text()
    assert "0.600 [0.30, 0.90]" in page and "[-0.30, 0.40]" in page


def test_test_experiments_have_their_own_design_and_lift_the_split_limit() -> None:
    from transfertwin.rehearsal import RehearsalConfig, calibration_design

    cal = calibration_design(("o3", "o7"), 20, 0)
    test = calibration_design(("o3", "o7"), 20, 0, "test")
    assert test == calibration_design(("o3", "o7"), 20, 0, "test")  # reproducible
    assert [r.object_id for r in test] == [r.object_id for r in cal]  # objects in turn
    assert [(r.face, r.theta_deg) for r in test] != [(r.face, r.theta_deg) for r in cal]
    with pytest.raises(InputError):
        RehearsalConfig(plant_seed=1, objects=("o3",), calibration_experiments=2)
    cfg = RehearsalConfig(plant_seed=1, objects=("o3",), calibration_experiments=2,
                          test_experiments=10)  # fmt: skip
    assert cfg.test_experiments == 10
    with pytest.raises(InputError):
        RehearsalConfig(plant_seed=1, objects=("o3",), calibration_experiments=20,
                        test_experiments=-1)  # fmt: skip
