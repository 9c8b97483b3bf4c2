"""What each asset class does on its node: transfer units and objects (`UnitRole`,
`ObjectRole`), the knowledge graph (`GraphRole`), the Transport Module System (`TmsRole`),
a virtual transport module or one on real hardware (`ModuleRole`, `RemoteModuleRole`), the
Experiment Manager (`ExperimentRole`) and PropS (`PropsRole`); `role_for` is the registry
the node is handed as its factory.
"""

from typing import TYPE_CHECKING

from transfertwin._lazy import lazy_exports

if TYPE_CHECKING:
    from transfertwin.cps.roles._docking import CAMERA_SIGMA_THETA_RAD, CAMERA_SIGMA_XY_M
    from transfertwin.cps.roles._em import ExperimentRole
    from transfertwin.cps.roles._graph import GraphRole
    from transfertwin.cps.roles._module import ModuleRole
    from transfertwin.cps.roles._plant_unit import (
        PHYSICAL_RECORD_EXTRA,
        PLANT_LOG,
        RUN_TRANSFER,
        PlantUnitRole,
        physical_record,
        plant_descriptors,
    )
    from transfertwin.cps.roles._props import PropsRole
    from transfertwin.cps.roles._registry import role_for
    from transfertwin.cps.roles._remote_module import RemoteModuleRole
    from transfertwin.cps.roles._tms import TmsRole
    from transfertwin.cps.roles._unit import (
        UNIT_SIGMA_THETA_RAD,
        UNIT_SIGMA_XY_M,
        ObjectRole,
        UnitRole,
    )

__all__ = [
    "CAMERA_SIGMA_THETA_RAD",
    "CAMERA_SIGMA_XY_M",
    "PHYSICAL_RECORD_EXTRA",
    "PLANT_LOG",
    "RUN_TRANSFER",
    "UNIT_SIGMA_THETA_RAD",
    "UNIT_SIGMA_XY_M",
    "ExperimentRole",
    "GraphRole",
    "ModuleRole",
    "ObjectRole",
    "PlantUnitRole",
    "PropsRole",
    "RemoteModuleRole",
    "TmsRole",
    "UnitRole",
    "physical_record",
    "plant_descriptors",
    "role_for",
]

__getattr__, __dir__ = lazy_exports(__name__, __file__)
