"""Replays of plant experiments E^P: from what was recorded of them, as a real plant's are.

A real plant's experiment is watched again from its recording (a camera's video, the light
barriers, the controller's log), never from a simulation of the plant, whose parameters no
one knows. So is an emulated plant's: `record_plant` asks the plant that made a logged row
(`EmulatedPlant.observe`) for its recording, a `transfertwin.plant.PlantRecording`, which
holds the object's pose at a camera's resolution, the barriers, the commanded belt speeds,
the controller's clock starts and the logged row, and no hidden parameter. The scene is the
twin's: its nominal units and gap, the TU docked with the row's *measured* docking error,
and the object drawn with the twin's mesh of the core (not the plant's hidden one).

The rows come from a plant's log (`PLANT_COLUMNS`): a rehearsal's ``plant_calibration.csv``,
``plant_test.csv``, ``plant_validation.csv`` (and those of its ``ablate-*`` folders), or a
CPS's ``plant_experiments.csv``. The plant is the one of ``--plant-seed`` or
``--plant-seed-file``, else the one beside the table: the owner-only ``plant.secret`` of a
plant floor's work folder or of a rehearsal's folder (whose ``rehearsal.json`` names the
plant's kind and the mismatch parts switched off, never its seed).
"""

from __future__ import annotations

import csv
import dataclasses
import json
from pathlib import Path

import numpy as np

from transfertwin._errors import InputError
from transfertwin.plant import (
    PLANT_COLUMNS,
    PLANT_KINDS,
    PLANT_SEED_FILE,
    EmulatedPlant,
    PlantRecording,
    read_plant_seed,
)
from transfertwin.replay._record import OTS_CODES, Marker, Replay, compile_system
from transfertwin.sim import DockingError, SceneConfig
from transfertwin.study.experiment import ExperimentSpec

__all__ = ["PlantRow", "plant_row", "plant_source", "record_plant"]


@dataclasses.dataclass(frozen=True)
class PlantRow:
    """One logged row of a plant experiment and the plant that made it.

    Attributes:
        row: The row as the table has it (`PLANT_COLUMNS`).
        index: Its index in the table (0-based, the header not counted).
        table: The table's file name.
        plant: The plant (an `EmulatedPlant`; its seed is not shown anywhere).
        note: Where the plant came from, in words (without its seed).
    """

    row: dict[str, str]
    index: int
    table: str
    plant: EmulatedPlant
    note: str


def _read_seed(path: Path, what: str) -> int:
    try:
        return read_plant_seed(path)
    except InputError as exc:
        raise InputError(f"{what}: {exc}") from None


def _plant_beside(table: Path) -> tuple[int, str, str, tuple[str, ...]] | None:
    """(seed, kind, where, mismatch parts switched off) of the plant that wrote `table`: the
    ``plant.secret`` beside it or one folder up (a plant floor's work folder, a rehearsal's
    folder and its ``ablate-*`` folders), of the kind and parts the ``rehearsal.json`` beside
    that secret names (none: a plant floor's in-class plant)."""
    for folder in (table.parent, table.parent.parent):
        secret = folder / PLANT_SEED_FILE
        record = folder / "rehearsal.json"
        if not secret.is_file():
            continue
        seed = _read_seed(secret, f"{folder.name}/{PLANT_SEED_FILE}")
        if not record.is_file():
            return seed, "in-class", f"the plant of {folder.name}/{PLANT_SEED_FILE}", ()
        try:
            config = json.loads(record.read_text(encoding="utf-8"))["config"]
            kind = str(config.get("plant_kind", "in-class"))
            off = tuple(str(p) for p in config.get("mismatch_off", ()))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError,
                AttributeError) as exc:  # fmt: skip
            raise InputError(f"{record}: not a rehearsal's record ({type(exc).__name__}: "
                             f"{exc})") from None  # fmt: skip
        return seed, kind, f"the plant of {folder.name}/rehearsal.json", off
    return None


def plant_row(
    table: str | Path,
    index: int,
    *,
    plant_seed: int | None = None,
    plant_seed_file: str | Path | None = None,
    plant_kind: str | None = None,
) -> PlantRow:
    """Row `index` of the plant table `table` and the plant that made it: the plant of
    `plant_seed` or of the seed in `plant_seed_file`, else the one beside the table: the
    ``plant.secret`` beside it or one folder up (a plant floor's, or a rehearsal's beside its
    ``rehearsal.json``); of kind `plant_kind` (default: the rehearsal's, else 'in-class')."""
    path = Path(table)
    if plant_seed is not None and plant_seed_file is not None:
        raise InputError("--plant-seed and --plant-seed-file: give one of them")
    if not path.is_file():
        raise InputError(f"--plant-rows {table}: no such file")
    try:
        with path.open(newline="", encoding="utf-8") as fh:
            reader = csv.DictReader(fh)
            missing = [c for c in PLANT_COLUMNS if c not in (reader.fieldnames or ())]
            rows = list(reader)
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise InputError(f"--plant-rows {table}: unreadable ({exc})") from None
    if missing:
        raise InputError(f"--plant-rows {path.name}: not a plant table (no column "
                         f"{', '.join(missing)})")  # fmt: skip
    if isinstance(index, bool) or not 0 <= index < len(rows):
        raise InputError(f"--row must be in 0..{len(rows) - 1} ({path.name}), got {index}")
    found = _plant_beside(path.resolve())
    if plant_seed is not None:
        seed, note = plant_seed, "the plant of --plant-seed"
    elif plant_seed_file is not None:
        seed = _read_seed(Path(plant_seed_file), f"--plant-seed-file {plant_seed_file}")
        note = "the plant of --plant-seed-file"
    elif found is not None:
        seed, note = found[0], found[2]
    else:
        raise InputError(f"--plant-rows {path.name}: which plant made it? Give --plant-seed "
                         "or --plant-seed-file (no plant.secret beside it or one folder "
                         "up: a rehearsal keeps its plant's seed there)")  # fmt: skip
    kind = plant_kind or (found[1] if found is not None else "in-class")
    if kind not in PLANT_KINDS:
        raise InputError(f"--plant-kind must be one of {', '.join(PLANT_KINDS)}, got {kind!r}")
    # the parts a rehearsal switched off, when the plant is that rehearsal's
    off = found[3] if found is not None and found[1] == kind and seed == found[0] else ()
    try:
        plant = EmulatedPlant(seed, kind, mismatch_off=off)
    except InputError as exc:  # a record naming parts this version does not know
        raise InputError(f"{note}: {exc}") from None
    what = kind + (f" without {', '.join(off)}" if off else "")
    return PlantRow(rows[index], index, path.name, plant, f"{note} ({what})")


def _spec(recording: PlantRecording) -> ExperimentSpec:
    """The twin's setting of the experiment: the logged object and state, the measured
    docking error, the twin's nominal scene."""
    row = recording.row
    error = DockingError.from_mm_deg(*(float(row[c]) for c in  # type: ignore[arg-type]
                                       ("dock_err_x_mm", "dock_err_y_mm", "dock_err_theta_deg")))
    return ExperimentSpec(str(row["object_id"]), str(row["face"]), str(row["conveyor"]),
                          int(row["theta_deg"]), docking_error=error,  # type: ignore[arg-type]
                          scene=SceneConfig(), record=True)  # fmt: skip


def _time_line(rec: PlantRecording) -> tuple[np.ndarray, list[Marker]]:
    """OTS codes and markers from the controller's clock starts: it starts its clock at the
    check of S_pre, again when the transfer there forms its OTS, and when the transfer back
    does (which it only starts after the transfer there ended in S+). The end is the log's
    outcome."""
    t, starts = rec.t_s, rec.starts
    codes = np.full(len(t), OTS_CODES["none"], dtype=np.int8)
    placed = "object placed; settling with the belts stopped"
    if rec.attempts > 1:
        placed += f" (placement {rec.attempts}: the earlier ones did not give an outcome)"
    markers = [Marker(0.0, "none", placed)]

    def before(time: float) -> int:
        return max(0, int(np.searchsorted(t, time, side="right")) - 1)

    if len(starts) < 2:
        if starts:
            codes[before(starts[0])] = OTS_CODES["invalid"]
            markers.append(Marker(starts[0], "invalid", "settled state not in S_pre: no transfer"))
    else:
        i = before(starts[1])
        codes[i] = OTS_CODES["pre"]
        codes[i + 1 :] = OTS_CODES["non_terminal"]
        markers.append(Marker(starts[1], "pre", "TM → TU: s(t0) ∈ S_pre: OTS formed"))
        if len(starts) >= 3:
            j = before(starts[2])
            codes[j] = OTS_CODES["success"]
            markers.append(Marker(float(t[j]), "success", "TM → TU: s(t_end) ∈ S+, success"))
            markers.append(Marker(starts[2], "pre", "TU → TM: s(t0) ∈ S_pre: OTS formed"))
    logged = "success" if int(str(rec.row["success"])) == 1 else "failure"
    if len(starts) >= 2:
        codes[-1] = OTS_CODES[logged]
    took = rec.row.get("transfer_time_s")
    took_txt = "" if not isinstance(took, float) or np.isnan(took) else f", {took:.3f} s"
    end = f"end of the recording; the plant's log: {logged}{took_txt}"
    markers.append(Marker(float(t[-1]), logged, end))
    return codes, markers


def record_plant(found: PlantRow) -> Replay:
    """The replay of plant row `found`: its recording (`EmulatedPlant.observe`), drawn in
    the twin's scene (see the module doc)."""
    rec = found.plant.observe(found.row)
    spec = _spec(rec)
    system = compile_system(spec)
    system.reset(spec.docking_error)
    codes, markers = _time_line(rec)
    return Replay(
        spec=spec, result=None, t_s=rec.t_s, qpos=rec.pose, barriers=rec.barriers,
        belts=rec.belts, ots=codes, markers=tuple(markers),
        tu_pose=tuple(float(v) for v in system.tu_pose),  # type: ignore[arg-type]
        nominal_tu_pose=(float(spec.scene.gap_m), 0.0, 0.0), logged=dict(rec.row),
    )  # fmt: skip


def plant_source(found: PlantRow, replay: Replay) -> dict[str, object]:
    """The replay document's ``source`` for a plant row (no seed, no hidden value)."""
    row = replay.logged or {}
    return {"kind": "plant", "table": found.table, "row": found.index,
            "experiment_id": row.get("experiment_id"), "transfer_unit": row.get("transfer_unit"),
            "logged_success": row.get("success"), "note": found.note,
            "drawn": "the twin's nominal scene and mesh, the TU docked with the measured error",
            "camera": "pose to 1 mm and 1e-3 of a quaternion, time to 1 ms"}  # fmt: skip
