"""The emulated plant as the CPS's physical assets (issue 12, item 1; Ch. 3, Eq. 5.1–5.3).

`cps up --plant-seed N` starts, beside the virtual models ``TU_A``…``TU_D``, their physical
twins ``TU_A_P``…``TU_D_P``: transfer units of type D/E whose OPC UA servers expose what a
physical unit exposes (belt speeds, light barriers, docked transport module, possessed
objects, from the same AAS tables as the virtual models) and one more operation,
``RunTransfer``: one experiment cycle at that station — the plant's transport module docks,
the object goes over in the given pre-transfer state and back — executed in the plant's
hidden simulation (`transfertwin.plant.EmulatedPlant`). It answers with the plant's log row
(the columns of the real calibration table plus the cycle time), nothing else.

The Experiment Manager runs E^P with the same ``RunExperiment`` call as E^V: when the unit it
names is a physical asset it calls that unit's ``RunTransfer`` over OPC UA, returns the
record in the shape of an E^V row (`PHYSICAL_RECORD_EXTRA` added; what a real plant does
not observe — y1, y2, the states — is empty) and appends the log row to
``plant_experiments.csv`` in the work folder, a table `calibrate --real` and the rehearsal
read like the real one.

What keeps the plant's parameters hidden: the plant lives in `PhysicalPlant`'s private
slot and is used through `EmulatedPlant.stations` and `EmulatedPlant.operate` only (a test
records every attribute the CPS touches); nothing the physical servers, the AAS, the
knowledge graph or cps.json hold is derived from a hidden parameter (a test browses them
all for the hidden values); the plant seed itself is not published either.
"""

from __future__ import annotations

import asyncio
import csv
import json
import logging
import math
import threading
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import TYPE_CHECKING

from transfertwin._errors import InputError
from transfertwin.cps.aas import (
    Arg,
    AssetDescriptor,
    AssetKind,
    AssetRepresentation,
    OperationSpec,
    build_representation,
    demo_descriptors,
    operation,
    physical_twin,
)
from transfertwin.cps.floor import PROVENANCE as HAL_PROVENANCE
from transfertwin.cps.opcua import OperationRefused

if TYPE_CHECKING:
    from transfertwin.plant import PlantRequest

# The plant (a simulation with the study's calibration stack) is imported when a plant is
# made, not with the CPS: every `cps` command and the web console import this module.

__all__ = [
    "PHYSICAL_RECORD_EXTRA",
    "PLANT_LOG",
    "RUN_TRANSFER",
    "PhysicalAssets",
    "PhysicalPlant",
    "check_plant_seed",
    "physical_record",
    "plant_descriptors",
    "plant_representation",
]

log = logging.getLogger("transfertwin.cps")

#: The work-folder table of E^P rows (the real calibration table's columns).
PLANT_LOG = "plant_experiments.csv"

#: Keys of a physical record beyond an E^V row's (`store.RESULT_COLUMNS`).
PHYSICAL_RECORD_EXTRA = ("kind", "experiment_id", "transfer_unit", "gap_area_cm2")

#: The transport module the plant's schedule docks (a plant resource, not a CPS asset).
PLANT_TM = "TM_1_P"

PROVENANCE = HAL_PROVENANCE["plant"]

RUN_TRANSFER = OperationSpec(
    "RunTransfer",
    (
        Arg("object", "xs:string"),
        Arg("face", "xs:string"),
        Arg("conveyor", "xs:string"),
        Arg("theta_deg", "xs:int", "deg"),
    ),
    (Arg("result_json", "xs:string"),),
    "Run one experiment cycle at this unit: the transport module docks, the object goes "
    "over in the pre-transfer state and back; the plant's log row.",
)


def check_plant_seed(seed: object) -> int:
    """A plant seed as `EmulatedPlant` takes it; InputError otherwise."""
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError(f"--plant-seed must be a non-negative integer, got {seed!r}")
    return seed


def plant_descriptors() -> tuple[AssetDescriptor, ...]:
    """The physical twins of the demo's virtual transfer units (``TU_A_P``…``TU_D_P``)."""
    return tuple(physical_twin(d) for d in demo_descriptors() if d.asset_class == "transfer_unit")


def plant_representation(desc: AssetDescriptor, endpoint: str) -> AssetRepresentation:
    """The AAS a physical unit of the plant serves: its virtual model's structure (same
    OperationalData and ControlInterface rows) plus ``RunTransfer``."""
    if desc.kind is not AssetKind.PHYSICAL or desc.asset_class != "transfer_unit":
        raise InputError(f"{desc.asset_id} is no physical transfer unit")
    rep = build_representation(desc, endpoint=endpoint, provenance=PROVENANCE)
    rep.submodel("ControlInterface").submodel_element.add(operation(RUN_TRANSFER))
    return rep


def physical_record(row: dict[str, object], seed: int) -> dict[str, object]:
    """An E^P log row (`PLANT_COLUMNS` + ``transfer_time_s``) in the shape of an E^V row.

    ``success`` and the docking error are what the plant logged; ``t_end_s`` is the cycle
    time by the plant's clock (NaN when the object never settled in a valid state, which
    the plant logs as a failure); y1, y2, the per-transfer times and the states are not
    observed on a plant and stay empty. ``seed`` is the request's (a real experiment is not
    seeded; it is kept so a record says what was asked).
    """
    t = float(row["transfer_time_s"])  # type: ignore[arg-type]
    return {
        "object_id": row["object_id"], "face": row["face"], "conveyor": row["conveyor"],
        "theta_deg": row["theta_deg"], "run": 0, "seed": int(seed),
        "dock_err_x_mm": row["dock_err_x_mm"], "dock_err_y_mm": row["dock_err_y_mm"],
        "dock_err_theta_deg": row["dock_err_theta_deg"], "y1": None, "y2": None,
        "success": row["success"], "t_end_s": t, "status": "ok",
        "t_end_1_s": math.nan, "t_end_2_s": math.nan,
        "message": "E^P" if math.isfinite(t) else "E^P: no valid pre-transfer state",
        "state_pre": "", "state_end_1": "", "state_end_2": "",
        "kind": "physical", "experiment_id": row["experiment_id"],
        "transfer_unit": row["transfer_unit"], "gap_area_cm2": row["gap_area_cm2"],
    }  # fmt: skip


class PhysicalPlant:
    """The plant side of the CPS: one `EmulatedPlant`, used only through its public
    `stations` and `operate`; one experiment cycle at a time (the plant's experiment ids
    follow the order of the cycles, so the same sequence gives the same rows).

    Args:
        seed: The plant seed (draws every hidden parameter; not published).
    """

    __slots__ = ("__lock", "__plant")

    def __init__(self, seed: int) -> None:
        from transfertwin.plant import EmulatedPlant

        self.__plant = EmulatedPlant(check_plant_seed(seed))
        self.__lock = threading.Lock()

    def __reduce__(self) -> None:  # type: ignore[override]
        raise TypeError("a PhysicalPlant cannot be pickled (its plant's parameters are hidden)")

    @property
    def stations(self) -> tuple[str, ...]:
        """The plant's stations as its log names them ('TU_A', …)."""
        return self.__plant.stations

    def cycle(self, request: PlantRequest) -> dict[str, object]:
        """Run one experiment cycle (blocking); the plant's log row and cycle time."""
        with self.__lock:
            (row,) = self.__plant.operate([request])
        return row


def _station(asset_id: str) -> str:
    """The plant's log name of a physical unit: ``TU_A_P`` → ``TU_A``."""
    return asset_id.removesuffix("_P")


class PhysicalAssets:
    """The CPS's physical assets from an emulated plant (mixed into `Cps` before
    `AssetApplications`): their start, their operations, and the Experiment Manager's E^P.

    Uses the runtime's `config` (``plant_seed``, ``workdir``), `assets`, `client()`,
    `_start()` and `_set_possessed()`.
    """

    _plant: PhysicalPlant | None = None
    _cycling: frozenset[str] = frozenset()

    async def _start_physical(self) -> None:
        """Draw the plant (fitting its docking model takes a few seconds) and start its
        units; rotate an earlier session's E^P log out of the way."""
        seed = getattr(self.config, "plant_seed", None)  # type: ignore[attr-defined]
        if seed is None:
            return
        self._plant = await asyncio.to_thread(PhysicalPlant, seed)
        self._cycling = frozenset()
        path = self._plant_log()
        if path.exists():
            n = 1
            while (old := path.with_name(f"plant_experiments.{n}.csv")).exists():
                n += 1
            path.rename(old)
        for desc in plant_descriptors():
            if _station(desc.asset_id) not in self._plant.stations:
                raise InputError(f"the plant has no station for {desc.asset_id}")
            await self._start(desc)  # type: ignore[attr-defined]
        log.info("plant up: %d physical transfer units", len(plant_descriptors()))

    def _plant_log(self) -> Path:
        return Path(self.config.workdir) / PLANT_LOG  # type: ignore[attr-defined]

    def _is_physical_unit(self, asset_id: str) -> bool:
        asset = self.assets.get(asset_id)  # type: ignore[attr-defined]
        return (
            asset is not None
            and asset.desc.kind is AssetKind.PHYSICAL
            and asset.desc.asset_class == "transfer_unit"
        )

    # -- handlers -------------------------------------------------------------------------
    def _handlers(self, desc: AssetDescriptor) -> dict[str, Callable[..., Awaitable[object]]]:
        if desc.kind is AssetKind.PHYSICAL and desc.asset_class == "transfer_unit":
            aid = desc.asset_id
            possess = self._set_possessed  # type: ignore[attr-defined]
            cycle = self._run_transfer
            return {"SetBeltSpeed": lambda b, v: self._physical_belt(aid, b, v),
                    "SetPossessedObjects": lambda objs: possess(aid, objs),
                    "RunTransfer": lambda o, f, c, t: cycle(aid, o, f, c, t)}  # fmt: skip
        return super()._handlers(desc)  # type: ignore[misc]

    async def _physical_belt(self, aid: str, belt: str, speed: float) -> bool:
        if belt not in ("left", "right"):
            raise ValueError(f"unknown belt {belt!r}")
        if aid in self._cycling:
            raise _refused(f"{aid} is running an experiment cycle")
        server = self.assets[aid].server  # type: ignore[attr-defined]
        await server.set("OperationalData", f"BeltSpeed{belt.capitalize()}", float(speed))
        return True

    async def _run_transfer(self, aid: str, obj: str, face: str, conveyor: str,
                            theta_deg: int) -> str:  # fmt: skip
        """A physical unit's experiment cycle, executed by the plant."""
        if self._plant is None:  # pragma: no cover - physical units exist only with a plant
            raise _refused("no plant")
        if aid in self._cycling:
            raise _refused(f"{aid} is running an experiment cycle")
        from transfertwin.plant import PlantRequest

        request = PlantRequest(obj, face, conveyor, int(theta_deg), _station(aid))
        server = self.assets[aid].server  # type: ignore[attr-defined]
        nominal = self.config.scene.layout.belt_speed_m_s  # type: ignore[attr-defined]
        self._cycling = self._cycling | {aid}
        try:
            # What the unit shows while the cycle runs: the plant's TM docked, its belts at
            # the commanded (nominal) speed.
            await server.set("OperationalData", "DockedTransportModule", PLANT_TM)
            for belt in ("Left", "Right"):
                await server.set("OperationalData", f"BeltSpeed{belt}", float(nominal))
            row = await asyncio.to_thread(self._plant.cycle, request)
        finally:
            for belt in ("Left", "Right"):
                await server.set("OperationalData", f"BeltSpeed{belt}", 0.0)
            await server.set("OperationalData", "DockedTransportModule", "")
            self._cycling = self._cycling - {aid}
        return json.dumps(row)

    # -- experiment manager: E^P ----------------------------------------------------------
    async def _run_experiment(self, unit: str, obj: str, face: str, conveyor: str,
                              theta_deg: int, seed: int) -> str:  # fmt: skip
        """EM: E^V against a virtual unit, E^P against a physical one (over OPC UA)."""
        if not self._is_physical_unit(unit):
            return await super()._run_experiment(unit, obj, face, conveyor, theta_deg, seed)  # type: ignore[misc]
        if isinstance(seed, bool) or int(seed) < 0:
            raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
        async with self.client(unit) as session:  # type: ignore[attr-defined]
            row = json.loads(await session.call("RunTransfer", obj, face, conveyor,
                                                int(theta_deg)))  # fmt: skip
        self._append_log(row)
        log.info("EM: E^P %s on %s: %s %s %s %d: success %s", row["experiment_id"], unit,
                 obj, face, conveyor, int(theta_deg), row["success"])  # fmt: skip
        return json.dumps(physical_record(row, int(seed)))

    def _append_log(self, row: dict[str, object]) -> None:
        from transfertwin.plant import PLANT_COLUMNS

        path = self._plant_log()
        new = not path.exists()
        with path.open("a", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=PLANT_COLUMNS, extrasaction="ignore")
            if new:
                writer.writeheader()
            writer.writerow(row)


def _refused(reason: str) -> OperationRefused:
    return OperationRefused(reason, status="BadInvalidState")
