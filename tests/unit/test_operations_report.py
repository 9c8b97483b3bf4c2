"""The operations benchmark's report (benchmarks/_operations_report.py): differences and
targets pooled over the seeds on which both arms ran, cold start's two metrics, and the
pooling of split runs, which refuses outputs that are not one experiment."""

from __future__ import annotations

import json

import pytest
from benchmarks._operations_report import load_runs, pair, report, verdicts

from transfertwin.study.validation import newcombe_difference


def _arm(delivered, n, first_1=(0, 0), first_3=(0, 0)):
    return {"delivered": delivered, "n": n, "first_1": list(first_1), "first_3": list(first_3),
            "ops_per_floor_hour": 50.0, "ops_ci95": [40.0, 60.0], "campaign_floor_s": 0.0,
            "faults": 0, "twin_wrong": {}, "failed_by_reason": {}}  # fmt: skip


def _run(tmp_path, name, per_seed, regime="steady", orders=200):
    path = tmp_path / name
    path.write_text(json.dumps({"regime": regime, "plant_kind": "mismatch", "mismatch_off": [],
                                "floor": "large", "orders": orders, "seed": 0,
                                "per_seed": per_seed}))  # fmt: skip
    return path


def test_a_difference_is_pooled_over_the_seeds_both_arms_ran_on():
    per_seed = {31: {"learning-alone": _arm(160, 200), "calibrated": _arm(170, 200)},
                32: {"learning-alone": _arm(150, 200)}}  # fmt: skip
    a, b, seeds = pair(per_seed, "calibrated", "learning-alone", None)
    assert (a, b, seeds) == ((170, 200), (160, 200), [31])  # seed 32's learning not in it
    (t,) = [t for t in verdicts(per_seed, "steady", "mismatch") if "calibrated" in t["target"]]
    d = newcombe_difference(170, 200, 160, 200)
    assert t["ci95"] == [d.low, d.high] and t["seeds"] == [31]
    assert t["verdict"] == ("met" if d.low > -0.05 else "undecided")


def test_cold_start_reports_first_orders_and_first_three(capsys):
    per_seed = {31: {"learning-alone": _arm(40, 60, (10, 20), (40, 60)),
                     "calibrated": _arm(50, 60, (17, 20), (50, 60))}}  # fmt: skip
    out = report(per_seed, "cold-start", "mismatch", "title")
    assert out["pooled"]["calibrated"] == [17, 20]
    assert out["pooled"]["calibrated (first_3)"] == [50, 60]
    assert set(out["differences"]) == {"calibrated - learning-alone",
                                       "calibrated - learning-alone (first_3)"}
    (t,) = out["targets"]  # the calibrated-alone target has no arms here
    d = newcombe_difference(17, 20, 10, 20)  # targets on the first order
    assert t["ci95"] == [d.low, d.high]
    text = capsys.readouterr().out
    assert "each object's first three orders" in text


def test_what_the_twin_and_learning_are_worth_without_each_other_is_reported():
    per_seed = {31: {"learning-alone": _arm(37, 60, (12, 20), (46, 59)),
                     "twin-only": _arm(47, 60, (18, 20), (47, 60)),
                     "predictive": _arm(53, 59, (17, 20), (53, 59))}}  # fmt: skip
    out = report(per_seed, "cold-start", "bullet", "title")["differences"]
    d = newcombe_difference(18, 20, 12, 20)
    assert out["twin-only - learning-alone"]["ci95"] == [d.low, d.high]
    d = newcombe_difference(53, 59, 47, 60)
    assert out["predictive - twin-only (first_3)"]["ci95"] == [d.low, d.high]


def test_split_runs_pool_and_what_is_not_one_experiment_is_refused(tmp_path):
    a = _run(tmp_path, "a.json", {"31": {"calibrated": _arm(170, 198)}})
    b = _run(tmp_path, "b.json", {"32": {"calibrated": _arm(150, 200)},
                                  "31": {"learning-alone": _arm(167, 199)}})  # fmt: skip
    regime, kind, off, per_seed = load_runs([a, b])
    assert (regime, kind, off) == ("steady", "mismatch", [])
    assert per_seed == {31: {"calibrated": _arm(170, 198), "learning-alone": _arm(167, 199)},
                        32: {"calibrated": _arm(150, 200)}}  # fmt: skip
    with pytest.raises(ValueError, match="seed 31 arm calibrated is in two runs"):
        load_runs([a, a])
    other = _run(tmp_path, "c.json", {"33": {}}, regime="cold-start")
    with pytest.raises(ValueError, match="regime 'cold-start' differs"):
        load_runs([a, other])
    fewer = _run(tmp_path, "d.json", {"33": {}}, orders=100)
    with pytest.raises(ValueError, match="orders 100 differs"):
        load_runs([a, fewer])
    (tmp_path / "e.json").write_text("[]")
    with pytest.raises(ValueError, match=r"not an operations\.py output"):
        load_runs([tmp_path / "e.json"])
