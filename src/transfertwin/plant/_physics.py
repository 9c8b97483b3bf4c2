"""`PlantPhysics`: the emulated plant's hardware, for a process that simulates it.

On a process floor in plant mode (`transfertwin cps up --floor F --plant-seed N`) the
transport module's process runs the physics of itself and the unit it is docked at. There
the "real" hardware is the plant's: the object with its hidden features, mass and centre of
mass, the plant's friction, gap, belt slip, and the docked unit's height step and pitch.
`PlantPhysics.system` hands out that compiled system. The `PlantPhysics` object keeps its
seed and scene in name-mangled slots, but the system it returns is a compiled model (MuJoCo,
or PyBullet on a 'bullet' plant) that holds the hidden values (the object's hulls, mass and
inertia, μ, the gap, the TU's step and pitch, the belts' slip): whoever holds the system can
read them. Only the module's process holds it, behind its HAL; nothing that process
publishes carries it.
"""

from __future__ import annotations

from transfertwin._errors import InputError
from transfertwin.plant._bullet import BulletTransferSystem
from transfertwin.plant._mismatch import (
    check_mismatch_off,
    draw_mismatch_scene,
    without_parts,
)
from transfertwin.plant._plant import _bullet_system, _mismatch_object, _system
from transfertwin.plant._truth import draw_object, draw_scene
from transfertwin.sim import VirtualTransferSystem

__all__ = ["CAMERA_FREE_KINDS", "FLOOR_PLANT_KINDS", "PlantPhysics", "check_camera"]

#: The plant kinds a floor's modules can simulate: the in-class plant, the mismatch plant
#: (MuJoCo models with the structural differences of `transfertwin.plant._mismatch`), and the
#: in-class plant in PyBullet ('bullet', `transfertwin.plant._bullet`), which no depth camera
#: renders: a floor on it senses the object by its ground truth (`CAMERA_FREE_KINDS`).
FLOOR_PLANT_KINDS = ("in-class", "mismatch", "bullet")

#: The plant kinds whose systems a depth camera cannot render (no MuJoCo model).
CAMERA_FREE_KINDS = ("bullet",)


def check_camera(kind: str, sensor: str, docking: str) -> None:
    """Refuse (InputError, one line) a floor that needs a depth camera on a plant none can
    render: the operation's ``sensor = "camera"`` or ``--docking navigated`` (which scans the
    station) on a 'bullet' plant."""
    if kind in CAMERA_FREE_KINDS and (sensor == "camera" or docking == "navigated"):
        need = "operation.sensor = camera" if sensor == "camera" else "--docking navigated"
        raise InputError(f"a {kind!r} plant has no depth camera to render ({need} needs one): "
                         "use the floor's ground-truth sensor and sampled docking on it")


class PlantPhysics:
    """The plant of `seed` as hardware to be driven: one compiled transfer system per object.

    Args:
        seed: The plant seed (non-negative integer; never published).
        kind: 'in-class' (default), 'mismatch' or 'bullet' (`FLOOR_PLANT_KINDS`): the
            plant `EmulatedPlant(seed, kind)` runs its experiments on.
        mismatch_off: Parts of the mismatch (`MISMATCH_PARTS`) switched back to the
            in-class plant's, as `EmulatedPlant`'s ``mismatch_off`` (an ablation).
    """

    __slots__ = ("__kind", "__mismatch", "__off", "__scene", "__seed")

    def __init__(self, seed: int, kind: str = "in-class",
                 mismatch_off: tuple[str, ...] = ()) -> None:  # fmt: skip
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise InputError(f"the plant seed must be a non-negative integer, got {seed!r}")
        if kind not in FLOOR_PLANT_KINDS:
            raise InputError(f"a floor's plant kind must be one of "
                             f"{', '.join(FLOOR_PLANT_KINDS)}, got {kind!r}")  # fmt: skip
        self.__seed = seed
        self.__kind = kind
        self.__off = check_mismatch_off(mismatch_off, kind)
        self.__scene = draw_scene(seed)
        self.__mismatch = draw_mismatch_scene(seed) if kind == "mismatch" else None

    def __repr__(self) -> str:
        return "PlantPhysics(<hidden>)"

    def __reduce__(self) -> None:  # type: ignore[override]
        raise TypeError("a PlantPhysics cannot be pickled (its plant's parameters are hidden)")

    def system(self, object_id: str) -> VirtualTransferSystem | BulletTransferSystem:
        """The plant's transfer system (TM + docked TU + object `object_id`), cached: its
        belts slip as the plant's do, and it steps the plant's hidden scene (a
        `BulletTransferSystem` on a 'bullet' plant).

        The returned system is a compiled model holding the hidden values (geometry, mass,
        friction, gap, TU pose) readable from its `MjModel` or its PyBullet client: hand it
        only to the code that plays the hardware (the HAL), never to the twin.
        """
        from transfertwin.objects import builtin_ids

        if object_id not in set(builtin_ids()):
            raise InputError(f"the plant has no object {object_id} (it holds o1..o37)")
        if self.__kind == "bullet":
            return _bullet_system(draw_object(self.__seed, object_id), self.__scene)
        mismatch = None
        if self.__mismatch is not None:
            mismatch = without_parts(_mismatch_object(self.__seed, object_id),
                                     self.__mismatch, self.__off)  # fmt: skip
        return _system(draw_object(self.__seed, object_id), self.__scene, 0, mismatch)
