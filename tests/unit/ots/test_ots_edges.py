"""Edges of the belt OTS building blocks that the mutation run (issue 40) found untested:
the bounds of the thresholds' own checks (Eq. 5.7–5.9), the defaults and dtype of
`make_states` (Eq. 5.4) and `PreTransferState.to_state` (Eq. 6.1), `conveyor_of` at zero
width (Eq. 5.6), the exact wording of the code and label errors, the thresholds reaching
every set `belt_sets` builds in both directions, the state length the sets require, and
the loop clock written into a state that ``u`` returned as integers (Eq. 4.10–4.11).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from transfertwin._errors import InputError
from transfertwin.ots import (
    ASSET_TM,
    ASSET_TU,
    BeltPreTransferSet,
    BeltThresholds,
    Col,
    Conveyor,
    PreTransferState,
    TransferDirection,
    belt_sets,
    conveyor_of,
    experiment_pre_transfer_set,
    make_states,
    non_terminal_set,
    parse_conveyor,
    parse_face,
    run_transfer,
    series,
)

TM_TO_TU, TU_TO_TM = TransferDirection.TM_TO_TU, TransferDirection.TU_TO_TM


@pytest.mark.parametrize(
    "kw",
    [
        {"tm_x_min": 0.0},  # tm_x_min == tm_x_max
        {"tu_x_min": 0.5},  # tu_x_min == tu_x_max
        {"tm_x_max": 0.1},  # tm_x_max > tu_x_min
        {"y_min": 0.2},  # y_min == y_max
        {"x_success": 0.5},  # x_success == tu_x_max
        {"x_success": -0.1},  # below tm_x_max
        {"x_success_return": -0.65},  # the return threshold must exceed tm_x_min
        {"t_max": 0.0},
        {"t0_tol": -1e-12},
        {"z_fall": None, "t0_tol": math.inf},  # t0_tol is checked after a None z_fall
        {"x_success_return": math.nan},
    ],
)
def test_eq_5_7_to_5_9_thresholds_refuse_bounds_that_touch(kw: dict) -> None:
    with pytest.raises(InputError, match="BeltThresholds"):
        BeltThresholds(**kw)


@pytest.mark.parametrize(
    "kw",
    [{"x_success": 0.0}, {"t_max": 0.5}, {"t0_tol": 0.0}, {"tm_x_max": 0.0, "tu_x_min": 0.0},
     {"x_success_return": -0.649}],
)  # fmt: skip
def test_eq_5_7_to_5_9_thresholds_accept_the_inclusive_bounds(kw: dict) -> None:
    th = BeltThresholds(**kw)
    assert all(getattr(th, k) == v for k, v in kw.items())


def test_eq_5_8_return_threshold_mirrors_or_overrides() -> None:
    th = BeltThresholds(tm_x_max=-0.05, tu_x_min=0.0, x_success=0.25)
    assert th.success_threshold(TU_TO_TM) == pytest.approx(-0.35)
    assert BeltThresholds(x_success_return=-0.1).success_threshold(TU_TO_TM) == -0.1


TH = BeltThresholds(tm_x_min=-0.5, tm_x_max=-0.0625, tu_x_min=0.0625, tu_x_max=0.4375,
                    y_min=-0.125, y_max=0.25, x_success=0.125, t_max=8.0, z_fall=-0.0625,
                    t0_tol=0.25)  # fmt: skip


@pytest.mark.parametrize("direction", [TM_TO_TU, TU_TO_TM], ids=lambda d: d.value)
def test_eq_5_7_to_5_10_belt_sets_carry_the_thresholds_into_every_set(direction) -> None:
    sets = belt_sets(direction, TH)
    fwd = direction is TM_TO_TU
    assert (sets.a_pre, sets.a_post) == ((ASSET_TM, ASSET_TU) if fwd else (ASSET_TU, ASSET_TM))
    assert sets.direction is direction and sets.thresholds is TH
    pre_box = (TH.tm_x_min, TH.tm_x_max) if fwd else (TH.tu_x_min, TH.tu_x_max)
    post_box = (TH.tu_x_min, TH.tu_x_max) if fwd else (TH.tm_x_min, TH.tm_x_max)
    assert (sets.pre.asset, sets.pre.x_min, sets.pre.x_max) == (sets.a_pre, *pre_box)
    assert (sets.pre.y_min, sets.pre.y_max, sets.pre.t0_tol) == (-0.125, 0.25, 0.25)
    s = sets.success
    assert (s.asset, s.x_min, s.x_max, s.y_min, s.y_max) == (sets.a_post, *post_box, -0.125, 0.25)
    assert (s.t_max, s.x_threshold, s.direction) == (8.0, TH.success_threshold(direction),
                                                      direction)  # fmt: skip
    f = sets.failure
    assert (f.x_min, f.x_max, f.y_min, f.y_max, f.t_max, f.z_fall) == (
        -0.5, 0.4375, -0.125, 0.25, 8.0, -0.0625)  # fmt: skip
    nt = non_terminal_set(TH, direction)
    assert nt.success == s and nt.failure == f
    assert sets.non_terminal == nt


@pytest.mark.parametrize("shape", [(3, 10), (3, 12), (10,)])
@pytest.mark.parametrize("which", ["pre", "success", "failure"])
def test_eq_5_4_sets_require_eleven_columns(which: str, shape: tuple) -> None:
    s = getattr(belt_sets(TM_TO_TU), which)
    with pytest.raises(InputError, match="d = 11"):
        s.contains(np.zeros(shape))


def test_eq_6_1_experiment_set_keeps_the_thresholds_time_tolerance() -> None:
    pre = experiment_pre_transfer_set(TH, x_min=-0.375)
    assert (pre.x_min, pre.x_max, pre.t0, pre.t0_tol) == (-0.375, -0.0625, 0.0, 0.25)
    inside = make_states(x=-0.25, y=0.0, s_x=0.0625, s_y=0.0625, t=0.25)
    assert bool(pre.contains(inside)) and pre.contains_one(inside[0])
    assert not bool(pre.contains(make_states(x=-0.25, y=0.0, s_x=0.0625, s_y=0.0625, t=0.3)))
    message = r"^x_min must be finite and below -0\.0625 m, got -0\.0625 \(Eq\. 6\.1\)$"
    with pytest.raises(InputError, match=message):
        experiment_pre_transfer_set(TH, x_min=-0.0625)  # x_min == x_max


def test_eq_5_4_make_states_defaults_and_float_dtype() -> None:
    s = make_states(x=0, y=0, s_x=0, s_y=0)
    assert s.dtype == np.float64 and s.shape == (1, 11)
    assert s[0].tolist() == [ASSET_TM, 0, 0, 0, 0, 0, 0, 0, 0, int(Conveyor.BOTH), 0]
    ints = make_states(x=1, y=0, s_x=0, s_y=0, z=0, s_z=0, theta=0, t=0, c=0)
    assert ints.dtype == np.float64


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"a": 3}, r"^asset a code must be one of 0 \(TM\), 1 \(TU\), got 3\.0 \(Eq\. 5\.4\)$"),
        ({"f": 2}, r"^face f code must be one of 0 \(FRONT\), 1 \(BACK\), got 2\.0 \(Eq\. 5\.4\)$"),
        ({"c": 7}, r"^conveyor c code must be one of 0 \(LEFT\), 1 \(RIGHT\), "
                   r"2 \(BOTH\), got 7\.0 \(Eq\. 5\.4\)$"),
    ],
)  # fmt: skip
def test_eq_5_4_unknown_codes_name_the_column_the_codes_and_the_value(kw, message) -> None:
    with pytest.raises(InputError, match=message):
        make_states(x=0.0, y=0.0, s_x=0.1, s_y=0.1, **kw)


def test_eq_5_6_zero_width_box_and_zero_gap_are_allowed() -> None:
    assert conveyor_of(0.0, 0.0).tolist() == int(Conveyor.BOTH)
    assert conveyor_of(0.01, 0.0, belt_gap_half_width=0.0).tolist() == int(Conveyor.LEFT)
    assert conveyor_of([0.0], [0.0], belt_gap_half_width=0.0).dtype == np.int64
    with pytest.raises(InputError, match="must be >= 0"):
        conveyor_of(0.0, 0.1, belt_gap_half_width=-1e-9)


def test_eq_6_1_to_state_defaults() -> None:
    # placed on the right of the belts but labelled 'left': the label, not the geometry, is c
    st = PreTransferState("back", "left", np.int64(30), -0.3, -0.1)
    assert type(st.theta_deg) is int and st.theta_deg == 30
    s = st.to_state(s_x=0.1, s_y=0.05)
    assert s[Col.A] == ASSET_TM and s[Col.Z] == 0.0 and s[Col.SZ] == 0.0 and s[Col.T] == 0.0
    assert (s[Col.X], s[Col.Y], s[Col.SX], s[Col.SY]) == (-0.3, -0.1, 0.1, 0.05)
    assert s[Col.C] == int(Conveyor.LEFT) and s[Col.F] == 1
    assert s[Col.THETA] == pytest.approx(math.radians(30))
    s2 = PreTransferState("front", "right", 0, -0.3, 0.1).to_state(s_x=0.1, s_y=0.05, z=0.2,
                                                                   s_z=0.3)  # fmt: skip
    assert (s2[Col.Z], s2[Col.SZ], s2[Col.C]) == (0.2, 0.3, int(Conveyor.RIGHT))
    assert dataclasses.replace(st).theta_deg == 30


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: parse_face("side"), r"^face \(Eq\. 5\.5\) must be one of 'front', 'back', "
                                     r"got 'side'$"),
        (lambda: parse_conveyor(3), r"^conveyor \(Eq\. 5\.6\) must be one of 'left', 'both', "
                                    r"'right', got 3$"),
        (lambda: series("front", "both"), r"^series side \(Eq\. 6\.21-6\.24\) must be one of "
                                          r"'left', 'right', got 'both'$"),
    ],
)  # fmt: skip
def test_eq_5_5_labels_name_what_they_parse_and_the_options(call, message) -> None:
    with pytest.raises(InputError, match=message):
        call()


def test_eq_4_10_a_state_returned_as_integers_gets_the_float_clock() -> None:
    sets = belt_sets(TM_TO_TU)
    s0 = make_states(x=-0.3, y=0.0, s_x=0.1, s_y=0.1, z=0.05, s_z=0.05)[0]

    def u(s: np.ndarray) -> list[int]:
        return [ASSET_TU, 0, 0, 0, 0, 0, 0, 0, 0, 2, 0]  # on the TU, at rest, short of x_success

    trace = run_transfer(s0, u, pre=sets.pre, success=sets.success, failure=sets.failure,
                         dt=0.25, t_max=1.0, time_index=int(Col.T))  # fmt: skip
    assert trace.states.dtype == np.float64
    assert trace.states[1:, Col.T].tolist() == [0.25, 0.5, 0.75, 1.0]
    assert trace.timed_out and trace.t_end == 1.0


@pytest.mark.parametrize("max_steps", [1, 2])
def test_eq_4_11_max_steps_of_one_is_allowed(max_steps: int) -> None:
    sets = belt_sets(TM_TO_TU)
    s0 = make_states(x=-0.3, y=0.0, s_x=0.1, s_y=0.1, z=0.05, s_z=0.05)[0]
    trace = run_transfer(s0, lambda s: s, pre=sets.pre, success=sets.success,
                         failure=sets.failure, dt=0.5, t_max=10.0, time_index=int(Col.T),
                         max_steps=max_steps)  # fmt: skip
    assert trace.n_transitions == max_steps and trace.timed_out


def test_eq_5_7_pre_transfer_time_is_measured_from_t0() -> None:
    pre = BeltPreTransferSet(ASSET_TM, -0.5, 0.0, -0.2, 0.2, t0=5.0, t0_tol=0.125)
    at = make_states(x=-0.25, y=0.0, s_x=0.125, s_y=0.125, t=[5.125, 4.875, 5.25, 0.0])
    assert pre.contains(at).tolist() == [True, True, False, False]
    assert [pre.contains_one(s) for s in at] == [True, True, False, False]


def test_eq_5_7_the_tm_belts_need_a_length() -> None:
    """tm_x_min == tm_x_max with every other check satisfied (the return threshold set)."""
    with pytest.raises(InputError, match=r"^BeltThresholds: need tm_x_min < tm_x_max <= "):
        BeltThresholds(tm_x_min=0.0, tm_x_max=0.0, x_success_return=0.1)
