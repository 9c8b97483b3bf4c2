"""MuJoCo scene builders for TM^V, TU^V and the object (Sec. 5.2.1), over `mujoco.MjSpec`.

World frame = the TM tip frame F_T. The TM is static in the world; the TU is a mocap body,
so its docked pose (and thereby the docking error) is set per experiment in `MjData`
without recompiling. Belts are static geoms with `surfacevel`: a deck box moving its top
surface along the unit's x, and one pulley at each end (a prism mesh by default, or a
cylinder) spinning with ω = v/r.
Everything is read back by name.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from transfertwin.sim._config import LayoutConfig, PhysicsConfig, SceneConfig
from transfertwin.sim._names import (
    OBJECT_BODY,
    OBJECT_JOINT,
    TU_BODY,
    barrier_sensor,
    belt_geom,
    object_hull,
)

__all__ = [
    "BARRIERS",
    "BELTS",
    "UNITS",
    "add_belt",
    "add_light_barrier",
    "add_object",
    "add_unit",
    "build_spec",
    "configure_physics",
    "pulley_prism",
    "unit_layout",
]

UNITS = ("tm", "tu")
BELTS = ("left", "right")
BARRIERS = ("near", "far")

# Rotation taking a cylinder's local z axis onto world +y (pulley axles run across the belt).
_Z_TO_Y = np.array([np.cos(-np.pi / 4), np.sin(-np.pi / 4), 0.0, 0.0])
# Rotation taking a site's z axis onto world -y (light barrier beams run across the belt).
_Z_TO_MINUS_Y = np.array([np.cos(np.pi / 4), np.sin(np.pi / 4), 0.0, 0.0])

_BELT_RGBA = (0.15, 0.15, 0.17, 1.0)
_PULLEY_RGBA = (0.45, 0.45, 0.5, 1.0)
_OBJECT_RGBA = (0.62, 0.52, 0.38, 1.0)


@dataclass(frozen=True)
class UnitGeometry:
    """A unit's belt span along its own x axis (m): from `x_start` to `x_end`."""

    x_start: float
    x_end: float


def configure_physics(spec: mujoco.MjSpec, physics: PhysicsConfig, n_hulls: int = 1) -> None:
    """Write the solver settings of `physics` into `spec.option` (for an object of
    `n_hulls` convex hulls: multi-CCD may depend on it, `PhysicsConfig.multiccd_for`)."""
    opt = spec.option
    opt.timestep = physics.timestep_s
    opt.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{physics.integrator.upper()}")
    opt.solver = getattr(mujoco.mjtSolver, f"mjSOL_{physics.solver.upper()}")
    opt.cone = getattr(mujoco.mjtCone, f"mjCONE_{physics.cone.upper()}")
    opt.iterations = physics.iterations
    opt.ls_iterations = physics.ls_iterations
    opt.tolerance = physics.tolerance
    opt.impratio = physics.impratio
    opt.noslip_iterations = physics.noslip_iterations
    # MuJoCo >= 4 generates multiple contacts per convex pair by default; opt out here.
    if not physics.multiccd_for(n_hulls):
        opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_MULTICCD)


def add_belt(
    parent: mujoco.MjsBody,
    unit: str,
    belt: str,
    span: UnitGeometry,
    layout: LayoutConfig,
    mu: float,
    physics: PhysicsConfig | None = None,
    spec: mujoco.MjSpec | None = None,
) -> None:
    """Add one belt (deck + two end pulleys) to `parent`, in the unit's frame.

    The top of the belt is at z = 0. Geom names: ``{unit}_{belt}_deck``,
    ``{unit}_{belt}_pulley_start``, ``{unit}_{belt}_pulley_end``. The belts carry
    priority 1 so that their friction `mu` governs every contact with the object — and,
    because MuJoCo takes *all* contact parameters from the higher-priority geom, also
    `physics`' condim, solref and solimp, which are therefore set on the belt geoms here
    (None: MuJoCo's defaults). The pulleys are prism meshes when `physics.pulley_facets`
    is set, as by default (their meshes are added to `spec`, required then), else MuJoCo
    cylinders; either way a pulley's axle runs along the unit's y axis and its surface
    turns with the belt.
    """
    physics = physics if physics is not None else PhysicsConfig()
    r = layout.pulley_radius_m
    half_w = 0.5 * layout.belt_width_m
    y = layout.belt_centre_y(belt)
    friction = [mu, 0.005, 0.0001]
    x0, x1 = span.x_start + r, span.x_end - r
    deck = parent.add_geom(
        name=belt_geom(unit, belt, "deck"),
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.5 * (x1 - x0), half_w, r],
        pos=[0.5 * (x0 + x1), y, -r],
        rgba=_BELT_RGBA,
    )
    # Any non-zero surface velocity at compile time enables the feature; drives reset it.
    deck.surfacevel = np.array([layout.belt_speed_m_s, 0, 0, 0, 0, 0], dtype=float)
    deck.priority = 1
    deck.friction = friction
    _contact_settings(deck, physics)
    facets = physics.pulley_facets
    if facets and spec is None:
        raise ValueError("prism pulleys need the spec to add their meshes to")
    for end, x in (("start", x0), ("end", x1)):
        name = belt_geom(unit, belt, f"pulley_{end}")
        if facets:
            spec.add_mesh(name=name, uservert=pulley_prism(r, half_w, facets).ravel())
            shape = {"type": mujoco.mjtGeom.mjGEOM_MESH, "meshname": name}
        else:
            shape = {"type": mujoco.mjtGeom.mjGEOM_CYLINDER, "size": [r, half_w, 0]}
        pulley = parent.add_geom(name=name, pos=[x, y, -r], quat=_Z_TO_Y, rgba=_PULLEY_RGBA,
                                 **shape)  # fmt: skip
        # Spin about the geom's z axis (the axle); `MujocoUnitHAL` re-aims it at the axle
        # in the compiled geom frame, which MuJoCo turns to a mesh's principal axes.
        pulley.surfacevel = np.array([0, 0, 0, 0, 0, layout.belt_speed_m_s / r], dtype=float)
        pulley.priority = 1
        pulley.friction = friction
        _contact_settings(pulley, physics)


def pulley_prism(radius_m: float, half_width_m: float, facets: int) -> np.ndarray:
    """Vertices (2·facets, 3) of a prism pulley about the z axis, in float32.

    The polygon circumscribes the circle of `radius_m` (every facet touches it) and a
    facet is centred at each of the angles 0, 90, 180 and 270° when `facets` is a multiple
    of 4: turned by `_Z_TO_Y`, the top facet lies flush with the deck's surface.

    Why a prism: MuJoCo's native collider (nativeccd) finds a single contact between a
    hull and a cylinder, by EPA, and for a hull's face resting on the cylinder's top line
    that contact's normal depends on the hull's orientation (a box's 'front' got a
    horizontal normal, a wall at the roller; its 'back' the vertical one). Between two
    meshes it clips polygons and finds the face's corners wherever the hull points.
    """
    r_circ = radius_m / np.cos(np.pi / facets)
    angles = np.pi / facets + 2 * np.pi * np.arange(facets) / facets
    ring = np.stack([r_circ * np.cos(angles), r_circ * np.sin(angles)], axis=1)
    return np.concatenate([
        np.column_stack([ring, np.full(facets, z)]) for z in (-half_width_m, half_width_m)
    ]).astype(np.float32)  # fmt: skip


def _contact_settings(geom: mujoco.MjsGeom, physics: PhysicsConfig) -> None:
    """condim, solref and solimp of `physics` on `geom`."""
    geom.condim = physics.condim
    geom.solref = np.asarray(physics.solref, dtype=float)
    geom.solimp = np.asarray(physics.solimp, dtype=float)


def add_light_barrier(
    parent: mujoco.MjsBody,
    spec: mujoco.MjSpec,
    unit: str,
    which: str,
    x: float,
    layout: LayoutConfig,
) -> None:
    """Add a light barrier across both belts at unit-frame x: a site and a rangefinder.

    The beam starts just outside the left belt's outer edge and points to -y; the barrier
    is interrupted when the rangefinder sees a geom closer than the beam length.
    """
    y_edge = layout.belt_separation_m / 2 + layout.belt_width_m + 0.01
    site = parent.add_site(
        name=barrier_sensor(unit, which),
        pos=[x, y_edge, layout.barrier_height_m],
        quat=_Z_TO_MINUS_Y,
        size=[0.003, 0, 0],
    )
    sensor = spec.add_sensor(
        name=barrier_sensor(unit, which),
        type=mujoco.mjtSensor.mjSENS_RANGEFINDER,
        objtype=mujoco.mjtObj.mjOBJ_SITE,
        objname=site.name,
    )
    sensor.cutoff = 0.0
    sensor.intprm[0] = 1 << int(mujoco.mjtRayDataField.mjRAYDATA_DIST)


def unit_layout(layout: LayoutConfig, unit: str) -> tuple[UnitGeometry, float, float]:
    """A unit's belt span along its own x axis and the x of its 'near' and 'far' light
    barriers (m), in the unit's frame: TM belts span [-tm_length, 0] of F_T, the TU's
    [0, tu_length] of the TU frame. Every engine's scene takes its geometry from here."""
    if unit == "tm":
        span = UnitGeometry(-layout.tm_length_m, 0.0)
        return span, span.x_end - layout.barrier_inset_m, span.x_start + layout.barrier_inset_m
    span = UnitGeometry(0.0, layout.tu_length_m)
    return span, span.x_start + layout.barrier_inset_m, span.x_end - layout.barrier_inset_m


def add_unit(
    spec: mujoco.MjSpec,
    unit: str,
    layout: LayoutConfig,
    mu: float,
    physics: PhysicsConfig | None = None,
) -> None:
    """Add TM (static, in the world) or TU (mocap body ``tu``) with both belts and barriers.

    TM's belts span x in [-tm_length, 0] of F_T; the TU's span [0, tu_length] of the TU
    frame, whose pose in F_T is set per experiment through ``data.mocap_pos/quat``.
    """
    parent = spec.worldbody if unit == "tm" else spec.worldbody.add_body(name=TU_BODY, mocap=True)
    span, near, far = unit_layout(layout, unit)
    for belt in BELTS:
        add_belt(parent, unit, belt, span, layout, mu, physics, spec)
    add_light_barrier(parent, spec, unit, "near", near, layout)
    add_light_barrier(parent, spec, unit, "far", far, layout)


def add_object(
    spec: mujoco.MjSpec,
    hulls: tuple[np.ndarray, ...],
    mass_kg: float,
    com_m: np.ndarray,
    inertia_kg_m2: np.ndarray,
    physics: PhysicsConfig,
    feature_hulls: int = 0,
    feature_mu: float | None = None,
    mu: float = 0.489,
) -> None:
    """Add the free-floating object body ``object`` built from convex hulls.

    Args:
        spec: Spec to add to.
        hulls: Convex hull vertex arrays, each (k, 3), in the object frame F_O (m).
        mass_kg: Mass of the object.
        com_m: Centre of mass (3,) in F_O.
        inertia_kg_m2: Inertia tensor (3, 3) about the centre of mass, in F_O axes.
        physics: For the contact settings (condim, solref, solimp).
        feature_hulls: How many of the last hulls are features (a proxy's protrusions).
        feature_mu: Friction of the feature hulls; None leaves them to the belts' μ. Set,
            the feature geoms get priority 2 (above the belts' 1), so theirs governs.
        mu: The belts' friction, which priority-2 features keep when `feature_mu` is None
            and only `physics.feature_solref` (compliant features) raised their priority.
            Priority-2 features take condim and solimp from `physics` as the belts do.
    """
    first_feature = len(hulls) - max(0, min(feature_hulls, len(hulls)))
    body = spec.worldbody.add_body(name=OBJECT_BODY, pos=[0, 0, 0.5])
    body.add_freejoint(name=OBJECT_JOINT)
    body.explicitinertial = True
    body.mass = float(mass_kg)
    body.ipos = np.asarray(com_m, dtype=float)
    i = np.asarray(inertia_kg_m2, dtype=float)
    body.fullinertia = np.array([i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2]])
    for k, verts in enumerate(hulls):
        name = object_hull(k)
        spec.add_mesh(name=name, uservert=np.asarray(verts, dtype=np.float32).ravel())
        geom = body.add_geom(
            name=name,
            type=mujoco.mjtGeom.mjGEOM_MESH,
            meshname=name,
            rgba=_OBJECT_RGBA,
            condim=physics.condim,
            friction=[0.0, 0.0, 0.0],
        )
        geom.solref = np.asarray(physics.solref, dtype=float)
        geom.solimp = np.asarray(physics.solimp, dtype=float)
        geom.contype = 1
        geom.conaffinity = 1
        geom.mass = 0.0
        if k >= first_feature and (feature_mu is not None or physics.feature_solref):
            geom.priority = 2
            geom.friction = [feature_mu if feature_mu is not None else mu, 0.005, 0.0001]
            if physics.feature_solref is not None:  # a compliant part
                geom.solref = np.asarray(physics.feature_solref, dtype=float)


def build_spec(
    hulls: tuple[np.ndarray, ...],
    mass_kg: float,
    com_m: np.ndarray,
    inertia_kg_m2: np.ndarray,
    cfg: SceneConfig,
    feature_hulls: int = 0,
) -> mujoco.MjSpec:
    """The full scene: physics options, TM, TU (mocap), object, a floor and lights.

    The floor lies well below the belts; an object that reaches it has fallen. The last
    `feature_hulls` hulls are the object's features (see `add_object`).
    """
    spec = mujoco.MjSpec()
    spec.modelname = "transfertwin_ots"
    configure_physics(spec, cfg.physics, len(hulls))
    spec.visual.global_.offwidth = 1920
    spec.visual.global_.offheight = 1080
    spec.worldbody.add_geom(
        name="floor",
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[3, 3, 0.1],
        pos=[0, 0, -0.6],
        rgba=(0.8, 0.8, 0.78, 1),
    )
    spec.worldbody.add_light(name="sun", pos=[0, 0, 2.0], dir=[0, 0, -1], castshadow=False)
    add_unit(spec, "tm", cfg.layout, cfg.mu, cfg.physics)
    add_unit(spec, "tu", cfg.layout, cfg.mu, cfg.physics)
    add_object(spec, hulls, mass_kg, com_m, inertia_kg_m2, cfg.physics,
               feature_hulls=feature_hulls, feature_mu=cfg.feature_mu, mu=cfg.mu)  # fmt: skip
    return spec
