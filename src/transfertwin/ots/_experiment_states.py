"""The discrete pre-transfer states of the application study (Eq. 6.1–6.10, 6.21–6.24).

Per face, an object is placed at one of three positions (Eq. 6.3) with an integer
yaw in degrees (Eq. 6.4): at ``p_left`` / ``p_right`` with θ ∈ Θ_single (Eq. 6.5,
102 angles) and at ``p_middle`` with θ ∈ Θ_both (Eq. 6.6, 258 angles), which makes
2 × (102 + 258 + 102) = 924 states (Eq. 6.7–6.10, 6.20).

Stable order of `experiment_states` (studies index states by it): face
``front`` then ``back``; within a face conveyor ``left``, ``both``, ``right``
(the order of Eq. 6.7); within a conveyor θ ascending.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from numbers import Integral, Real

import numpy as np

from transfertwin._errors import InputError
from transfertwin.ots._belt_sets import BeltPreTransferSet, pre_transfer_set
from transfertwin.ots._belt_state import ASSET_TM, Conveyor, Face, make_states
from transfertwin.ots._belt_thresholds import BeltThresholds

__all__ = [
    "CONVEYORS",
    "EXPERIMENT_PRE_X_MIN",
    "FACES",
    "POSITIONS",
    "P_LEFT",
    "P_MIDDLE",
    "P_RIGHT",
    "SERIES_ORDER",
    "STATES_CSV_HEADER",
    "THETA_ALL",
    "THETA_BOTH",
    "THETA_SINGLE",
    "PreTransferState",
    "check_theta_deg",
    "experiment_pre_transfer_set",
    "experiment_states",
    "filter_theta_step",
    "parse_conveyor",
    "parse_face",
    "series",
    "state_index",
    "states_csv",
]

#: Object positions (x, y) in F_T, metres (Eq. 6.3).
P_LEFT = (-0.325, 0.094)
P_MIDDLE = (-0.325, 0.0)
P_RIGHT = (-0.325, -0.094)
POSITIONS = {"left": P_LEFT, "both": P_MIDDLE, "right": P_RIGHT}

#: Yaw angles in whole degrees (Eq. 6.4–6.6), ascending.
THETA_ALL: tuple[int, ...] = tuple(range(-179, 181))
THETA_SINGLE: tuple[int, ...] = (
    tuple(range(-179, -154)) + tuple(range(-25, 26)) + tuple(range(155, 181))
)
THETA_BOTH: tuple[int, ...] = tuple(sorted(set(THETA_ALL) - set(THETA_SINGLE)))

FACES = ("front", "back")
CONVEYORS = ("left", "both", "right")
#: Order of the four 360-state series (Eq. 6.21–6.24) as (face, side).
SERIES_ORDER = (("front", "left"), ("front", "right"), ("back", "left"), ("back", "right"))
#: Far end of the TM belts in the study's pre-transfer set (Eq. 6.1; Eq. 5.7 has -0.65 m).
EXPERIMENT_PRE_X_MIN = -0.625
STATES_CSV_HEADER = "face,conveyor,theta_deg,x_m,y_m"


def _parse_label(value: object, allowed: tuple[str, ...], what: str) -> str:
    label = value.strip().lower() if isinstance(value, str) else None
    if label not in allowed:
        options = ", ".join(repr(a) for a in allowed)
        raise InputError(f"{what} must be one of {options}, got {value!r}")
    return label


def parse_face(value: object) -> str:
    """Face label ``'front'`` or ``'back'`` (Eq. 5.5), case and blanks ignored.

    Raises:
        InputError: For anything else.
    """
    return _parse_label(value, FACES, "face (Eq. 5.5)")


def parse_conveyor(value: object) -> str:
    """Conveyor label ``'left'``, ``'both'`` or ``'right'`` (Eq. 5.6).

    Raises:
        InputError: For anything else.
    """
    return _parse_label(value, CONVEYORS, "conveyor (Eq. 5.6)")


def check_theta_deg(value: object) -> int:
    """Yaw as an integer in -179..180 degrees (Eq. 6.4).

    Accepts ints, integral floats and decimal strings such as ``"-15"``.

    Raises:
        InputError: For non-integers, booleans and values outside -179..180.
    """
    theta: int | None = None
    if isinstance(value, str):
        try:
            theta = int(value.strip())
        except ValueError:
            theta = None
    elif isinstance(value, (bool, np.bool_)):
        theta = None
    elif isinstance(value, Real) and math.isfinite(float(value)) and float(value).is_integer():
        theta = int(value)
    if theta is None or not -179 <= theta <= 180:
        raise InputError(f"theta_deg (Eq. 6.4) must be an integer in -179..180, got {value!r}")
    return theta


@dataclass(frozen=True)
class PreTransferState:
    """One discrete pre-transfer state of the study (Eq. 6.8–6.10).

    Attributes:
        face: ``'front'`` or ``'back'`` (Eq. 5.5).
        conveyor: ``'left'``, ``'both'`` or ``'right'`` (Eq. 5.6).
        theta_deg: Yaw in whole degrees, -179..180 (Eq. 6.4).
        x_m: Object position x in F_T, metres (Eq. 6.3).
        y_m: Object position y in F_T, metres (Eq. 6.3).
    """

    face: str
    conveyor: str
    theta_deg: int
    x_m: float
    y_m: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "face", parse_face(self.face))
        object.__setattr__(self, "conveyor", parse_conveyor(self.conveyor))
        object.__setattr__(self, "theta_deg", check_theta_deg(self.theta_deg))
        for name in ("x_m", "y_m"):
            value = getattr(self, name)
            if not isinstance(value, Real) or not math.isfinite(float(value)):
                raise InputError(f"{name} must be a finite number of metres, got {value!r}")
            object.__setattr__(self, name, float(value))

    @property
    def key(self) -> tuple[str, str, int]:
        """``(face, conveyor, theta_deg)``, unique within `experiment_states`."""
        return (self.face, self.conveyor, self.theta_deg)

    @property
    def theta_rad(self) -> float:
        """Yaw in radians, as stored in the state vector."""
        return math.radians(self.theta_deg)

    @property
    def face_code(self) -> Face:
        """Face code of column f."""
        return Face[self.face.upper()]

    @property
    def conveyor_code(self) -> Conveyor:
        """Conveyor code of column c."""
        return Conveyor[self.conveyor.upper()]

    def to_state(self, *, s_x: float, s_y: float, z: float = 0.0, s_z: float = 0.0) -> np.ndarray:
        """Belt state vector ``(11,)`` at t = 0 possessed by the TM (Eq. 5.4).

        The box centre is placed at (x_m, y_m); the half extents depend on the
        object and its yaw and are supplied by the caller, metres.
        """
        return make_states(
            a=ASSET_TM, x=self.x_m, y=self.y_m, z=z, s_x=s_x, s_y=s_y, s_z=s_z,
            theta=self.theta_rad, f=int(self.face_code), c=int(self.conveyor_code), t=0.0,
        )[0]  # fmt: skip


@functools.cache
def experiment_states() -> tuple[PreTransferState, ...]:
    """All 924 discrete pre-transfer states (Eq. 6.7–6.10) in the stable order."""
    out = []
    for face in FACES:
        for conveyor in CONVEYORS:
            thetas = THETA_BOTH if conveyor == "both" else THETA_SINGLE
            x, y = POSITIONS[conveyor]
            out.extend(PreTransferState(face, conveyor, th, x, y) for th in thetas)
    return tuple(out)


@functools.cache
def _index() -> dict[tuple[str, str, int], int]:
    return {s.key: i for i, s in enumerate(experiment_states())}


def state_index(face: str, conveyor: str, theta_deg: int) -> int:
    """Position of a state in `experiment_states`.

    Raises:
        InputError: If the labels are invalid or the combination is not in the set.
    """
    key = (parse_face(face), parse_conveyor(conveyor), check_theta_deg(theta_deg))
    if key not in _index():
        raise InputError(f"{key} is not a pre-transfer state of the experiments (Eq. 6.7)")
    return _index()[key]


def series(face: str, side: str) -> tuple[PreTransferState, ...]:
    """One 360-state series (Eq. 6.21–6.24), θ ascending from -179 to 180.

    Args:
        face: ``'front'`` or ``'back'``.
        side: ``'left'`` (conveyor ∈ {both, left}) or ``'right'`` (∈ {both, right}).

    Raises:
        InputError: On an invalid face or side.
    """
    face = parse_face(face)
    side = _parse_label(side, ("left", "right"), "series side (Eq. 6.21-6.24)")
    chosen = [s for s in experiment_states() if s.face == face and s.conveyor in ("both", side)]
    return tuple(sorted(chosen, key=lambda s: s.theta_deg))


def filter_theta_step(
    states: tuple[PreTransferState, ...] | list[PreTransferState], step_deg: int
) -> tuple[PreTransferState, ...]:
    """Keep the states whose θ is a multiple of ``step_deg``, order preserved.

    Raises:
        InputError: If ``step_deg`` is not an integer in 1..360.
    """
    if isinstance(step_deg, bool) or not isinstance(step_deg, Integral) or not 1 <= step_deg <= 360:
        raise InputError(f"theta step must be an integer in 1..360 degrees, got {step_deg!r}")
    return tuple(s for s in states if s.theta_deg % int(step_deg) == 0)


def states_csv(states: tuple[PreTransferState, ...] | list[PreTransferState] | None = None) -> str:
    """CSV text (header `STATES_CSV_HEADER`, ``\\n`` line ends), one row per state.

    Args:
        states: States to write; ``None`` writes all of `experiment_states`.
    """
    rows = [STATES_CSV_HEADER]
    for s in experiment_states() if states is None else states:
        rows.append(f"{s.face},{s.conveyor},{s.theta_deg},{s.x_m!r},{s.y_m!r}")
    return "\n".join(rows) + "\n"


def experiment_pre_transfer_set(
    th: BeltThresholds | None = None, *, x_min: float = EXPERIMENT_PRE_X_MIN
) -> BeltPreTransferSet:
    """S_pre of Eq. 6.1: the TM -> TU set of Eq. 5.7 with far belt end ``x_min``.

    Args:
        th: Thresholds for the other bounds; ``None`` uses the defaults.
        x_min: Lower bound of ``x - s_x``, metres (-0.625 in Eq. 6.1).
    """
    base = pre_transfer_set(th)
    if not (math.isfinite(x_min) and x_min < base.x_max):
        raise InputError(f"x_min must be finite and below {base.x_max} m, got {x_min} (Eq. 6.1)")
    return BeltPreTransferSet(
        base.asset, x_min, base.x_max, base.y_min, base.y_max, base.t0, base.t0_tol
    )
