"""Virtual vs physical comparison per state (Sec. 6.7) and its plot data (Fig. 6.24/6.25).

Expected values are hand-derived (counts, p̂, which states and objects differ) or
published: Clopper–Pearson 95 % bounds 9/10 → [0.5550, 0.9975] and 3/10 →
[0.0667, 0.6525]; Newcombe (1998) Table II, method 10: 9/10 − 3/10 →
[0.1705, 0.8090].
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import pytest
from matplotlib.figure import Figure

from transfertwin._errors import InputError
from transfertwin.report._figure import figure_png
from transfertwin.report._validation_plots import (
    plot_validation,
    validate_and_report,
    validation_plot_data,
)
from transfertwin.study.validation import (
    VALIDATION_COLUMNS,
    DifferenceInterval,
    StateComparison,
    compare,
    summary_json_text,
    validate,
    validation_csv_text,
)

A = ("o1", "front", "left", 0)  # 9/10 virtual vs 3/10 physical: significant
B = ("o1", "back", "both", 90)  # 5/10 vs 5/10: not significant
C = ("o2", "front", "right", 0)  # 10/10 vs 8/10: not significant
V_ONLY = ("o2", "back", "left", -10)  # run only virtually
P_ONLY = ("o3", "front", "both", 45)  # run only physically
INVALID_P = ("o2", "front", "both", 60)  # physical side has only 'invalid' rows


def rows(state: tuple, k: int, n: int, status: str = "ok") -> list[dict]:
    obj, face, conveyor, theta = state
    return [
        {"object_id": obj, "face": face, "conveyor": conveyor, "theta_deg": theta,
         "success": int(i < k), "status": status}
        for i in range(n)
    ]  # fmt: skip


def virtual() -> list[dict]:
    return [*rows(A, 9, 10), *rows(A, 0, 3, "error"), *rows(B, 5, 10), *rows(C, 10, 10),
            *rows(V_ONLY, 2, 4), *rows(INVALID_P, 3, 5)]  # fmt: skip


def physical() -> list[dict]:
    return [*rows(A, 3, 10), *rows(B, 5, 10), *rows(C, 8, 10), *rows(P_ONLY, 1, 2),
            *rows(INVALID_P, 0, 2, "invalid")]  # fmt: skip


def test_sec_6_7_compare_states_on_both_sides_by_hand() -> None:
    comps = compare(virtual(), physical())
    assert [c.key for c in comps] == [A, B, C]  # natural object order, face, conveyor, θ
    a = comps[0]
    assert (a.n_v, a.k_v, a.p_v, a.n_p, a.k_p, a.p_p) == (10, 9, 0.9, 10, 3, 0.3)  # errors left out
    assert (a.ci_v_low, a.ci_v_high) == pytest.approx((0.5550, 0.9975), abs=5e-5)
    assert (a.ci_p_low, a.ci_p_high) == pytest.approx((0.0667, 0.6525), abs=5e-5)
    assert (a.diff_low, a.diff_high) == pytest.approx((0.1705, 0.8090), abs=5e-5)
    assert a.difference.estimate == pytest.approx(0.6)
    assert [c.significant for c in comps] == [True, False, False]
    b = comps[1]
    assert b.diff_low == pytest.approx(-b.diff_high)  # equal proportions: symmetric interval


def test_sec_6_7_alpha_widens_and_narrows_every_interval() -> None:
    wide = compare(virtual(), physical(), alpha=0.01)[0]
    narrow = compare(virtual(), physical(), alpha=0.2)[0]
    assert wide.alpha == 0.01
    assert wide.ci_v_low < narrow.ci_v_low and wide.diff_high > narrow.diff_high


def test_sec_6_7_no_common_state_gives_an_empty_comparison() -> None:
    assert compare(rows(A, 1, 2), rows(B, 1, 2)) == []


def test_sec_6_7_significance_needs_zero_strictly_outside() -> None:
    assert not DifferenceInterval(0.0, 0.5, 0.2).excludes_zero
    assert not DifferenceInterval(-0.5, 0.0, -0.2).excludes_zero
    assert DifferenceInterval(1e-9, 0.5, 0.2).excludes_zero
    assert DifferenceInterval(-0.5, -1e-9, -0.2).excludes_zero


def test_state_comparison_round_trips_through_a_dict() -> None:
    comp = compare(virtual(), physical())[0]
    assert StateComparison.from_dict(json.loads(json.dumps(comp.to_dict()))) == comp


def test_sec_6_7_validate_counts_unmatched_states_and_objects() -> None:
    result = validate(virtual(), physical())
    assert result.virtual_only == (INVALID_P, V_ONLY)  # front before back; INVALID_P not run
    assert result.physical_only == (P_ONLY,)
    assert result.object_ids == ("o1", "o2")
    assert result.differing_objects == ("o1",)
    assert result.summary_line == "1/2 objects differ"
    summary = json.loads(summary_json_text(result))
    assert summary["summary"] == "1/2 objects differ"
    assert summary["difference_interval"] == "newcombe-hybrid-score"
    assert (summary["states_compared"], summary["states_significant"]) == (3, 1)
    assert (summary["states_virtual_only"], summary["states_physical_only"]) == (2, 1)
    assert summary["objects"]["o1"] == {
        "states_compared": 2, "states_significant": 1, "states_virtual_only": 0,
        "states_physical_only": 0, "differs": True,
    }  # fmt: skip
    assert summary["objects"]["o2"]["differs"] is False
    assert summary["objects"]["o2"]["states_virtual_only"] == 2
    assert summary["objects"]["o3"]["differs"] is None  # nothing compared


def test_sec_6_7_validation_csv_header_and_rows() -> None:
    text = validation_csv_text(compare(virtual(), physical()))
    lines = text.splitlines()
    assert lines[0] == (
        "object_id,face,conveyor,theta_deg,n_v,k_v,p_v,n_p,k_p,p_p,diff_low,diff_high,significant"
    )
    assert tuple(lines[0].split(",")) == VALIDATION_COLUMNS
    records = list(csv.DictReader(io.StringIO(text)))
    assert [r["significant"] for r in records] == ["1", "0", "0"]
    assert records[0]["p_v"] == "0.9" and records[2]["k_p"] == "8"
    assert float(records[0]["diff_low"]) == pytest.approx(0.1705, abs=5e-5)


def test_sec_6_7_validate_writes_csv_and_json(tmp_path: Path) -> None:
    out = tmp_path / "nested" / "val"
    result = validate(virtual(), physical(), out)
    assert (out / "validation.csv").read_text() == validation_csv_text(result.comparisons)
    assert json.loads((out / "summary.json").read_text()) == result.to_dict()
    assert sorted(p.name for p in out.iterdir()) == ["summary.json", "validation.csv"]


def test_sec_6_7_no_common_state_is_an_input_error_and_writes_nothing(tmp_path: Path) -> None:
    out = tmp_path / "never"
    with pytest.raises(InputError, match="no pre-transfer state was run on both sides"):
        validate(rows(A, 1, 2), rows(B, 1, 2), out)
    with pytest.raises(InputError):
        validate_and_report(rows(A, 1, 2), rows(B, 1, 2), out)
    assert not out.exists()


def test_sec_6_7_bad_input_names_the_side(tmp_path: Path) -> None:
    bad = [{**rows(A, 1, 1)[0], "success": 7}]
    with pytest.raises(InputError, match=r"^physical results: results row 1"):
        validate(virtual(), bad)
    with pytest.raises(InputError, match="no such file"):
        validate(tmp_path / "missing.csv", physical())
    with pytest.raises(InputError, match="alpha"):
        validate(virtual(), physical(), alpha=1.0)


def test_fig_6_24_plot_data_is_pure_and_labels_states() -> None:
    data = validation_plot_data(reversed(compare(virtual(), physical())), title="best states")
    assert data.object_ids == ("o1", "o1", "o2")
    assert data.labels == ("o1 f/left/0°", "o1 b/both/90°", "o2")
    assert data.p_v == (0.9, 0.5, 1.0) and data.p_p == (0.3, 0.5, 0.8)
    assert data.diff == pytest.approx((0.6, 0.0, 0.2))
    assert data.significant == (True, False, False)
    assert data.title == "best states" and data.alpha == 0.05
    with pytest.raises(InputError):
        validation_plot_data([])


def test_fig_6_24_plot_validation_draws_one_or_two_axes() -> None:
    data = validation_plot_data(compare(virtual(), physical()))
    fig = plot_validation(data)
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    top, bottom = fig.axes
    assert len(top.containers) == 2  # virtual and physical error bars
    assert [t.get_text() for t in bottom.get_xticklabels()] == list(data.labels)
    assert figure_png(fig).startswith(b"\x89PNG")
    given = Figure()
    assert plot_validation(data, given, difference=False) is given and len(given.axes) == 1


def test_sec_6_7_validate_and_report_writes_the_figure(tmp_path: Path) -> None:
    result = validate_and_report(virtual(), physical(), tmp_path)
    assert result.summary_line == "1/2 objects differ"
    assert (tmp_path / "validation.png").read_bytes().startswith(b"\x89PNG")
    assert (tmp_path / "validation.csv").exists() and (tmp_path / "summary.json").exists()
