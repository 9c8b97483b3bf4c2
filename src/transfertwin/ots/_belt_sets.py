"""State sets of the belt OTS (Eq. 5.7–5.10) for both transfer directions.

The sets read only columns a, x, y, s_x, s_y, t (and z, s_z for the fall
extension) of the state vector `Col`; θ, f and c are never read, so θ may be
NaN during a transfer.

Decisions the equations leave open:

* **Eq. 5.9 slip.** The printed failure condition joins the two overhang
  conditions of each axis with ∧, which would require the box to overhang both
  ends of the belt area at once. Implemented is the stated intent: failure iff
  ``t > t_max`` or the box leaves the belt area ``[tm_x_min, tu_x_max] ×
  [y_min, y_max]`` on any side (strict inequalities, so touching an outer edge
  is not yet a failure). The gap between the two units is inside the area.
* **Fall extension.** A box whose bottom ``z - s_z`` is below ``z_fall`` has
  fallen off the belts or into the gap: failure. ``z_fall=None`` disables it.
* **NaN.** Comparisons with NaN are false, so a state with NaN in a column a
  set reads is in no pre-transfer or success set; it *is* in the failure set
  (a state that cannot be verified on the belts ends the transfer).
* **Return transfer TU → TM** (the same OTS run backwards): a_pre = TU,
  a_post = TM; pre-transfer needs the box within the TU belts; success needs
  a = TM, ``t < t_max``, the box within the TM belts and ``x`` beyond the
  mirror of the success threshold about the TM's tip ``x = tm_x_max``, i.e.
  ``x < 2 * tm_x_max - x_success`` (-0.2 m by default; ``x_success_return``
  overrides it). The failure set is the same in both directions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from transfertwin.ots._belt_state import ASSET_TM, ASSET_TU, N_COLS, Col
from transfertwin.ots._belt_thresholds import BeltThresholds, TransferDirection
from transfertwin.ots._sets import NonTerminalSet, batched_contains

__all__ = [
    "BeltFailureSet",
    "BeltPreTransferSet",
    "BeltSets",
    "BeltSuccessSet",
    "belt_sets",
    "failure_set",
    "non_terminal_set",
    "pre_transfer_set",
    "success_set",
]


# Plain int column indices for the scalar fast paths (an IntEnum index costs a call).
_A, _X, _Y, _Z = int(Col.A), int(Col.X), int(Col.Y), int(Col.Z)
_SX, _SY, _SZ, _T = int(Col.SX), int(Col.SY), int(Col.SZ), int(Col.T)


def _aabb_within(
    s: np.ndarray, x_min: float, x_max: float, y_min: float, y_max: float
) -> np.ndarray:
    """Box of each state inside ``[x_min, x_max] × [y_min, y_max]``, inclusive."""
    return (
        (s[:, Col.X] - s[:, Col.SX] >= x_min)
        & (s[:, Col.X] + s[:, Col.SX] <= x_max)
        & (s[:, Col.Y] - s[:, Col.SY] >= y_min)
        & (s[:, Col.Y] + s[:, Col.SY] <= y_max)
    )


def _within_one(
    x: float, y: float, sx: float, sy: float,
    x_min: float, x_max: float, y_min: float, y_max: float,
) -> bool:  # fmt: skip
    """Scalar `_aabb_within` for one state (same comparisons, same float64 arithmetic)."""
    return x - sx >= x_min and x + sx <= x_max and y - sy >= y_min and y + sy <= y_max


@dataclass(frozen=True)
class BeltPreTransferSet:
    """Pre-transfer states S_pre (Eq. 5.7; Eq. 6.1 with another ``x_min``).

    Attributes:
        asset: a_pre, the code required in column a.
        x_min, x_max, y_min, y_max: Region the box must lie in (inclusive), metres.
        t0: Time at which the OTS is formed, seconds.
        t0_tol: Allowed ``|t - t0|``, seconds.
    """

    one_dim: ClassVar[int] = N_COLS  # state length `contains_one` handles
    asset: int
    x_min: float
    x_max: float
    y_min: float
    y_max: float
    t0: float = 0.0
    t0_tol: float = 1e-9

    def contains(self, states: ArrayLike) -> np.ndarray:
        """Membership per state; ``(N, 11) -> (N,)``, ``(11,) -> ()``."""
        return batched_contains(states, self._mask, N_COLS)

    def contains_one(self, s: np.ndarray) -> bool:
        """Scalar fast path of `contains` for one state (11,); same comparisons."""
        v = s.tolist()
        x, y, sx, sy = v[_X], v[_Y], v[_SX], v[_SY]
        return (
            v[_A] == self.asset
            and abs(v[_T] - self.t0) <= self.t0_tol
            and _within_one(x, y, sx, sy, self.x_min, self.x_max, self.y_min, self.y_max)
        )

    def _mask(self, s: np.ndarray) -> np.ndarray:
        return (
            (s[:, Col.A] == self.asset)
            & (np.abs(s[:, Col.T] - self.t0) <= self.t0_tol)
            & _aabb_within(s, self.x_min, self.x_max, self.y_min, self.y_max)
        )


@dataclass(frozen=True)
class BeltSuccessSet:
    """Success states S+ (Eq. 5.8, and its mirror for the return transfer).

    Attributes:
        asset: a_post, the code required in column a.
        x_min, x_max, y_min, y_max: Receiver's belt region (inclusive), metres.
        t_max: Success needs ``t < t_max``, seconds.
        x_threshold: Centre x threshold, metres (strict).
        direction: TM_TO_TU needs ``x > x_threshold``, TU_TO_TM ``x < x_threshold``.
    """

    one_dim: ClassVar[int] = N_COLS  # state length `contains_one` handles
    asset: int
    x_min: float
    x_max: float
    y_min: float
    y_max: float
    t_max: float
    x_threshold: float
    direction: TransferDirection = TransferDirection.TM_TO_TU

    def contains(self, states: ArrayLike) -> np.ndarray:
        """Membership per state; ``(N, 11) -> (N,)``, ``(11,) -> ()``."""
        return batched_contains(states, self._mask, N_COLS)

    def contains_one(self, s: np.ndarray) -> bool:
        """Scalar fast path of `contains` for one state (11,); same comparisons."""
        v = s.tolist()
        x, y, sx, sy = v[_X], v[_Y], v[_SX], v[_SY]
        if self.direction is TransferDirection.TM_TO_TU:
            beyond = x > self.x_threshold
        else:
            beyond = x < self.x_threshold
        return (
            v[_A] == self.asset
            and v[_T] < self.t_max
            and beyond
            and _within_one(x, y, sx, sy, self.x_min, self.x_max, self.y_min, self.y_max)
        )

    def _mask(self, s: np.ndarray) -> np.ndarray:
        x = s[:, Col.X]
        if self.direction is TransferDirection.TM_TO_TU:
            beyond = x > self.x_threshold
        else:
            beyond = x < self.x_threshold
        return (
            (s[:, Col.A] == self.asset)
            & (s[:, Col.T] < self.t_max)
            & beyond
            & _aabb_within(s, self.x_min, self.x_max, self.y_min, self.y_max)
        )


@dataclass(frozen=True)
class BeltFailureSet:
    """Failure states S- (intent of Eq. 5.9, see the module docstring).

    Attributes:
        x_min, x_max, y_min, y_max: Outer edges of the belt area, metres.
        t_max: Failure once ``t > t_max``, seconds.
        z_fall: Failure once ``z - s_z < z_fall``, metres; ``None`` disables.
    """

    one_dim: ClassVar[int] = N_COLS  # state length `contains_one` handles
    x_min: float
    x_max: float
    y_min: float
    y_max: float
    t_max: float
    z_fall: float | None = None

    def contains(self, states: ArrayLike) -> np.ndarray:
        """Membership per state; ``(N, 11) -> (N,)``, ``(11,) -> ()``."""
        return batched_contains(states, self._mask, N_COLS)

    def contains_one(self, s: np.ndarray) -> bool:
        """Scalar fast path of `contains` for one state (11,); same comparisons."""
        v = s.tolist()
        x, y, sx, sy, t = v[_X], v[_Y], v[_SX], v[_SY], v[_T]
        isfinite = math.isfinite
        if self.z_fall is not None:
            z, sz = v[_Z], v[_SZ]
            if z - sz < self.z_fall or not (isfinite(z) and isfinite(sz)):
                return True
        if not (isfinite(x) and isfinite(y) and isfinite(sx) and isfinite(sy) and isfinite(t)):
            return True
        return (
            t > self.t_max
            or x - sx < self.x_min
            or x + sx > self.x_max
            or y - sy < self.y_min
            or y + sy > self.y_max
        )

    def _mask(self, s: np.ndarray) -> np.ndarray:
        read = [Col.X, Col.Y, Col.SX, Col.SY, Col.T]
        if self.z_fall is not None:
            read += [Col.Z, Col.SZ]
        failed = ~np.all(np.isfinite(s[:, read]), axis=1)
        failed |= s[:, Col.T] > self.t_max
        failed |= s[:, Col.X] - s[:, Col.SX] < self.x_min
        failed |= s[:, Col.X] + s[:, Col.SX] > self.x_max
        failed |= s[:, Col.Y] - s[:, Col.SY] < self.y_min
        failed |= s[:, Col.Y] + s[:, Col.SY] > self.y_max
        if self.z_fall is not None:
            failed |= s[:, Col.Z] - s[:, Col.SZ] < self.z_fall
        return failed


def _thresholds(th: BeltThresholds | None) -> BeltThresholds:
    return BeltThresholds() if th is None else th


def pre_transfer_set(
    th: BeltThresholds | None = None,
    direction: TransferDirection = TransferDirection.TM_TO_TU,
) -> BeltPreTransferSet:
    """S_pre of Eq. 5.7 (box within the giving unit's belts, ``t = 0``)."""
    th = _thresholds(th)
    if direction is TransferDirection.TM_TO_TU:
        return BeltPreTransferSet(
            ASSET_TM, th.tm_x_min, th.tm_x_max, th.y_min, th.y_max, t0_tol=th.t0_tol
        )
    return BeltPreTransferSet(
        ASSET_TU, th.tu_x_min, th.tu_x_max, th.y_min, th.y_max, t0_tol=th.t0_tol
    )


def success_set(
    th: BeltThresholds | None = None,
    direction: TransferDirection = TransferDirection.TM_TO_TU,
) -> BeltSuccessSet:
    """S+ of Eq. 5.8 (or its mirror for TU_TO_TM, see the module docstring)."""
    th = _thresholds(th)
    x_thr = th.success_threshold(direction)
    if direction is TransferDirection.TM_TO_TU:
        return BeltSuccessSet(
            ASSET_TU, th.tu_x_min, th.tu_x_max, th.y_min, th.y_max, th.t_max, x_thr, direction
        )
    return BeltSuccessSet(
        ASSET_TM, th.tm_x_min, th.tm_x_max, th.y_min, th.y_max, th.t_max, x_thr, direction
    )


def failure_set(th: BeltThresholds | None = None) -> BeltFailureSet:
    """S- of Eq. 5.9 as intended (same for both directions)."""
    th = _thresholds(th)
    return BeltFailureSet(th.tm_x_min, th.tu_x_max, th.y_min, th.y_max, th.t_max, th.z_fall)


def non_terminal_set(
    th: BeltThresholds | None = None,
    direction: TransferDirection = TransferDirection.TM_TO_TU,
) -> NonTerminalSet:
    """S' of Eq. 5.10, the complement of S+ ∪ S-."""
    return NonTerminalSet(success_set(th, direction), failure_set(th))


@dataclass(frozen=True)
class BeltSets:
    """All state sets of one belt transfer direction.

    Attributes:
        direction: The transfer direction.
        thresholds: The thresholds the sets were built from.
        pre: S_pre (Eq. 5.7).
        success: S+ (Eq. 5.8).
        failure: S- (Eq. 5.9).
        non_terminal: S' (Eq. 5.10).
        a_pre: Code of the giving asset.
        a_post: Code of the receiving asset.
    """

    direction: TransferDirection
    thresholds: BeltThresholds
    pre: BeltPreTransferSet
    success: BeltSuccessSet
    failure: BeltFailureSet
    non_terminal: NonTerminalSet
    a_pre: int
    a_post: int


def belt_sets(
    direction: TransferDirection = TransferDirection.TM_TO_TU,
    th: BeltThresholds | None = None,
) -> BeltSets:
    """Bundle the sets of Eq. 5.7–5.10 for ``direction``."""
    th = _thresholds(th)
    success = success_set(th, direction)
    failure = failure_set(th)
    forward = direction is TransferDirection.TM_TO_TU
    return BeltSets(
        direction=direction,
        thresholds=th,
        pre=pre_transfer_set(th, direction),
        success=success,
        failure=failure,
        non_terminal=NonTerminalSet(success, failure),
        a_pre=ASSET_TM if forward else ASSET_TU,
        a_post=ASSET_TU if forward else ASSET_TM,
    )
