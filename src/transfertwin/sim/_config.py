"""Frozen configuration of the virtual transfer system (SI units).

`PhysicsConfig` is the analogue of the study's simulation-parameter tables (Tables A.3/A.4):
every MuJoCo option that can change a transfer's outcome lives here, and nowhere else.
`LayoutConfig` fixes the geometry of the transport module TM^V and the transfer unit TU^V
in the tip frame F_T (docs/design-choices.md, "Frames and geometry"). `SceneConfig` bundles them
with the instance parameters of Sec. 6.5.2 (friction μ_k and initial gap d_gap).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

from transfertwin._errors import InputError
from transfertwin.control import STALL_MODES

__all__ = [
    "MULTICCD_HULLS",
    "PROFILES",
    "DockingError",
    "LayoutConfig",
    "PhysicsConfig",
    "PlacementConfig",
    "SceneConfig",
    "scene_profile",
]

_SOLVERS = ("PGS", "CG", "Newton")
_CONES = ("pyramidal", "elliptic")
_INTEGRATORS = ("Euler", "RK4", "implicit", "implicitfast")

#: `PhysicsConfig.multiccd` None: objects of fewer convex hulls keep multi-CCD (a box of one
#: hull needs it to rest flat); the built-in cores have 12-26 hulls, 8 after the 'lean' budget.
MULTICCD_HULLS = 8


def _positive(owner: str, **values: float) -> None:
    for name, value in values.items():
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise InputError(f"{owner}.{name} must be a positive number, got {value!r}")


def _bounded(name: str, value: object, limit: float) -> None:
    """InputError unless `value` is a finite number with |value| <= limit."""
    ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    if not (ok and math.isfinite(value) and abs(value) <= limit):
        raise InputError(f"{name} must be a number within ±{limit:g}, got {value!r}")


@dataclass(frozen=True)
class PhysicsConfig:
    """MuJoCo solver settings (our analogue of the study's Tables A.3/A.4).

    Defaults are the fast settings (5 ms implicitfast steps), validated against the
    'reference' profile (2 ms steps), docs/speed.md; see `scene_profile`.

    Attributes:
        timestep_s: Physics step (s).
        integrator: One of Euler, RK4, implicit, implicitfast.
        solver: One of PGS, CG, Newton.
        cone: Friction cone, pyramidal or elliptic.
        iterations: Main solver iterations.
        ls_iterations: Line-search iterations.
        tolerance: Solver tolerance.
        impratio: Frictional-to-normal impedance ratio (>1 reduces slip).
        noslip_iterations: Extra no-slip solver iterations (0 disables).
        multiccd: Multiple contact points per convex pair (MuJoCo 4's default: on). None
            decides by the object (`multiccd_for`; the 'lean' profile): on for an object of
            fewer than `MULTICCD_HULLS` convex hulls, off for more. Off makes steps ~20 %
            cheaper; an object of several hulls keeps its support polygon (several hulls
            touch the belt), but a single-hull box rocks and sinks ~6 mm into the belt
            without it, and the held-out F0.5 drops (docs/speed.md).
        pulley_facets: The end pulleys' collider: N >= 8 (default 32) makes each an
            N-sided prism mesh circumscribing the pulley radius, with a facet on top flush
            with the deck (32: at most 0.06 mm outside a 12.5 mm circle); 0 uses MuJoCo's
            cylinder primitive, whose contacts with an object's hull depend on the hull's
            orientation, so a box turned over behaves differently (docs/design-choices.md,
            "Contact asymmetry").
        max_hulls: Hull budget per object: None (default) keeps every convex hull of the
            object; N (the 'lean' profile: 8) merges them (`transfertwin.objects.merge_hulls`,
            least added volume first) into at most N besides its feature hulls. Fewer hulls
            make steps cheaper but fill concavities between parts (docs/speed.md).
        condim: Contact dimensionality of object–belt contacts (3: sliding friction; 4
            adds torsional, 6 adds rolling).
        solref: Contact stiffness/damping time constants (s, -) of object–belt contacts;
            MuJoCo raises a time constant below 2 timesteps to 2 timesteps.
        solimp: Contact impedance (d0, dwidth, width, midpoint, power).
        feature_solref: Compliant features: contact time constant and damping ratio of an
            object's feature hulls (a calibrated proxy's protrusions: cable housings, plastic
            clips, rubber that yield under load) against the belts; the feature geoms then
            carry priority 2, so theirs govern (friction stays `SceneConfig.feature_mu` or
            `mu`). None: features are as rigid as the body (the belts' solref).
        guard: Detect implausible events (a counter-measure against contact simulation that
            launches objects): the object faster than `guard_speed_factor` x belt speed plus
            what a free fall from its highest point since the reset explains; a rise in its
            mechanical energy (kinetic + potential) above `guard_energy_j_per_kg` x mass
            between two checks (every `VirtualTransferSystem.step` call, i.e. every camera
            sample); a contact penetrating deeper than `guard_penetration_m`; a non-finite
            state (always checked). Any of them raises `SimulationUnstable`.
        guard_speed_factor, guard_energy_j_per_kg, guard_penetration_m: Guard limits. In
            60 ordinary runs of random cores (fast profile) the largest values seen were
            1.4 x belt speed, 0.09 J/kg and 8 mm (an edge on a pulley): the limits leave
            a margin of 3-5x (docs/explanation/rehearsal.md).
        guard_retry_timestep_factor: With `guard` on, a run marked 'unstable' is run once
            more with the timestep times this factor (None: no re-run).

    The contact settings are set on the belt geoms *and* the object's: the belts carry
    contact priority 1, and MuJoCo takes every contact parameter from the geom of higher
    priority. (Until this was found they were set on the object only and had no effect;
    the defaults are the values that were in effect then — MuJoCo's geom defaults —
    so outcomes did not change.)
    """

    timestep_s: float = 0.005
    integrator: str = "implicitfast"
    solver: str = "Newton"
    cone: str = "elliptic"
    iterations: int = 50
    ls_iterations: int = 20
    tolerance: float = 1e-8
    impratio: float = 1.0
    noslip_iterations: int = 0
    multiccd: bool | None = True
    pulley_facets: int = 32
    max_hulls: int | None = None
    condim: int = 3
    solref: tuple[float, float] = (0.02, 1.0)
    solimp: tuple[float, float, float, float, float] = (0.9, 0.95, 0.001, 0.5, 2.0)
    feature_solref: tuple[float, float] | None = None
    guard: bool = False
    guard_speed_factor: float = 5.0
    guard_energy_j_per_kg: float = 0.5
    guard_penetration_m: float = 0.015
    guard_retry_timestep_factor: float | None = 0.5

    def __post_init__(self) -> None:
        _positive(
            "PhysicsConfig",
            timestep_s=self.timestep_s,
            tolerance=self.tolerance,
            impratio=self.impratio,
            guard_speed_factor=self.guard_speed_factor,
            guard_energy_j_per_kg=self.guard_energy_j_per_kg,
            guard_penetration_m=self.guard_penetration_m,
        )
        if self.feature_solref is not None:
            if len(self.feature_solref) != 2:
                raise InputError("PhysicsConfig.feature_solref must be (timeconst, dampratio)")
            _positive("PhysicsConfig", feature_solref=min(self.feature_solref))
        f = self.guard_retry_timestep_factor
        if f is not None and not (isinstance(f, (int, float)) and 0 < f < 1):
            raise InputError(
                f"PhysicsConfig.guard_retry_timestep_factor must be in (0, 1) or none, got {f!r}"
            )
        if self.solver not in _SOLVERS:
            raise InputError(f"PhysicsConfig.solver must be one of {_SOLVERS}, got {self.solver!r}")
        if self.cone not in _CONES:
            raise InputError(f"PhysicsConfig.cone must be one of {_CONES}, got {self.cone!r}")
        if self.integrator not in _INTEGRATORS:
            raise InputError(
                f"PhysicsConfig.integrator must be one of {_INTEGRATORS}, got {self.integrator!r}"
            )
        facets = self.pulley_facets
        if (
            isinstance(facets, bool)
            or not isinstance(facets, int)
            or not (facets == 0 or 8 <= facets <= 256)
        ):
            raise InputError(
                f"PhysicsConfig.pulley_facets must be 0 or an integer 8..256, got {facets!r}"
            )
        budget = self.max_hulls
        if budget is not None and (
            isinstance(budget, bool) or not isinstance(budget, int) or budget < 1
        ):
            raise InputError(f"PhysicsConfig.max_hulls must be >= 1 or none, got {budget!r}")
        if self.multiccd is not None and not isinstance(self.multiccd, bool):
            raise InputError(
                f"PhysicsConfig.multiccd must be true, false or none, got {self.multiccd!r}"
            )
        if self.condim not in (1, 3, 4, 6):
            raise InputError(f"PhysicsConfig.condim must be 1, 3, 4 or 6, got {self.condim!r}")
        if self.iterations < 1 or self.ls_iterations < 1 or self.noslip_iterations < 0:
            raise InputError("PhysicsConfig iteration counts must be >= 1 (noslip >= 0)")

    def multiccd_for(self, n_hulls: int) -> bool:
        """Whether multi-CCD is on for an object of `n_hulls` convex hulls (after the hull
        budget, features included): `multiccd` when set, else on below `MULTICCD_HULLS`."""
        if self.multiccd is not None:
            return self.multiccd
        return n_hulls < MULTICCD_HULLS


@dataclass(frozen=True)
class LayoutConfig:
    """Geometry of TM^V and TU^V in the tip frame F_T (m).

    F_T: origin at the TM's front tip on the belt surface, x towards the TU, z up.
    TM belts span x in [-tm_length_m, 0], TU belts x in [d_gap, d_gap + tu_length_m]
    (nominal pose). Each unit has a *left* (y > 0) and a *right* (y < 0) belt of width
    `belt_width_m`, separated by `belt_separation_m`. A belt is a flat deck plus a
    pulley of radius `pulley_radius_m` at each end, so the belt surface rounds
    off at the unit's ends: that rounding and the gap make the hand-over hard.

    Attributes:
        tm_length_m: Length of the TM belts.
        tu_length_m: Length of the TU belts.
        belt_width_m: Width of one belt.
        belt_separation_m: Free space between a unit's left and right belt.
        pulley_radius_m: End pulley radius (study: not given; 12.5 mm, the prototype's
            estimate of 10-15 mm, chosen by the held-out fit in docs/fidelity.md).
        belt_speed_m_s: Surface speed of a running belt (study: not given; 0.15 m/s).
        tip_to_centre_m: Distance from F_T back to the TM centre frame F_D, the point
            the docking error rotates about (study: not given; 0.40 m chosen).
        barrier_height_m: Height of the light barriers' beams above the belt surface.
        barrier_inset_m: Distance of a barrier from its unit's end.
        tu_height_offset_m: Height of the docked TU's belt surface above the TM's (a step
            at the gap; candidate mechanism nobody measured; 0 nominal, within ±50 mm).
        tu_pitch_deg: Tilt of the docked TU about the gap line (its near end's line, the
            TU frame's y axis on the belt surface); positive raises the TU's far end, so its
            belt climbs away from the gap. 0 nominal, within ±10°.
        tu_roll_deg: Tilt of the docked TU about its centre line (the TU frame's x axis,
            through the gap line's middle); positive raises the TU's left belt (y > 0).
            0 nominal, within ±10°.
    """

    tm_length_m: float = 0.65
    tu_length_m: float = 0.5
    belt_width_m: float = 0.195
    belt_separation_m: float = 0.01
    pulley_radius_m: float = 0.0125
    belt_speed_m_s: float = 0.15
    tip_to_centre_m: float = 0.40
    barrier_height_m: float = 0.012
    barrier_inset_m: float = 0.015
    tu_height_offset_m: float = 0.0
    tu_pitch_deg: float = 0.0
    tu_roll_deg: float = 0.0

    def __post_init__(self) -> None:
        _bounded("LayoutConfig.tu_height_offset_m", self.tu_height_offset_m, 0.05)
        _bounded("LayoutConfig.tu_pitch_deg", self.tu_pitch_deg, 10.0)
        _bounded("LayoutConfig.tu_roll_deg", self.tu_roll_deg, 10.0)
        _positive(
            "LayoutConfig",
            tm_length_m=self.tm_length_m,
            tu_length_m=self.tu_length_m,
            belt_width_m=self.belt_width_m,
            pulley_radius_m=self.pulley_radius_m,
            belt_speed_m_s=self.belt_speed_m_s,
            tip_to_centre_m=self.tip_to_centre_m,
            barrier_height_m=self.barrier_height_m,
        )
        if 2 * self.pulley_radius_m >= min(self.tm_length_m, self.tu_length_m):
            raise InputError("LayoutConfig.pulley_radius_m is too large for the belt length")

    def belt_centre_y(self, belt: str) -> float:
        """Centre line y (m) of belt 'left' or 'right' in its unit's frame."""
        offset = 0.5 * (self.belt_separation_m + self.belt_width_m)
        return offset if belt == "left" else -offset


@dataclass(frozen=True)
class PlacementConfig:
    """How a pre-transfer state is realised in simulation (docs/design-choices.md,
    "Object frame, faces and placement").

    The object is dropped from `drop_height_m` above the belt and settles with all belts
    stopped for `settle_time_s`. Real placement is never exact: each run draws a small
    pose perturbation from its seed (`sigma_xy_m`, `sigma_theta_deg`); set both to 0
    for an exact placement.

    With `rest_speed_m_s` set, settling ends early once the object is at rest: after at
    least `min_settle_time_s`, as soon as its rest speed (`VirtualTransferSystem.
    object_rest_speed`: body-origin speed plus 0.1 m times the angular speed) is below
    `rest_speed_m_s`, checked every `rest_check_s`; `settle_time_s` stays the upper bound.
    None settles for exactly `settle_time_s` (the reference behaviour). The same rule
    applies to the pause between the two transfers of E^V.
    """

    drop_height_m: float = 0.002
    settle_time_s: float = 0.6
    sigma_xy_m: float = 0.002
    sigma_theta_deg: float = 1.0
    rest_speed_m_s: float | None = 0.005
    min_settle_time_s: float = 0.1
    rest_check_s: float = 0.02

    def __post_init__(self) -> None:
        _positive(
            "PlacementConfig",
            settle_time_s=self.settle_time_s,
            min_settle_time_s=self.min_settle_time_s,
            rest_check_s=self.rest_check_s,
        )
        if self.rest_speed_m_s is not None:
            _positive("PlacementConfig", rest_speed_m_s=self.rest_speed_m_s)
        if self.drop_height_m < 0 or self.sigma_xy_m < 0 or self.sigma_theta_deg < 0:
            raise InputError("PlacementConfig heights and sigmas must be >= 0")


@dataclass(frozen=True)
class SceneConfig:
    """Everything that defines one virtual transfer system instance.

    Attributes:
        mu: Dynamic friction coefficient between belts and object (study's best 0.489).
        gap_m: Nominal gap d_gap between the TM tip and the TU's first belt end
            (study's best 11.88 mm).
        camera_rate_hz: Rate at which the object's state is sampled and the sets are
            evaluated (a depth camera's frame rate; 15 Hz, 'reference': 30 Hz). Each
            sample costs Python work, so it bounds the framework overhead per step.
        t_max_s: Timeout of one OTS (Eq. 5.8/5.9).
        stall_time_s: Early timeout: when the object's AABB centre has stayed within
            `stall_tol_m` of one point for this long while a transfer runs, nothing will
            change before t_max (a stuck or stopped object), so the transfer ends now as
            the timeout it would become, with t_end = the timeout time. None waits for
            t_max (the reference behaviour).
        stall_tol_m: Displacement below which the object counts as immobile.
        stall_mode: What "immobile" means for the early timeout: 'progress' (default) —
            the AABB centre gets no `stall_tol_m` further towards the receiving unit, so a
            core stuck at the gap that creeps sideways also ends early (about half of all
            physics steps were such creeping at the gap); 'still' — the centre stays
            within `stall_tol_m` of one point (the earlier rule). Measured to agree with
            the 'reference' profile; the rare core that creeps for seconds and then
            passes is lost (2 of 288 experiments, docs/speed.md).
        feature_mu: Friction coefficient of an object's *features* — the protrusion hulls of
            a calibrated proxy (`transfertwin.objects.ProxySpec`): the steel ears, bolt heads
            and studs a real core rests on — against the belts and pulleys. None uses `mu`
            (today's behaviour); no effect on an object without features. (A whole-object
            override would be the same as changing `mu`: every contact that matters is
            object-vs-belt.)
        com_offset_m: Shift of the object's centre of mass along its own x axis (towards the
            pinion for > 0), a non-uniform mass distribution; the inertia about the centre
            of mass is kept. 0 nominal, within ±100 mm.
        physics, layout, placement: Sub-configurations.
    """

    mu: float = 0.489
    gap_m: float = 0.01188
    camera_rate_hz: float = 15.0
    t_max_s: float = 30.0
    stall_time_s: float | None = 5.0
    stall_tol_m: float = 0.002
    stall_mode: str = "progress"
    feature_mu: float | None = None
    com_offset_m: float = 0.0
    physics: PhysicsConfig = field(default_factory=PhysicsConfig)
    layout: LayoutConfig = field(default_factory=LayoutConfig)
    placement: PlacementConfig = field(default_factory=PlacementConfig)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.mu) and self.mu >= 0):
            raise InputError(f"SceneConfig.mu must be >= 0, got {self.mu!r}")
        if not (math.isfinite(self.gap_m) and 0 <= self.gap_m < 0.5):
            raise InputError(f"gap must be in [0, 500) mm, got {self.gap_m * 1000:g} mm")
        _positive("SceneConfig", camera_rate_hz=self.camera_rate_hz, t_max_s=self.t_max_s)
        _positive("SceneConfig", stall_tol_m=self.stall_tol_m)
        if self.stall_time_s is not None:
            _positive("SceneConfig", stall_time_s=self.stall_time_s)
        if self.stall_mode not in STALL_MODES:
            raise InputError(
                f"SceneConfig.stall_mode must be one of {STALL_MODES}, got {self.stall_mode!r}"
            )
        if self.feature_mu is not None and not (
            isinstance(self.feature_mu, (int, float))
            and math.isfinite(self.feature_mu)
            and self.feature_mu >= 0
        ):
            raise InputError(
                f"SceneConfig.feature_mu must be >= 0 or none, got {self.feature_mu!r}"
            )
        _bounded("SceneConfig.com_offset_m", self.com_offset_m, 0.1)

    def steps_per_sample(self) -> int:
        """Physics steps between two camera samples (at least 1)."""
        return max(1, round(1.0 / (self.camera_rate_hz * self.physics.timestep_s)))

    def with_overrides(self, **changes: object) -> SceneConfig:
        """`dataclasses.replace` that also accepts dotted names, e.g. ``physics.solver``."""
        nested: dict[str, dict[str, object]] = {}
        flat: dict[str, object] = {}
        for key, value in changes.items():
            head, _, tail = key.partition(".")
            if tail:
                nested.setdefault(head, {})[tail] = value
            else:
                flat[key] = value
        names = {f.name for f in fields(self)}
        for head, sub in nested.items():
            if head not in ("physics", "layout", "placement"):
                raise InputError(f"unknown configuration section {head!r}")
            current = getattr(self, head)
            known = {f.name for f in fields(current)}
            unknown = set(sub) - known
            if unknown:
                raise InputError(f"unknown {head} setting(s): {', '.join(sorted(unknown))}")
            flat[head] = replace(current, **sub)
        unknown = set(flat) - names
        if unknown:
            raise InputError(f"unknown scene setting(s): {', '.join(sorted(unknown))}")
        return replace(self, **flat)


@dataclass(frozen=True)
class DockingError:
    """Docking error ξ = (ξx, ξy, ξθ): pose of the docked TM centre F_D in its goal F_D_G.

    Eq. 6.11. Units: metres and radians. A negative ξx means the TM stopped short of its
    goal, which widens the gap.
    """

    x_m: float = 0.0
    y_m: float = 0.0
    theta_rad: float = 0.0

    def __post_init__(self) -> None:
        for name in ("x_m", "y_m", "theta_rad"):
            if not math.isfinite(getattr(self, name)):
                raise InputError(f"docking error {name} must be finite")
        if abs(self.x_m) > 0.2 or abs(self.y_m) > 0.2 or abs(self.theta_rad) > math.radians(30):
            raise InputError(
                "docking error out of range: |x|,|y| must be <= 200 mm and |theta| <= 30 deg"
            )

    @classmethod
    def from_mm_deg(cls, x_mm: float, y_mm: float, theta_deg: float) -> DockingError:
        """Build from the units used in result tables (mm, mm, degrees)."""
        return cls(x_mm / 1000.0, y_mm / 1000.0, math.radians(theta_deg))

    @classmethod
    def from_text(cls, text: str) -> DockingError:
        """Parse ``X_MM,Y_MM,THETA_DEG`` (the ``--dock-error`` option of `transfer`, `study
        run`, `perceive` and `replay`), e.g. ``"-2.5,1,0.5"``.

        Raises:
            InputError: If the text is not three numbers, or they are out of range.
        """
        try:
            values = [float(p) for p in text.split(",")]
        except ValueError:
            values = []
        if len(values) != 3:
            raise InputError(f"--dock-error expects X_MM,Y_MM,THETA_DEG, got {text[:60]!r}")
        return cls.from_mm_deg(*values)

    def as_mm_deg(self) -> tuple[float, float, float]:
        """(x_mm, y_mm, theta_deg) for result tables."""
        return self.x_m * 1000.0, self.y_m * 1000.0, math.degrees(self.theta_rad)


def _reference() -> SceneConfig:
    return SceneConfig(
        physics=PhysicsConfig(timestep_s=0.002, multiccd=True, max_hulls=None, condim=3),
        placement=PlacementConfig(settle_time_s=0.6, rest_speed_m_s=None),
        camera_rate_hz=30.0,
        stall_time_s=None,
    )


def _lean() -> SceneConfig:
    return SceneConfig().with_overrides(**{"physics.max_hulls": 8, "physics.multiccd": None})


#: Named scenes. 'fast' is `SceneConfig()` (the defaults); 'reference' is the settings the
#: fast defaults were validated against (2 ms steps, multi-CCD, fixed 0.6 s settling, no
#: early timeout: every transfer runs to its terminal state or t_max); 'lean' is the fast
#: defaults with cheaper contacts (a core's hulls merged to 8, multi-CCD off for 8+ hulls):
#: ~1.46x the throughput, agreeing with 'reference', at a small cost in held-out F0.5
#: (docs/speed.md).
PROFILES = {"fast": SceneConfig, "reference": _reference, "lean": _lean}


def scene_profile(name: str, **changes: object) -> SceneConfig:
    """The named scene of `PROFILES` ('fast', 'reference', 'lean'), with dotted overrides."""
    try:
        base = PROFILES[name]()
    except KeyError:
        raise InputError(f"unknown profile {name!r}; built-in: {', '.join(PROFILES)}") from None
    return base.with_overrides(**changes) if changes else base
