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
from transfertwin.plant._plant import _system
from transfertwin.plant._truth import draw_object, draw_scene
from transfertwin.sim import VirtualTransferSystem

__all__ = ["PlantPhysics"]


class PlantPhysics:
    """The plant of `seed` as hardware to be driven: one compiled transfer system per object.

    Args:
        seed: The plant seed (non-negative integer; never published).
    """

    __slots__ = ("__scene", "__seed")

    def __init__(self, seed: int) -> None:
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise InputError(f"the plant seed must be a non-negative integer, got {seed!r}")
        self.__seed = seed
        self.__scene = draw_scene(seed)

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
        return _system(draw_object(self.__seed, object_id), self.__scene)
