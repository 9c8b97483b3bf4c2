"""State vector of the belt OTS (Eq. 5.4–5.6).

A state is a float vector of 11 components ``(a, x, y, z, s_x, s_y, s_z, θ, f, c, t)``
(Eq. 5.4), indexed by `Col`. A batch of states has shape ``(N, 11)``.

Frame F_T: origin at the transport module's front tip on the belt surface, x
towards the transfer unit, z up, y to the left (left belt at y > 0).

==========  =======  ==========================================================
column      unit     meaning
==========  =======  ==========================================================
``A``       code     possessing asset: `ASSET_TM` = 0, `ASSET_TU` = 1
``X..Z``    m        centre of the object's axis-aligned bounding box in F_T
``SX..SZ``  m        half extents of that box (>= 0)
``THETA``   rad      yaw of the object frame F_O; may be NaN during a transfer
``F``       code     face the object lies on (Eq. 5.5): `Face`
``C``       code     conveyor(s) under the object (Eq. 5.6): `Conveyor`
``T``       s        time since the OTS was formed
==========  =======  ==========================================================
"""

from __future__ import annotations

from enum import IntEnum

import numpy as np
from numpy.typing import ArrayLike

from transfertwin._errors import InputError

__all__ = [
    "ASSET_TM",
    "ASSET_TU",
    "N_COLS",
    "Asset",
    "Col",
    "Conveyor",
    "Face",
    "conveyor_of",
    "make_states",
]


class Col(IntEnum):
    """Column indices of the belt state vector (Eq. 5.4)."""

    A = 0
    X = 1
    Y = 2
    Z = 3
    SX = 4
    SY = 5
    SZ = 6
    THETA = 7
    F = 8
    C = 9
    T = 10


#: Number of components of a belt state (Eq. 5.4).
N_COLS = len(Col)


class Asset(IntEnum):
    """Asset codes stored in column `Col.A`."""

    TM = 0  # transport module
    TU = 1  # transfer unit


ASSET_TM = int(Asset.TM)
ASSET_TU = int(Asset.TU)


class Face(IntEnum):
    """Face codes stored in column `Col.F` (Eq. 5.5)."""

    FRONT = 0
    BACK = 1

    @property
    def label(self) -> str:
        """Lower-case name used in files and the CLI, e.g. ``'front'``."""
        return self.name.lower()


class Conveyor(IntEnum):
    """Conveyor codes stored in column `Col.C` (Eq. 5.6); left belt at y > 0."""

    LEFT = 0
    RIGHT = 1
    BOTH = 2

    @property
    def label(self) -> str:
        """Lower-case name used in files and the CLI, e.g. ``'both'``."""
        return self.name.lower()


def _check_codes(values: np.ndarray, allowed: type[IntEnum], what: str) -> None:
    valid = np.isin(values, [int(m) for m in allowed])
    if not np.all(valid):
        bad = values[~valid].flat[0]
        codes = ", ".join(f"{int(m)} ({m.name})" for m in allowed)
        raise InputError(f"{what} code must be one of {codes}, got {bad} (Eq. 5.4)")


def conveyor_of(y: ArrayLike, s_y: ArrayLike, *, belt_gap_half_width: float = 0.005) -> np.ndarray:
    """Conveyor code from the box's lateral overlap with the belts (Eq. 5.6).

    The left belt covers ``y >= +belt_gap_half_width``, the right belt
    ``y <= -belt_gap_half_width``. The box ``[y - s_y, y + s_y]`` overlaps a belt
    if it reaches strictly into it (touching the edge is no overlap). A box that
    overlaps neither belt (narrower than the gap between them) gets `Conveyor.BOTH`
    so that both belts are driven.

    Args:
        y: Box centre y in F_T, metres; any shape broadcastable with ``s_y``.
        s_y: Box half extent in y, metres (>= 0).
        belt_gap_half_width: Half the gap between the two belts, metres (>= 0).

    Returns:
        int64 array of `Conveyor` codes with the broadcast shape.

    Raises:
        InputError: On non-finite input, negative ``s_y`` or gap.
    """
    y_arr, s_arr = np.broadcast_arrays(np.asarray(y, dtype=float), np.asarray(s_y, dtype=float))
    if not (np.all(np.isfinite(y_arr)) and np.all(np.isfinite(s_arr))):
        raise InputError("y and s_y must be finite (Eq. 5.6)")
    if np.any(s_arr < 0.0) or not belt_gap_half_width >= 0.0:
        raise InputError("s_y and belt_gap_half_width must be >= 0 (Eq. 5.6)")
    on_left = y_arr + s_arr > belt_gap_half_width
    on_right = y_arr - s_arr < -belt_gap_half_width
    codes = np.full(y_arr.shape, int(Conveyor.BOTH), dtype=np.int64)
    codes[on_left & ~on_right] = int(Conveyor.LEFT)
    codes[on_right & ~on_left] = int(Conveyor.RIGHT)
    return codes


def make_states(
    *,
    x: ArrayLike,
    y: ArrayLike,
    s_x: ArrayLike,
    s_y: ArrayLike,
    a: ArrayLike = ASSET_TM,
    z: ArrayLike = 0.0,
    s_z: ArrayLike = 0.0,
    theta: ArrayLike = 0.0,
    f: ArrayLike = int(Face.FRONT),
    c: ArrayLike | None = None,
    t: ArrayLike = 0.0,
) -> np.ndarray:
    """Build a batch of belt states from named columns (Eq. 5.4).

    All arguments broadcast against each other to a common shape of at most
    one dimension; scalars give a batch of one state.

    Args:
        x: Box centre x in F_T, metres.
        y: Box centre y in F_T, metres.
        s_x: Box half extent in x, metres.
        s_y: Box half extent in y, metres.
        a: Possessing asset code (`Asset`).
        z: Box centre z in F_T, metres.
        s_z: Box half extent in z, metres.
        theta: Yaw in radians (NaN allowed: unobservable during a transfer).
        f: Face code (`Face`, Eq. 5.5).
        c: Conveyor code (`Conveyor`, Eq. 5.6); ``None`` derives it with
            `conveyor_of` (default belt gap; needs finite ``y`` and ``s_y``).
        t: Time since the OTS was formed, seconds.

    Returns:
        Float array of shape ``(N, 11)``, columns in `Col` order.

    Raises:
        InputError: On unknown codes, negative half extents or shapes that do not
            broadcast to at most 1-D.
    """
    if c is None:
        c = conveyor_of(y, s_y)
    columns = {
        Col.A: a, Col.X: x, Col.Y: y, Col.Z: z, Col.SX: s_x, Col.SY: s_y,
        Col.SZ: s_z, Col.THETA: theta, Col.F: f, Col.C: c, Col.T: t,
    }  # fmt: skip
    try:
        arrays = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in columns.values()))
    except ValueError as exc:
        raise InputError(f"state columns do not broadcast: {exc} (Eq. 5.4)") from None
    if arrays[0].ndim > 1:
        raise InputError(f"columns must be scalars or 1-D, got shape {arrays[0].shape} (Eq. 5.4)")
    states = np.stack([np.atleast_1d(arr) for arr in arrays], axis=1)
    _check_codes(states[:, Col.A], Asset, "asset a")
    _check_codes(states[:, Col.F], Face, "face f")
    _check_codes(states[:, Col.C], Conveyor, "conveyor c")
    if np.any(states[:, [Col.SX, Col.SY, Col.SZ]] < 0.0):
        raise InputError("half extents s_x, s_y, s_z must be >= 0 (Eq. 5.4)")
    return states
