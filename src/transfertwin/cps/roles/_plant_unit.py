"""The emulated plant's physical transfer units (``TU_<name>_P``, kind physical) beside
their virtual models on a floor that runs on the plant (Ch. 3, Fig. 3.3a/5.8, Eq. 5.1–5.3).

Their servers expose what a physical unit exposes (belt speeds, light barriers, docked
transport module, possessed objects, from the same AAS tables as the virtual models) and
one more operation, ``RunTransfer``: one experiment cycle at that station — the plant's
transport module docks, the object goes over in the given pre-transfer state and back —
executed in the plant's hidden simulation (`transfertwin.plant.EmulatedPlant`). It answers
with the plant's log row (the columns of the real calibration table plus the cycle time),
nothing else. The Experiment Manager runs E^P with the same ``RunExperiment`` call as E^V
(`physical_record` gives the row the shape of an E^V record) and appends the log row to
``plant_experiments.csv`` in the floor's work folder, a table `calibrate --real` and the
rehearsal read like the real one.

What keeps the plant's parameters hidden: the plant lives in `PhysicalPlant`'s private
slot and is used through `EmulatedPlant.stations` and `EmulatedPlant.operate` only;
nothing a server, the AAS, the knowledge graph or cps.json holds is derived from a hidden
parameter; the plant seed is read from the floor's seed file (`read_plant_seed`). The
physical units served by one process share one plant (`plant_for`): its experiment ids
follow the order of their cycles, so the same sequence gives the same rows.
"""

from __future__ import annotations

import asyncio
import csv
import json
import logging
import math
import threading
from pathlib import Path
from typing import TYPE_CHECKING, Any

from transfertwin._errors import InputError
from transfertwin.cps.aas import (
    Arg,
    AssetDescriptor,
    OperationSpec,
    demo_descriptors,
    physical_twin,
)
from transfertwin.cps.floor import (
    check_plant_seed,
    read_plant_kind,
    read_plant_off,
    read_plant_seed,
)
from transfertwin.cps.hal import load_scene
from transfertwin.cps.opcua import OperationRefused
from transfertwin.cps.roles._unit import UnitRole

if TYPE_CHECKING:
    from transfertwin.cps.node import AssetNode
    from transfertwin.plant import PlantRequest

__all__ = [
    "PHYSICAL_RECORD_EXTRA",
    "PLANT_LOG",
    "RUN_TRANSFER",
    "PhysicalPlant",
    "PlantUnitRole",
    "append_plant_log",
    "physical_record",
    "plant_descriptors",
    "plant_for",
]

log = logging.getLogger("transfertwin.cps")

#: The work-folder table of E^P rows (the real calibration table's columns).
PLANT_LOG = "plant_experiments.csv"

#: Keys of a physical record beyond an E^V row's (`store.RESULT_COLUMNS`).
PHYSICAL_RECORD_EXTRA = ("kind", "experiment_id", "transfer_unit", "gap_area_cm2")

#: The transport module the plant's schedule docks (a plant resource, not an asset).
PLANT_TM = "TM_1_P"

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


def plant_descriptors() -> tuple[AssetDescriptor, ...]:
    """The physical twins of the demo's virtual transfer units (``TU_A_P``…``TU_D_P``)."""
    return tuple(physical_twin(d) for d in demo_descriptors() if d.asset_class == "transfer_unit")


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
        kind: The plant's kind ('in-class', 'mismatch' or 'bullet', `FLOOR_PLANT_KINDS`).
        mismatch_off: Mismatch parts switched off (`EmulatedPlant`'s, an ablation).
    """

    __slots__ = ("__lock", "__plant")

    def __init__(self, seed: int, kind: str = "in-class",
                 mismatch_off: tuple[str, ...] = ()) -> None:  # fmt: skip
        from transfertwin.plant import FLOOR_PLANT_KINDS, EmulatedPlant

        if kind not in FLOOR_PLANT_KINDS:
            raise InputError(f"a floor's plant kind must be one of "
                             f"{', '.join(FLOOR_PLANT_KINDS)}, got {kind!r}")  # fmt: skip
        self.__plant = EmulatedPlant(check_plant_seed(seed), kind,
                                     mismatch_off=tuple(mismatch_off))  # fmt: skip
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


_PLANTS: dict[tuple[int, str, tuple[str, ...]], PhysicalPlant] = {}
_PLANTS_LOCK = threading.Lock()


def plant_for(seed: int, kind: str = "in-class",
              mismatch_off: tuple[str, ...] = ()) -> PhysicalPlant:  # fmt: skip
    """This process's plant of `seed`, `kind` and `mismatch_off` (drawn once; fitting its
    docking model takes a few seconds): every physical unit served here runs its cycles
    on it."""
    key = (seed, kind, tuple(sorted(mismatch_off)))
    with _PLANTS_LOCK:
        if key not in _PLANTS:
            _PLANTS[key] = PhysicalPlant(*key)
        return _PLANTS[key]


class PlantUnitRole(UnitRole):
    """A physical transfer unit of the emulated plant: a unit's belts, docking and
    possession, and ``RunTransfer`` (one experiment cycle at its station, in the plant)."""

    def __init__(self, node: AssetNode) -> None:
        super().__init__(node)
        self._seed = read_plant_seed(node.cfg.hal.plant_seed_file)
        self._kind = read_plant_kind(node.cfg.hal.plant_seed_file)
        self._off = read_plant_off(node.cfg.hal.plant_seed_file)
        self._cycling = False

    def operations(self) -> tuple[OperationSpec, ...]:
        return (RUN_TRANSFER,)

    def handlers(self) -> dict[str, Any]:
        return {**super().handlers(), "RunTransfer": self._run_transfer}

    async def start(self) -> None:
        await self.set("PossessedObjects", ",".join(self.state.data["possessed"]))
        await self.set("DockedTransportModule", self.state.data["docked"])
        self.node.server.on_client_write(self._written)
        # drawn before it is asked
        self.node.spawn(asyncio.to_thread(plant_for, self._seed, self._kind, self._off))

    async def _set_belt(self, belt: str, speed: float) -> bool:
        if self._cycling:
            raise _refused(f"{self.aid} is running an experiment cycle")
        return await super()._set_belt(belt, speed)

    async def _run_transfer(self, obj: str, face: str, conveyor: str, theta_deg: int) -> str:
        """The unit's experiment cycle, executed by the plant."""
        from transfertwin.plant import PlantRequest

        if self._cycling:
            raise _refused(f"{self.aid} is running an experiment cycle")
        plant = await asyncio.to_thread(plant_for, self._seed, self._kind, self._off)
        if _station(self.aid) not in plant.stations:
            raise _refused(f"the plant has no station for {self.aid}")
        request = PlantRequest(obj, face, conveyor, int(theta_deg), _station(self.aid))
        nominal = load_scene().layout.belt_speed_m_s
        self._cycling = True
        try:
            # What the unit shows while the cycle runs: the plant's TM docked, its belts at
            # the commanded (nominal) speed.
            await self.set("DockedTransportModule", PLANT_TM)
            for belt in ("Left", "Right"):
                await self.set(f"BeltSpeed{belt}", float(nominal))
            row = await asyncio.to_thread(plant.cycle, request)
        finally:
            for belt in ("Left", "Right"):
                await self.set(f"BeltSpeed{belt}", 0.0)
            await self.set("DockedTransportModule", "")
            self._cycling = False
        return json.dumps(row)


def _refused(reason: str) -> OperationRefused:
    return OperationRefused(reason, status="BadInvalidState")


def append_plant_log(path: Path, row: dict[str, Any]) -> None:
    """Append an E^P row to the floor's plant log (the real calibration table's columns)."""
    from transfertwin.plant import PLANT_COLUMNS

    new = not path.exists()
    with path.open("a", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=PLANT_COLUMNS, extrasaction="ignore")
        if new:
            writer.writeheader()
        writer.writerow(row)
