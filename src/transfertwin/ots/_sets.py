"""State sets with a batched membership test (Eq. 4.2–4.7).

A state of the transferred object is a float vector whose component 0 is the
code of the possessing asset (Eq. 4.1); the other components depend on the
system. A *state set* answers, for a batch of such vectors at once, which of
them belong to it.

Shape convention shared by every set in this package:

* ``contains(states)`` with ``states`` of shape ``(N, d)`` returns a bool array
  of shape ``(N,)``; ``N = 0`` is allowed and gives shape ``(0,)``.
* A single state of shape ``(d,)`` gives a 0-d bool array (``shape == ()``);
  use ``bool(s.contains(state))`` for a Python bool.

Sets are immutable, picklable objects (frozen dataclasses), so they can travel
to worker processes together with the experiments that use them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from transfertwin._errors import InputError

__all__ = [
    "IntersectionSet",
    "NonTerminalSet",
    "PossessionSet",
    "PredicateSet",
    "StateSet",
    "UnionSet",
    "as_state_batch",
    "batched_contains",
]


@runtime_checkable
class StateSet(Protocol):
    """A set of object states with a vectorised membership test."""

    def contains(self, states: ArrayLike) -> np.ndarray:
        """Membership of each state.

        Args:
            states: Shape ``(N, d)`` for a batch or ``(d,)`` for one state.

        Returns:
            Bool array of shape ``(N,)`` for a batch, shape ``()`` for one state.
        """
        ...


def as_state_batch(states: ArrayLike, dim: int | None = None) -> tuple[np.ndarray, bool]:
    """Convert states to a float batch of shape ``(N, d)``.

    Args:
        states: One state ``(d,)`` or a batch ``(N, d)``.
        dim: Required state dimension ``d``; ``None`` accepts any ``d >= 1``.

    Returns:
        ``(batch, single)``: the float batch ``(N, d)`` (a view where possible,
        never written to) and whether the input was a single state.

    Raises:
        InputError: If the input is not numeric, not 1-D/2-D, or has the wrong ``d``.
    """
    try:
        arr = np.asarray(states, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"states must be numeric arrays: {exc}") from None
    if arr.ndim == 1:
        batch, single = arr.reshape(1, -1), True
    elif arr.ndim == 2:
        batch, single = arr, False
    else:
        raise InputError(f"states must have shape (d,) or (N, d), got shape {arr.shape}")
    if batch.shape[1] < 1:
        raise InputError("a state needs at least component 0, the possessing asset (Eq. 4.1)")
    if dim is not None and batch.shape[1] != dim:
        raise InputError(f"states must have d = {dim} components, got {batch.shape[1]}")
    return batch, single


def batched_contains(
    states: ArrayLike,
    mask: Callable[[np.ndarray], np.ndarray],
    dim: int | None = None,
) -> np.ndarray:
    """Apply a batch mask function with this package's shape convention.

    Args:
        states: One state ``(d,)`` or a batch ``(N, d)``.
        mask: Maps a float batch ``(N, d)`` to a boolean-like array ``(N,)``.
        dim: Required state dimension, see `as_state_batch`.

    Returns:
        Bool array ``(N,)``, or shape ``()`` for a single state.

    Raises:
        InputError: On malformed states or a mask result of the wrong shape.
    """
    batch, single = as_state_batch(states, dim)
    result = np.asarray(mask(batch))
    if result.shape != (batch.shape[0],):
        raise InputError(
            f"a set predicate must return shape ({batch.shape[0]},), got {result.shape}"
        )
    result = result.astype(bool, copy=False)
    return result.reshape(()) if single else result


@dataclass(frozen=True)
class PredicateSet:
    """The states for which a vectorised predicate holds (Eq. 4.4–4.6).

    Attributes:
        predicate: Maps a float batch ``(N, d)`` to bools ``(N,)``. Must be pure;
            a module-level function keeps the set picklable.
        name: Label used in reprs and error messages.
        dim: Required state dimension ``d``, or ``None`` for any.
    """

    predicate: Callable[[np.ndarray], np.ndarray]
    name: str = "predicate set"
    dim: int | None = None

    def contains(self, states: ArrayLike) -> np.ndarray:
        """Membership per state; see the module docstring for shapes."""
        return batched_contains(states, self.predicate, self.dim)


@dataclass(frozen=True)
class PossessionSet:
    """States possessed by one asset, by component 0 (Eq. 4.2 / 4.3).

    Attributes:
        asset: Asset code compared exactly with component 0.
        name: Label used in reprs.
    """

    asset: float
    name: str = "possession set"

    def contains(self, states: ArrayLike) -> np.ndarray:
        """Membership per state; see the module docstring for shapes."""
        return batched_contains(states, lambda s: s[:, 0] == self.asset)


@dataclass(frozen=True, init=False)
class _CombinedSet:
    """Members combined element-wise by `_combine` (a numpy ufunc) from `_identity`."""

    members: tuple[StateSet, ...]
    _identity: ClassVar[bool]
    _combine: ClassVar[np.ufunc]

    def __init__(self, *members: StateSet) -> None:
        if not members:
            raise InputError(f"{type(self).__name__} needs at least one member set")
        object.__setattr__(self, "members", tuple(members))

    def contains(self, states: ArrayLike) -> np.ndarray:
        """Membership per state; see the module docstring for shapes."""
        batch, single = as_state_batch(states)
        result = np.full(batch.shape[0], self._identity, dtype=bool)
        for member in self.members:
            type(self)._combine(result, member.contains(batch), out=result)
        return result.reshape(()) if single else result


@dataclass(frozen=True, init=False)
class UnionSet(_CombinedSet):
    """Union of state sets, e.g. the terminal states S+ ∪ S- of Eq. 4.9.

    Attributes:
        members: The united sets (at least one).
    """

    _identity: ClassVar[bool] = False
    _combine: ClassVar[np.ufunc] = np.logical_or


@dataclass(frozen=True, init=False)
class IntersectionSet(_CombinedSet):
    """Intersection of state sets, e.g. possession ∩ predicate in Eq. 4.4 / 4.5.

    Attributes:
        members: The intersected sets (at least one).
    """

    _identity: ClassVar[bool] = True
    _combine: ClassVar[np.ufunc] = np.logical_and


@dataclass(frozen=True)
class NonTerminalSet:
    """Non-terminal states S' = S_o minus (S+ ∪ S-) (Eq. 4.7 / 5.10).

    Attributes:
        success: The success set S+ (Eq. 4.5).
        failure: The failure set S- (Eq. 4.6).
    """

    success: StateSet
    failure: StateSet

    def contains(self, states: ArrayLike) -> np.ndarray:
        """Membership per state; see the module docstring for shapes."""
        batch, single = as_state_batch(states)
        result = ~(self.success.contains(batch) | self.failure.contains(batch))
        return result.reshape(()) if single else result
