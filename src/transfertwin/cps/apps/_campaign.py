"""A calibration campaign the Experiment Manager runs on the floor's own physical units
(Sec. 6.3–6.7 on the running floor; docs/architecture.md, "Calibration campaigns").

A campaign is the rehearsal's whole loop (`transfertwin.rehearsal.rehearse`) with the
floor's physical transfer units as its plant (`FloorPlant`): K calibration experiments
E^P on them over OPC UA (``RunTransfer``), object calibration of the twin on their rows,
its full-state prediction of every object on a θ grid — the floor's whole operation, both
legs — with docking errors from a copula fitted to the units' logged errors, and the
validation of each object's best and worst state against V more E^P (Newcombe, Sec. 6.7).
Its folder holds what ``transfertwin rehearse`` writes, and ``predictions.json``: each
object's states ranked as the TMS ranks them (the job's `predict`, e.g.
`transfertwin.cps.dispatch.campaign_predictions`).

Every E^P is journaled (``plant_journal.jsonl``) the moment it returns: a campaign that is
stopped, or whose process died, resumes from its request; the E^P it had are read back
from the journal (never run twice), the virtual experiments are computed again (the same
seeds: the same bits).
"""

from __future__ import annotations

import hashlib
import json
import math
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from transfertwin._atomic import write_atomic
from transfertwin._errors import InputError

__all__ = [
    "CAMPAIGN_MEASURES",
    "CampaignJob",
    "CampaignRequest",
    "CampaignStoppedError",
    "FloorPlant",
    "UnitUnavailableError",
]

#: The journal of a campaign's E^P, one JSON line each (``key``, ``unit``, ``row``).
JOURNAL = "plant_journal.jsonl"
#: The ranked states per object a finished campaign publishes.
PREDICTIONS = "predictions.json"
#: The campaign's status, rewritten on every change.
STATUS = "campaign.json"

#: The twin's counter-measures in a campaign: the floor's units have no scale, so the
#: measured-mass one (the plant's `weigh` in a rehearsal) is off.
CAMPAIGN_MEASURES = ("stability", "compliance")

_KEYS = {"objects", "experiments", "runs", "validation_runs", "theta_step", "seed",
         "workers", "holdout", "depths_mm", "tune_trials", "design", "object_prior",
         "min_face_rows", "sampling"}  # fmt: skip


class CampaignStoppedError(Exception):
    """Raised inside the campaign's thread when it was asked to stop."""


class UnitUnavailableError(Exception):
    """A physical unit cannot run E^P at all (e.g. the plant has no station for it): the
    campaign goes on without it. `run_one` raises it; its argument is the reason."""

    def __init__(self, unit: str, reason: str) -> None:
        super().__init__(f"{unit}: {reason}")
        self.unit = unit


def _int(d: Mapping[str, Any], key: str, default: int, low: int, high: int) -> int:
    value = d.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise InputError(f"campaign: '{key}' must be an integer in {low}..{high}, got {value!r}")
    return value


@dataclass(frozen=True)
class CampaignRequest:
    """What a campaign is asked to do (JSON keys of the same names; `parse`).

    Attributes:
        objects: The floor's objects to calibrate and predict (default: all of them).
        experiments: K calibration E^P on the floor's physical units.
        runs: Replay runs per row and candidate, and runs per state of the prediction
            (4, as the floor's on-the-fly predictions: with 2 most of an object's states
            tie at 2 of 2 and the ranking says little).
        validation_runs: E^P (and E^V) per object's best and worst state.
        theta_step: θ grid of the prediction (the on-the-fly predictions' 30° default).
        seed: The twin's master seed (design, split, simulations).
        workers: Worker processes of the virtual experiments (at least 2: none of them
            runs in the Experiment Manager's own process).
        holdout: Share of the K rows held out to score the twin before and after.
        depths_mm: Candidate protrusion depths of the object calibration.
        tune_trials: TPE trials over μ and the gap after the objects (0: none).
        design: The calibration states: 'space-filling' (default: a Latin hypercube over
            face and θ per object, so that an object's few tries cover both faces and the
            circle) or 'random' (the study's).
        object_prior: What object calibration moves from: 'shipped' (default: each
            face's shipped feature, kept on a face no row tried) or 'plain' (the plain
            body, the study's; a face no row tried becomes plain), the rehearsal's
            `object_prior`.
        min_face_rows: Training rows a face needs before its depth is searched.
        sampling: How the prediction spends its `runs` a state: 'adaptive' (default, as
            the floor's on-the-fly predictions: where it can change an object's best and
            worst state, so that the states the twin ranks first are told apart) or
            'exhaustive' (every state alike; most of an object's states then tie).
    """

    objects: tuple[str, ...]
    experiments: int = 40
    runs: int = 4
    validation_runs: int = 4
    theta_step: int = 30
    seed: int = 0
    workers: int = 2
    holdout: float = 0.3
    depths_mm: tuple[float, ...] = (8.0, 16.0, 24.0, 32.0)
    tune_trials: int = 0
    design: str = "space-filling"
    object_prior: str = "shipped"
    min_face_rows: int = 1
    sampling: str = "adaptive"
    text: str = field(default="", compare=False)

    @classmethod
    def parse(cls, text: str, floor_objects: Sequence[str]) -> CampaignRequest:
        """Read and check a JSON request against the floor's objects.

        Raises:
            InputError: Not JSON, an unknown key, a bad value, an object not on the floor.
        """
        try:
            d = json.loads(text or "{}")
        except json.JSONDecodeError as exc:
            raise InputError(f"campaign: not JSON ({exc})") from None
        if not isinstance(d, dict):
            raise InputError("campaign: a JSON object is expected")
        unknown = sorted(set(d) - _KEYS)
        if unknown:
            raise InputError(f"campaign: unknown key(s) {', '.join(unknown)}; known: "
                             f"{', '.join(sorted(_KEYS))}")  # fmt: skip
        objects = d.get("objects") or list(floor_objects)
        if isinstance(objects, str):
            objects = [o.strip() for o in objects.split(",") if o.strip()]
        if not isinstance(objects, list) or not all(isinstance(o, str) for o in objects):
            raise InputError("campaign: 'objects' must be a list of the floor's object ids")
        missing = [o for o in objects if o not in set(floor_objects)]
        if missing or len(set(objects)) != len(objects):
            raise InputError(f"campaign: not objects of this floor (or named twice): "
                             f"{', '.join(missing) or ', '.join(objects)}")  # fmt: skip
        holdout = d.get("holdout", 0.3)
        if not isinstance(holdout, int | float) or isinstance(holdout, bool):
            raise InputError(f"campaign: 'holdout' must be a number, got {holdout!r}")
        depths = d.get("depths_mm", [8.0, 16.0, 24.0, 32.0])
        if not isinstance(depths, list) or not depths or \
                not all(isinstance(v, int | float) for v in depths):  # fmt: skip
            raise InputError("campaign: 'depths_mm' must be a list of depths in mm")
        req = cls(
            tuple(objects), _int(d, "experiments", 40, 3, 10_000), _int(d, "runs", 4, 1, 100),
            _int(d, "validation_runs", 4, 1, 1000), _int(d, "theta_step", 30, 1, 360),
            _int(d, "seed", 0, 0, 2**32 - 1), _int(d, "workers", 2, 2, 256), float(holdout),
            tuple(float(v) for v in depths), _int(d, "tune_trials", 0, 0, 1000),
            str(d.get("design", "space-filling")), str(d.get("object_prior", "shipped")),
            _int(d, "min_face_rows", 1, 1, 10_000), str(d.get("sampling", "adaptive")), text,
        )  # fmt: skip
        req.config()  # the rehearsal's own checks (θ step, hold-out split, depths)
        return req

    def as_dict(self) -> dict[str, Any]:
        return {"objects": list(self.objects), "experiments": self.experiments,
                "runs": self.runs, "validation_runs": self.validation_runs,
                "theta_step": self.theta_step, "seed": self.seed, "workers": self.workers,
                "holdout": self.holdout, "depths_mm": list(self.depths_mm),
                "tune_trials": self.tune_trials, "design": self.design,
                "object_prior": self.object_prior, "min_face_rows": self.min_face_rows,
                "sampling": self.sampling}  # fmt: skip

    @property
    def campaign_id(self) -> str:
        """12 hex digits of the request's canonical JSON: the same request, the same
        campaign (and folder), so that asking again resumes it."""
        canon = json.dumps(self.as_dict(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(canon.encode()).hexdigest()[:12]

    def config(self):  # -> RehearsalConfig
        """The rehearsal configuration (its plant fields unused: the floor is the plant)."""
        from transfertwin.rehearsal import RehearsalConfig

        return RehearsalConfig(
            plant_seed=0, objects=self.objects, calibration_experiments=self.experiments,
            runs=self.runs, validation_runs=self.validation_runs, theta_step=self.theta_step,
            holdout=self.holdout, depths_mm=self.depths_mm, tune_trials=self.tune_trials,
            seed=self.seed, workers=self.workers, design=self.design,
            object_prior=self.object_prior, min_face_rows=self.min_face_rows,
            fullstate_sampling=self.sampling,
        )  # fmt: skip


#: Runs one E^P on a unit: (unit id, object, face, conveyor, θ) → the plant's log row
#: (`PLANT_COLUMNS` and ``transfer_time_s``).
RunOne = Callable[[str, str, str, str, int], dict[str, Any]]


#: Each object's ranked states from a campaign's folder (`CampaignJob`'s `predict`).
Predict = Callable[[Path, Sequence[str], str], dict[str, list[dict[str, Any]]]]


class FloorPlant:
    """The floor's physical transfer units as a rehearsal's plant (`rehearse`'s `Plant`).

    Request i of a call runs on unit i mod U (the units in id order), each unit's requests
    one after another, the units side by side; a unit that cannot run E^P
    (`UnitUnavailableError`) is left out and what it had not run goes to the others. Each
    row is journaled as it returns, keyed by (call number, index): a resumed campaign makes
    the same calls (its design and its validation states follow from its seeds and the
    journaled rows) and gets the journaled rows back instead of running them again.
    """

    def __init__(self, run_one: RunOne, units: Sequence[str], journal: Path,
                 should_stop: Callable[[], bool] = lambda: False) -> None:  # fmt: skip
        if not units:
            raise InputError("the floor has no physical transfer unit to run E^P on "
                             "(start it with a plant: cps up --plant-seed N)")  # fmt: skip
        self._run_one = run_one
        self.units = tuple(sorted(units))
        self.journal = Path(journal)
        self._stop = should_stop
        self._calls = 0
        self._lock = threading.Lock()
        self._done: dict[str, dict[str, Any]] = {}
        if self.journal.exists():
            for line in self.journal.read_text().splitlines():
                try:
                    entry = json.loads(line)
                except json.JSONDecodeError:  # a line cut by a kill: run that one again
                    continue
                self._done[entry["key"]] = entry
        self.ran = 0  # E^P run by this object (not read back)
        self.left_out: dict[str, str] = {}  # units that cannot run E^P, and why

    @property
    def rows(self) -> list[dict[str, Any]]:
        """Every journaled E^P row."""
        with self._lock:
            return [e["row"] for e in self._done.values()]

    @property
    def floor_s(self) -> float:
        """The floor time of the journaled E^P: their cycle times by the plant's clock."""
        total = 0.0
        for row in self.rows:
            t = float(row.get("transfer_time_s", math.nan))
            total += t if math.isfinite(t) else 0.0
        return total

    def weigh(self, object_id: str):
        raise InputError("the floor's units have no scale (the mass counter-measure is off)")

    def run(self, requests, *, workers: int = 1, on_progress=None) -> list[dict[str, Any]]:
        """E^P of `requests` (`PlantRequest`), rows in request order (`PLANT_COLUMNS`)."""
        call, report = self._calls, on_progress or (lambda done, total: None)
        self._calls += 1
        rows: list[dict[str, Any] | None] = [None] * len(requests)
        for i, req in enumerate(requests):
            entry = self._done.get(f"{call}:{i}")
            if entry is not None:
                asked = entry["request"]
                if asked != [req.object_id, req.face, req.conveyor, int(req.theta_deg)]:
                    raise InputError(f"{self.journal}: experiment {call}:{i} was "
                                     f"{asked}, the campaign now asks {req}: the journal "
                                     "belongs to another campaign")  # fmt: skip
                rows[i] = entry["row"]
        done = [sum(r is not None for r in rows)]
        report(done[0], len(requests))

        def unit_worker(unit: str, queue: list[int]) -> None:
            for i in queue:
                if self._stop():
                    raise CampaignStoppedError
                req = requests[i]
                row = self._run_one(unit, req.object_id, req.face, req.conveyor,
                                    int(req.theta_deg))  # fmt: skip
                entry = {"key": f"{call}:{i}", "unit": unit,
                         "request": [req.object_id, req.face, req.conveyor,
                                     int(req.theta_deg)], "row": row}  # fmt: skip
                with self._lock:
                    with self.journal.open("a") as f:
                        f.write(json.dumps(entry) + "\n")
                        f.flush()
                    self._done[entry["key"]] = entry
                    self.ran += 1
                    rows[i] = row
                    done[0] += 1
                report(done[0], len(requests))

        while any(r is None for r in rows):
            units = self.units
            queues: dict[str, list[int]] = {u: [] for u in units}
            for i in (i for i, r in enumerate(rows) if r is None):
                queues[units[i % len(units)]].append(i)
            busy = [u for u in units if queues[u]]
            lost: list[UnitUnavailableError] = []
            with ThreadPoolExecutor(len(busy), thread_name_prefix="ep") as pool:
                for fut in [pool.submit(unit_worker, u, queues[u]) for u in busy]:
                    try:
                        fut.result()
                    except UnitUnavailableError as exc:
                        lost.append(exc)
            for exc in lost:
                self.units = tuple(u for u in self.units if u != exc.unit)
                self.left_out[exc.unit] = str(exc)
            if not self.units:
                raise InputError("no physical unit of the floor can run E^P: "
                                 + "; ".join(self.left_out.values()))  # fmt: skip
        return [r for r in rows if r is not None]


class CampaignJob:
    """One campaign into its folder; `run` blocks (call it in a thread), `stop` asks it to
    end after the E^P in flight, `status` is safe from any thread.

    Args:
        request: What to run.
        folder: The campaign's folder (created).
        run_one: One E^P on a physical unit (`RunOne`).
        units: The floor's physical transfer units (a `FloorPlant` over them journals
            into `folder`).
        predict: (folder, objects, campaign id) → each object's ranked states from the
            campaign's ``fullstate.csv`` (``predictions.json``).
        on_update: Called with `status()` after every change (in the job's thread).
    """

    def __init__(self, request: CampaignRequest, folder: Path, run_one: RunOne,
                 units: Sequence[str], predict: Predict,
                 on_update: Callable[[dict[str, Any]], None] | None = None) -> None:  # fmt: skip
        self.request = request
        self._predict = predict
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self._stop = threading.Event()
        self._ended = threading.Event()
        self._lock = threading.Lock()
        self._on_update = on_update or (lambda status: None)
        self.plant = FloorPlant(run_one, units, self.folder / JOURNAL, self._stop.is_set)
        self._t0 = time.monotonic()
        self._status: dict[str, Any] = {
            "state": "starting", "campaign": request.campaign_id, "folder": str(self.folder),
            "stage": "", "done": 0, "total": 0, "plant_experiments": len(self.plant.rows),
            "floor_s": round(self.plant.floor_s, 1), "units": list(self.plant.units),
            "units_left_out": {},
            "objects": list(request.objects), "experiments": request.experiments,
            "elapsed_s": 0.0, "error": None, "summary": None,
        }  # fmt: skip

    def status(self) -> dict[str, Any]:
        with self._lock:
            return dict(self._status)

    def _update(self, **changes: Any) -> None:
        with self._lock:
            self._status.update(changes, elapsed_s=round(time.monotonic() - self._t0, 1),
                                units=list(self.plant.units),
                                units_left_out=dict(self.plant.left_out),
                                plant_experiments=len(self.plant.rows),
                                floor_s=round(self.plant.floor_s, 1))  # fmt: skip
            status = dict(self._status)
        write_atomic(self.folder / STATUS, json.dumps(status, indent=2) + "\n")
        self._on_update(status)

    def stop(self) -> None:
        """End after the E^P in flight (journaled: a later start resumes)."""
        self._stop.set()
        if self.status()["state"] in ("starting", "running"):
            self._update(state="stopping")

    def wait(self, timeout_s: float) -> bool:
        return self._ended.wait(timeout_s)

    def run(self) -> dict[str, Any]:
        """Run the campaign; the final status (finished, stopped or failed)."""
        from transfertwin.rehearsal import rehearse

        def stage(name: str) -> None:
            if self._stop.is_set():
                raise CampaignStoppedError
            self._update(state="running", stage=name, done=0, total=0)

        def progress(done: int, total: int) -> None:
            if self._stop.is_set():
                raise CampaignStoppedError
            self._update(done=done, total=total)

        try:
            self._update(state="running", stage="starting")
            doc = rehearse(self.request.config(), self.folder, on_stage=stage,
                           on_progress=progress, plant=self.plant,
                           measures=CAMPAIGN_MEASURES, leg="operation")  # fmt: skip
            preds = self._predict(self.folder, self.request.objects, self.request.campaign_id)
            write_atomic(self.folder / PREDICTIONS, json.dumps(
                {"campaign": self.request.campaign_id, "leg": "operation",
                 "predictions": preds}, indent=1) + "\n")  # fmt: skip
            self._update(state="finished", stage="done", summary=_summary(doc))
        except CampaignStoppedError:
            self._update(state="stopped")
        except Exception as exc:  # reported in the status; the job's thread ends
            self._update(state="failed", error=f"{type(exc).__name__}: {exc}")
        finally:
            self._ended.set()
        return self.status()


def _summary(doc: Mapping[str, Any]) -> dict[str, Any]:
    """What the status shows of a finished campaign (``rehearsal.json`` has the rest)."""
    objects = doc.get("objects") or {}
    return {
        "f05_before": doc.get("f05_before"), "f05_after": doc.get("f05_after"),
        "f05_delta_ci": doc.get("f05_delta_ci"),
        "significant_best": doc.get("significant_best"),
        "significant_worst": doc.get("significant_worst"),
        "held_out": doc.get("held_out"), "virtual_experiments": doc.get("virtual_experiments"),
        "best": {o: {k: e["best"][k] for k in ("face", "conveyor", "theta_deg", "p_v",
                                                "p_p", "diff_low", "diff_high")}
                 for o, e in objects.items() if "best" in e},
    }  # fmt: skip
