"""An asset's hardware abstraction layer, by ``[hal] kind``: the twin's own simulation or the
emulated plant's (`environment_for`), a docked virtual unit mirrored into the module's
simulation (`MirroredUnitHAL`), and real hardware behind a HAL gateway (`GatewayHAL` for a
unit, `ModuleGateway` and `GatewayWorld` for a module; the gateway session: `GatewayLink`).
"""

from typing import TYPE_CHECKING

from transfertwin._lazy import lazy_exports

if TYPE_CHECKING:
    from transfertwin.cps.hal._gateway import (
        GatewayError,
        GatewayLink,
        gateway_refusal,
        gateway_trust_dir,
        open_gateway,
        poll_gateway,
    )
    from transfertwin.cps.hal._gateway_module import (
        COMMAND_TIMEOUT_S,
        GatewayWorld,
        ModuleGateway,
        ThreadHAL,
        WallClock,
    )
    from transfertwin.cps.hal._local import GatewayHAL, environment_for, load_scene
    from transfertwin.cps.hal._mirrored import MirroredUnitHAL

__all__ = [
    "COMMAND_TIMEOUT_S",
    "GatewayError",
    "GatewayHAL",
    "GatewayLink",
    "GatewayWorld",
    "MirroredUnitHAL",
    "ModuleGateway",
    "ThreadHAL",
    "WallClock",
    "environment_for",
    "gateway_refusal",
    "gateway_trust_dir",
    "load_scene",
    "open_gateway",
    "poll_gateway",
]

__getattr__, __dir__ = lazy_exports(__name__, __file__)
