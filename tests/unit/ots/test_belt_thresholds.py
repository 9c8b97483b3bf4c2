"""Belt thresholds (Eq. 5.7–5.9): defaults, validation, mirrored success threshold."""

from __future__ import annotations

import dataclasses

import pytest

from transfertwin import InputError
from transfertwin.ots import BeltThresholds, TransferDirection


def test_eq_5_7_5_8_defaults() -> None:
    th = BeltThresholds()
    assert (th.tm_x_min, th.tm_x_max, th.tu_x_min, th.tu_x_max) == (-0.65, 0.0, 0.0, 0.5)
    assert (th.y_min, th.y_max, th.x_success) == (-0.2, 0.2, 0.2)
    assert th.t_max == 30.0 and th.z_fall == -0.03


def test_eq_5_8_success_threshold_forward_and_mirrored() -> None:
    th = BeltThresholds()
    assert th.success_threshold(TransferDirection.TM_TO_TU) == 0.2
    assert th.success_threshold(TransferDirection.TU_TO_TM) == -0.2


def test_mirrored_threshold_is_reflected_about_the_tm_tip() -> None:
    th = BeltThresholds(tm_x_min=-0.75, tm_x_max=-0.125, x_success=0.125)
    assert th.success_threshold(TransferDirection.TU_TO_TM) == -0.375


def test_mirrored_threshold_can_be_overridden() -> None:
    th = BeltThresholds(x_success_return=-0.3)
    assert th.success_threshold(TransferDirection.TU_TO_TM) == -0.3


def test_replace_overrides_single_values() -> None:
    th = dataclasses.replace(BeltThresholds(), t_max=12.0, tu_x_min=0.01188, tu_x_max=0.51188)
    assert th.t_max == 12.0 and th.tu_x_min == 0.01188


def test_thresholds_are_frozen() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        BeltThresholds().t_max = 1.0  # type: ignore[misc]


@pytest.mark.parametrize(
    "kw",
    [
        {"tm_x_min": 0.0},  # tm_x_min >= tm_x_max
        {"tm_x_max": 0.1},  # TM overlaps the TU
        {"tu_x_max": 0.0},
        {"y_min": 0.2},
        {"x_success": 0.5},  # unreachable success
        {"x_success": -0.1},  # success threshold on the giving unit
        {"x_success": 0.0, "x_success_return": -0.7},  # below the TM's far end
        {"t_max": 0.0},
        {"t0_tol": -1.0},
        {"t_max": float("nan")},
        {"y_max": float("inf")},
        {"z_fall": float("nan")},
        {"t_max": "30"},
        {"t_max": True},
    ],
)
def test_nonsense_thresholds_raise_input_error(kw: dict) -> None:
    with pytest.raises(InputError, match="BeltThresholds"):
        BeltThresholds(**kw)
