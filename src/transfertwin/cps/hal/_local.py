"""An asset process's hardware: virtual, the emulated plant, or real hardware behind a HAL
gateway (docs/architecture.md, "Deployment"; the ``[hal]`` table of ``ASSET.toml``).

- ``virtual``: the twin's own models; a transport module simulates itself and its docked
  unit with the virtual scene (`Environment`).
- ``plant``: the emulated plant (`transfertwin.plant.PlantPhysics`): a transport module
  simulates its docked pair in the plant's hidden scene with the plant's hidden objects.
  The plant seed is read from a file of its own (``plant_seed_file``), so neither the asset
  file, nor a status, nor a log holds it or anything drawn from it.
- ``remote``: real hardware. The asset writes belt speeds to and reads its light barriers
  from a HAL gateway, an OPC UA server next to the machine (a PLC's, or a small bridge),
  at ``endpoint`` (`GatewayHAL`; the session, secure by default: `cps.hal._gateway`). A
  transport module also drives, localises and senses the object there
  (`cps.roles._remote_module`).
"""

from __future__ import annotations

import functools
import logging
from typing import TYPE_CHECKING

from transfertwin.cps.floor import read_plant_kind, read_plant_off, read_plant_seed
from transfertwin.cps.hal._gateway import GatewayError, GatewayLink, gateway_refusal
from transfertwin.cps.hal._gateway_module import GatewayWorld

if TYPE_CHECKING:
    from transfertwin.cps.floor import AssetConfig
    from transfertwin.sim import SceneConfig

__all__ = ["GatewayHAL", "environment_for", "load_scene"]

log = logging.getLogger("transfertwin.cps")


@functools.cache
def load_scene():
    """The virtual models' scene (the built-in defaults)."""
    from transfertwin.sim import SceneConfig

    return SceneConfig()


def environment_for(cfg: AssetConfig, scene: SceneConfig, sensor: str = "truth"):
    """The simulated world of a transport module's process: the virtual scene's, or, with
    ``[hal] kind = "plant"``, the plant's hidden physics; with ``"remote"`` none (a
    `GatewayWorld`: the hardware behind the gateway is the world). Its `scene` stays the twin's
    (what the module's controller knows: belt speed, thresholds, timing); only the systems
    it steps are the plant's. A plant no depth camera renders (PyBullet's) is refused when
    the floor's `sensor` or the module's docking needs the camera (InputError)."""
    from transfertwin.cps.apps import Environment  # the simulation: a module's process only

    if cfg.hal.kind == "virtual":
        return Environment(scene, cfg.time_scale)
    if cfg.hal.kind == "remote":  # the hardware is the world: nothing is simulated
        return GatewayWorld(scene)
    from transfertwin.plant import PlantPhysics, check_camera

    seed_file = cfg.hal.plant_seed_file
    kind = read_plant_kind(seed_file)
    check_camera(kind, sensor, cfg.docking)
    physics = PlantPhysics(read_plant_seed(seed_file), kind, read_plant_off(seed_file))
    return Environment(scene, cfg.time_scale, physics.system)


class GatewayHAL:
    """A remote transfer unit's belts and light barriers at its HAL gateway (an OPC UA
    server; the session: `cps.hal._gateway`).

    Belt speeds (m/s, Double) are written to the gateway's belt nodes; the barriers
    (Boolean, True: interrupted) are read from its barrier nodes. A belt command the
    gateway does not take is refused (`OperationRefused`, BadCommunicationError); a
    barrier read that fails raises `GatewayError` (a `ConnectionError`); one line each.

    Args:
        cfg: The asset's configuration (its ``[hal]`` table says where and which nodes).
    """

    def __init__(self, cfg: AssetConfig) -> None:
        self.cfg = cfg
        self.link = GatewayLink(cfg)
        self.endpoint = self.link.endpoint
        self.nodes = self.link.nodes

    async def set_belt(self, belt: str, speed_m_s: float) -> None:
        """Command `belt` ('left' or 'right') at the gateway."""
        from asyncua import ua

        if belt not in ("left", "right"):
            raise ValueError(f"unknown belt {belt!r}")
        try:
            await self.link.write(f"belt_{belt}", float(speed_m_s), ua.VariantType.Double)
        except GatewayError as exc:  # the caller is told why, as a refusal (no traceback)
            raise gateway_refusal(exc) from None

    async def barriers(self) -> dict[str, bool]:
        """The light barriers as the gateway reads them."""
        near, far = await self.link.read("barrier_near", "barrier_far")
        return {"near": bool(near), "far": bool(far)}

    async def close(self) -> None:
        """Close the gateway session."""
        await self.link.close()
