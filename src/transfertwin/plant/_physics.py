"""`PlantPhysics`: the emulated plant's hardware, for a process that simulates it.

On a process floor in plant mode (`transfertwin cps up --floor F --plant-seed N`) the
transport module's process runs the physics of itself and the unit it is docked at. There
the "real" hardware is the plant's: the object with its hidden features, mass and centre of
mass, the plant's friction, gap, belt slip, and the docked unit's height step and pitch.
`PlantPhysics.system` hands out that compiled system. The `PlantPhysics` object keeps its
seed and scene in name-mangled slots, but the system it returns is a compiled MuJoCo model
that holds the hidden values (the object's hulls, mass and inertia, μ, the gap, the TU's
step and pitch, the belts' slip) in plain arrays: whoever holds the system can read them.
Only the unit's process holds it, behind its HAL; nothing that process publishes carries it.
"""

from __future__ import annotations

from transfertwin._errors import InputError
from transfertwin.plant._mismatch import (
    check_mismatch_off,
    draw_mismatch_scene,
    without_parts,
)
from transfertwin.plant._plant import _mismatch_object, _system
from transfertwin.plant._truth import draw_object, draw_scene
from transfertwin.sim import VirtualTransferSystem

__all__ = ["FLOOR_PLANT_KINDS", "PlantPhysics"]

#: The plant kinds a floor's modules can simulate: the in-class plant, and the mismatch plant
#: (MuJoCo models with the structural differences of `transfertwin.plant._mismatch`). The
#: 'bullet' plant is another engine, which the modules' MuJoCo environment (and its depth
#: camera) cannot step: it runs in rehearsals only.
FLOOR_PLANT_KINDS = ("in-class", "mismatch")


class PlantPhysics:
    """The plant of `seed` as hardware to be driven: one compiled transfer system per object.

    Args:
        seed: The plant seed (non-negative integer; never published).
        kind: 'in-class' (default) or 'mismatch' (`FLOOR_PLANT_KINDS`): the plant
            `EmulatedPlant(seed, kind)` runs its experiments on.
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

    def system(self, object_id: str) -> VirtualTransferSystem:
        """The plant's transfer system (TM + docked TU + object `object_id`), cached: its
        belts slip as the plant's do, and it steps the plant's hidden scene.

        The returned system is a compiled model holding the hidden values (geometry, mass,
        friction, gap, TU pose) readable from its `MjModel`: hand it only to the code that
        plays the hardware (the HAL), never to the twin.
        """
        from transfertwin.objects import builtin_ids

        if object_id not in set(builtin_ids()):
            raise InputError(f"the plant has no object {object_id} (it holds o1..o37)")
        mismatch = None
        if self.__mismatch is not None:
            mismatch = without_parts(_mismatch_object(self.__seed, object_id),
                                     self.__mismatch, self.__off)  # fmt: skip
        return _system(draw_object(self.__seed, object_id), self.__scene, 0, mismatch)
