"""What an order needs of the assets that carry it out, in the terms of their capabilities'
constraints (the IDTA capability pattern, `CAPABILITY_SPECS`): matched against each
partner's constraint values by `transfertwin.cps.node.Partner.admits`."""

from __future__ import annotations

import functools
from collections.abc import Mapping
from types import MappingProxyType

__all__ = ["object_needs"]


@functools.cache
def object_needs(obj: str) -> Mapping[str, float]:
    """What moving object `obj` needs: ``{"ObjectMass": kg}`` for a built-in core (its mass,
    `transfertwin.objects.core_spec`); nothing for an object the package does not know.

    Example: ``object_needs("o4")`` is ``{"ObjectMass": 4.81...}``: a module whose transport
    capability says ``ObjectMassMax = 3.0`` does not admit it.
    """
    # the mesh library: imported by the TMS when it first weighs an object, not by the
    # processes that import the dispatcher for its data types
    from transfertwin.objects import core_spec, is_builtin_id

    if not is_builtin_id(obj):
        return MappingProxyType({})
    return MappingProxyType({"ObjectMass": float(core_spec(int(obj[1:])).mass_kg)})
