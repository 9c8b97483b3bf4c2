"""KPIs from the TMS's operation records (docs/architecture.md, "Operation")."""

from __future__ import annotations

import pytest
from scipy.stats import beta

from transfertwin.cps.dispatch._kpis import kpis, with_calibration


def _op(i, submitted, assigned, finished, status, module="TM_1", steps=(), floor_s=100.0,
        failed_step=None):  # fmt: skip
    result = {"status": status, "floor_s": floor_s}
    if failed_step:
        result["failed_step"] = failed_step
    return {"operation": f"op{i}", "state": "finished", "submitted": submitted,
            "assigned": assigned, "finished": finished, "module": module,
            "steps": [list(s) for s in steps], "result": result}  # fmt: skip


def test_kpis_of_three_finished_operations():
    ops = [
        _op(1, 0.0, 10.0, 110.0, "delivered",
            steps=[(10, "navigating", "TU_A"), (20, "docking", "TU_A"),
                   (30, "transferring", "TU_A"), (50, "navigating", "TU_B"),
                   (60, "transferring", "TU_B")]),
        _op(2, 0.0, 110.0, 210.0, "failed at delivery", failed_step="transferring"),
        _op(3, 50.0, 60.0, 360.0, "delivered", module="TM_2", floor_s=300.0),
    ]
    k = kpis(ops, ["TM_1", "TM_2", "TM_3"], ["TU_A", "TU_B"], now=400.0)
    assert (k["orders"], k["finished"], k["delivered"], k["failed"]) == (3, 3, 2, 1)
    assert k["window_s"] == 360.0
    assert k["operations_per_hour"] == pytest.approx(3600 * 2 / 360)
    assert k["floor_makespan_s"] == 300.0  # TM_1: 100 + 100, TM_2: 300
    assert k["operations_per_floor_hour"] == pytest.approx(3600 * 2 / 300)
    assert k["success_share"] == pytest.approx(2 / 3)
    low, high = k["success_share_ci95"]  # Clopper–Pearson (Eq. 6.27)
    assert low == pytest.approx(beta.ppf(0.025, 2, 2)) and high == pytest.approx(
        beta.ppf(0.975, 3, 1))
    assert k["mean_lead_time_s"] == pytest.approx((110 + 210 + 310) / 3)
    util = k["utilisation"]
    assert util["modules"] == {"TM_1": round(200 / 360, 4), "TM_2": round(300 / 360, 4),
                               "TM_3": 0.0}  # fmt: skip
    # TU_A docked 20..50 (docking, transferring), TU_B 60..110 (transferring to the end)
    assert util["units"] == {"TU_A": round(30 / 360, 4), "TU_B": round(50 / 360, 4)}
    assert k["failed_by_reason"] == {"failed while transferring": 1}


def test_kpis_of_a_floor_without_orders_and_with_one_running():
    empty = kpis([], ["TM_1"], ["TU_A"], now=5.0)
    assert (empty["orders"], empty["success_share"], empty["mean_lead_time_s"]) == (0, None, None)
    assert empty["success_share_ci95"] == [None, None]
    running = {"operation": "op1", "state": "running", "submitted": 0.0, "assigned": 1.0,
               "module": "TM_1", "steps": [[2.0, "docking", "TU_A"]], "result": None}
    k = kpis([running], ["TM_1"], ["TU_A"], now=10.0)
    assert (k["in_progress"], k["window_s"]) == (1, 10.0)
    assert k["utilisation"]["modules"]["TM_1"] == 0.9
    assert k["utilisation"]["units"]["TU_A"] == 0.8


def test_a_fault_is_counted_apart_from_the_transfer_outcomes():
    """A module that went offline mid-transfer (or restarted) is a fault of the floor, not
    a failed transfer: the success share and its interval are over the outcomes only."""
    lapsed = _op(3, 0.0, 1.0, 50.0, "failed while transferring", failed_step="transferring")
    lapsed["result"].update(reason="TM_1 went offline (lease expired) while transferring",
                            fault=True)
    restarted = _op(4, 0.0, 1.0, 60.0, "failed while docking", failed_step="docking")
    restarted["result"]["reason"] = "TM_1 restarted while docking"  # a record without the flag
    ops = [_op(1, 0.0, 1.0, 10.0, "delivered"),
           _op(2, 0.0, 1.0, 20.0, "failed at pick-up", failed_step="transferring"),
           lapsed, restarted]  # fmt: skip
    k = kpis(ops, ["TM_1"], ["TU_A"], now=100.0)
    assert (k["finished"], k["delivered"], k["failed"], k["faults"]) == (4, 1, 1, 2)
    assert k["success_share"] == pytest.approx(1 / 2)  # 1 of the 2 transfer outcomes
    low, high = k["success_share_ci95"]
    assert low == pytest.approx(beta.ppf(0.025, 1, 2)) and high == pytest.approx(
        beta.ppf(0.975, 2, 1))
    assert k["failed_by_reason"] == {"failed while transferring": 1}
    assert k["faults_by_reason"] == {"TM_1 restarted while docking": 1,
                                     "TM_1 went offline (lease expired) while transferring": 1}


def test_cps_kpis_prints_the_faults_apart_from_the_failures():
    """`cps kpis` without --json says how many orders ended in a fault and why (found by
    hand: a module killed mid-transfer was in the JSON only, the text said 0 failed)."""
    from transfertwin.cli._cps_ops import kpi_lines

    lapsed = _op(2, 0.0, 1.0, 50.0, "failed while transferring", failed_step="transferring")
    lapsed["result"].update(reason="TM_1 went offline (lease expired) while transferring",
                            fault=True)
    k = {"policy": "predictive", **kpis([_op(1, 0.0, 1.0, 10.0, "delivered"), lapsed],
                                        ["TM_1"], ["TU_A"], now=100.0)}
    lines = kpi_lines(k)
    assert lines[0] == ("policy predictive: 2 orders, 1 delivered, 0 failed, 1 faults, "
                        "0 in progress")
    assert ("faults (not transfer outcomes, not in the share): TM_1 went offline (lease "
            "expired) while transferring: 1") in lines
    k_clean = {"policy": "predictive", **kpis([_op(1, 0.0, 1.0, 10.0, "delivered")],
                                              ["TM_1"], ["TU_A"], now=100.0)}
    assert not any(line.startswith("faults") for line in kpi_lines(k_clean))


def test_calibration_floor_time_is_a_cost_shared_by_the_modules() -> None:
    k = {"delivered": 6, "floor_makespan_s": 1800.0, "operations_per_floor_hour": 12.0}
    out = with_calibration(k, 1200.0, modules=2)  # 1800 s + 1200 s / 2 modules
    assert out["calibration_floor_s"] == 1200.0
    assert out["operations_per_floor_hour_with_calibration"] == pytest.approx(3600 * 6 / 2400)
    assert out["operations_per_floor_hour"] == 12.0  # the floor's own figure stays
    assert with_calibration(k, 0.0, 2)["operations_per_floor_hour_with_calibration"] == 12.0
    empty = {"delivered": 0, "floor_makespan_s": 0.0}
    assert with_calibration(empty, 0.0, 1)["operations_per_floor_hour_with_calibration"] is None
