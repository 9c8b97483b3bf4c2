"""Edges of the run metrics (App. A.2, Table 6.4) that the mutation run (issue 40) found
open: the standard deviation where the runs do not exceed ddof (NaN, never numpy's inf),
ddof that is a bool or a float refused, and the bad-outcome message naming which side
(predicted or actual) is not binary.
"""

from __future__ import annotations

import math

import pytest

from transfertwin._errors import InputError
from transfertwin.study.calibration._metrics import ConfusionMatrix, summarize_runs

RUNS = [ConfusionMatrix(3, 1, 1, 5), ConfusionMatrix(4, 0, 2, 4)]


@pytest.mark.parametrize("ddof", [2, 3])
def test_table_6_4_std_is_nan_unless_the_runs_exceed_ddof(ddof: int) -> None:
    summary = summarize_runs(RUNS, ddof=ddof)
    assert summary["ddof"] == ddof and summary["n_runs"] == 2
    for m in summary["metrics"].values():
        assert math.isnan(m["std"])
    assert summary["metrics"]["accuracy"]["mean"] == pytest.approx(0.8)  # (8/10 + 8/10) / 2
    assert summary["metrics"]["tp"]["values"] == [3.0, 4.0]


def test_table_6_4_population_std_of_two_runs() -> None:
    assert summarize_runs(RUNS, ddof=0)["metrics"]["tp"]["std"] == pytest.approx(0.5)
    assert summarize_runs(RUNS)["metrics"]["tp"]["std"] == pytest.approx(math.sqrt(0.5))


@pytest.mark.parametrize("ddof", [True, 1.0, -1])
def test_table_6_4_ddof_must_be_a_non_negative_integer(ddof: object) -> None:
    with pytest.raises(InputError, match=r"^Table 6\.4: ddof must be a non-negative integer"):
        summarize_runs(RUNS, ddof=ddof)


@pytest.mark.parametrize(
    ("predicted", "actual", "side"),
    [([0, 2], [0, 1], "predicted"), ([0, 1], [0.5, 1], "actual"), (["a"], [1], "predicted")],
)
def test_app_a2_bad_outcomes_name_the_side(predicted, actual, side: str) -> None:
    with pytest.raises(InputError, match=rf"^App\. A\.2: {side} outcomes must be 0/1 or booleans$"):
        ConfusionMatrix.from_predictions(predicted, actual)
