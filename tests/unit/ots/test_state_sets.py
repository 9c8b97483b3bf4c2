"""Generic state sets (Eq. 4.2–4.7): shapes, composition, possession."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from transfertwin import InputError
from transfertwin.ots import (
    IntersectionSet,
    NonTerminalSet,
    PossessionSet,
    PredicateSet,
    StateSet,
    UnionSet,
    as_state_batch,
)


def _positive_x(states: np.ndarray) -> np.ndarray:
    return states[:, 1] > 0.0


def _above_one(states: np.ndarray) -> np.ndarray:
    return states[:, 1] > 1.0


def _negative_x(states: np.ndarray) -> np.ndarray:
    return states[:, 1] < 0.0


STATES = np.array([[0.0, -1.0], [0.0, 0.5], [1.0, 2.0], [1.0, 0.0]])


def test_batch_gives_one_bool_per_state() -> None:
    result = PredicateSet(_positive_x).contains(STATES)
    assert result.dtype == bool
    np.testing.assert_array_equal(result, [False, True, True, False])


def test_single_state_gives_0d_bool() -> None:
    result = PredicateSet(_positive_x).contains(np.array([0.0, 0.5]))
    assert result.shape == ()
    assert bool(result) is True


def test_empty_batch_gives_empty_result() -> None:
    result = PredicateSet(_positive_x).contains(np.zeros((0, 2)))
    assert result.shape == (0,)


def test_lists_are_accepted() -> None:
    assert bool(PredicateSet(_positive_x).contains([0.0, 1.0]))


@pytest.mark.parametrize("bad", [np.zeros((2, 2, 2)), np.float64(1.0), np.zeros((3, 0))])
def test_malformed_state_shapes_raise_input_error(bad: np.ndarray) -> None:
    with pytest.raises(InputError):
        PredicateSet(_positive_x).contains(bad)


def test_non_numeric_states_raise_input_error() -> None:
    with pytest.raises(InputError, match="numeric"):
        PredicateSet(_positive_x).contains(["a", "b"])


def test_dimension_is_checked_when_given() -> None:
    with pytest.raises(InputError, match="d = 3"):
        PredicateSet(_positive_x, dim=3).contains(STATES)


def test_predicate_with_wrong_result_shape_raises() -> None:
    bad = PredicateSet(lambda s: np.array([True]))
    with pytest.raises(InputError, match="shape"):
        bad.contains(STATES)


def test_as_state_batch_reports_single() -> None:
    batch, single = as_state_batch([1.0, 2.0, 3.0])
    assert batch.shape == (1, 3)
    assert single


def test_eq_4_2_4_3_possession_subsets_partition_by_component_0() -> None:
    pre, post = PossessionSet(0.0), PossessionSet(1.0)
    in_pre, in_post = pre.contains(STATES), post.contains(STATES)
    np.testing.assert_array_equal(in_pre, [True, True, False, False])
    assert not np.any(in_pre & in_post)
    assert np.all(in_pre | in_post)


def test_eq_4_4_intersection_of_possession_and_predicate() -> None:
    pre = IntersectionSet(PossessionSet(0.0), PredicateSet(_positive_x))
    np.testing.assert_array_equal(pre.contains(STATES), [False, True, False, False])


def test_union_set() -> None:
    union = UnionSet(PredicateSet(_negative_x), PredicateSet(_above_one))
    np.testing.assert_array_equal(union.contains(STATES), [True, False, True, False])
    assert union.contains(STATES[0]).shape == ()


def test_empty_union_or_intersection_is_rejected() -> None:
    with pytest.raises(InputError):
        UnionSet()
    with pytest.raises(InputError):
        IntersectionSet()


def test_eq_4_7_non_terminal_is_complement_of_union() -> None:
    success = IntersectionSet(PossessionSet(1.0), PredicateSet(_above_one))
    failure = PredicateSet(_negative_x)
    non_terminal = NonTerminalSet(success, failure)
    expected = ~(success.contains(STATES) | failure.contains(STATES))
    np.testing.assert_array_equal(non_terminal.contains(STATES), expected)
    np.testing.assert_array_equal(expected, [False, True, False, True])
    assert non_terminal.contains(STATES[1]).shape == ()


def test_sets_satisfy_the_protocol() -> None:
    for s in (
        PredicateSet(_positive_x),
        PossessionSet(0.0),
        UnionSet(PossessionSet(0.0)),
        IntersectionSet(PossessionSet(0.0)),
        NonTerminalSet(PossessionSet(0.0), PossessionSet(1.0)),
    ):
        assert isinstance(s, StateSet)


def test_sets_are_picklable() -> None:
    s = NonTerminalSet(
        IntersectionSet(PossessionSet(1.0), PredicateSet(_above_one, "s+")),
        UnionSet(PredicateSet(_negative_x, "s-")),
    )
    clone = pickle.loads(pickle.dumps(s))
    np.testing.assert_array_equal(clone.contains(STATES), s.contains(STATES))


def test_sets_are_frozen() -> None:
    s = PossessionSet(0.0)
    with pytest.raises(AttributeError):
        s.asset = 1.0  # type: ignore[misc]
