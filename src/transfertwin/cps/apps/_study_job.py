"""A study the Experiment Manager runs on request (Sec. 6.6).

A request is a JSON plan: the objects, the pre-transfer states (listed, or every state on a
θ step), the runs per state, the seed, the docking-error model and where the experiments
run (local worker processes or Ray). `StudyJob` runs it with the study runner
(`run_study`) into a SQLite result store, in a thread of the Experiment Manager's process;
it reports progress and an ETA after every stored batch and stops between batches when
asked. The runner skips what the store holds, so a stopped study, or one whose process
died, resumes where it was by running the same request again.
"""

from __future__ import annotations

import json
import math
import os
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from transfertwin._atomic import write_atomic
from transfertwin._errors import InputError

__all__ = [
    "STUDY_INDEX",
    "StudyJob",
    "StudyRequest",
    "record_store",
    "study_opcua_values",
    "study_stores",
]

#: The file in the Experiment Manager's state folder that lists the stores of its studies
#: (the console reads it to show them).
STUDY_INDEX = "study-stores.json"

_KEYS = {"objects", "states", "theta_step", "runs", "seed", "docking", "profile",
         "executor", "workers", "address", "chunk_size", "store", "leg"}  # fmt: skip
_EXECUTORS = ("local", "ray")


def _int(d: dict[str, Any], key: str, default: int | None, low: int) -> int:
    value = d.get(key, default)
    if value is None:
        raise InputError(f"plan: '{key}' is missing")
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise InputError(f"plan: '{key}' must be an integer >= {low}, got {value!r}")
    return value


def _objects(value: object) -> tuple[str, ...]:
    from transfertwin.study.experiment import parse_objects

    if isinstance(value, str):
        return parse_objects(value)
    if isinstance(value, list) and value and all(isinstance(v, str) for v in value):
        return parse_objects(",".join(value))
    raise InputError("plan: 'objects' must be a list of object ids (o1..o37) or mesh paths")


def _states(value: object) -> tuple[tuple[str, str, int], ...]:
    if not isinstance(value, list) or not value:
        raise InputError("plan: 'states' must be a non-empty list")
    out = []
    for item in value:
        if isinstance(item, dict) and set(item) == {"face", "conveyor", "theta_deg"}:
            item = [item["face"], item["conveyor"], item["theta_deg"]]
        ok = isinstance(item, list) and len(item) == 3 and isinstance(item[2], int)
        if not ok or not all(isinstance(v, str) for v in item[:2]):
            raise InputError("plan: each state is [face, conveyor, theta_deg] or "
                             f"{{face, conveyor, theta_deg}}, got {item!r}")
        out.append((item[0], item[1], item[2]))
    return tuple(out)


def _docking(value: object):  # -> DockingErrorModel
    from transfertwin.sim import DockingError
    from transfertwin.study.docking import FixedDockingError, docking_model

    if isinstance(value, dict) and set(value) == {"fixed"}:
        fixed = value["fixed"]
        if not (isinstance(fixed, list) and len(fixed) == 3
                and all(isinstance(v, int | float) for v in fixed)):  # fmt: skip
            raise InputError("plan: docking {\"fixed\": [x_mm, y_mm, theta_deg]}")
        return FixedDockingError(DockingError.from_mm_deg(*map(float, fixed)))
    if not isinstance(value, str):
        raise InputError("plan: 'docking' is copula, copula-per-station, resample, a model "
                         "JSON path or {\"fixed\": [x_mm, y_mm, theta_deg]}")  # fmt: skip
    return docking_model(value)


@dataclass(frozen=True)
class StudyRequest:
    """A study as the Experiment Manager is asked to run it.

    Attributes:
        plan: The study plan (its hash identifies the study in the store).
        executor: ``local`` (worker processes of the Experiment Manager) or ``ray``.
        workers: Local worker processes (1: in the Experiment Manager's process), or the
            CPUs of a local Ray.
        address: With Ray: ``auto`` or ``HOST:PORT`` of a cluster; None starts a local Ray.
        chunk_size: With Ray: experiments per task.
        store: The result store named in the request, or None (the manager's default).
        text: The request as given (kept to resume the study after a restart).
    """

    plan: Any  # StudyPlan
    executor: str = "local"
    workers: int = 1
    address: str | None = None
    chunk_size: int = 8
    store: Path | None = None
    text: str = field(default="", compare=False)

    @classmethod
    def parse(cls, text: str) -> StudyRequest:
        """Read and check a JSON plan (every mesh loads; the docking model is built).

        Raises:
            InputError: Not JSON, an unknown key, a bad value, an unknown object or state.
        """
        from transfertwin.study.experiment import StudyPlan, check_plan, load_profile

        try:
            d = json.loads(text)
        except json.JSONDecodeError as exc:
            raise InputError(f"plan: not JSON ({exc})") from None
        if not isinstance(d, dict):
            raise InputError("plan: a JSON object is expected")
        unknown = sorted(set(d) - _KEYS)
        if unknown:
            raise InputError(f"plan: unknown key(s) {', '.join(unknown)}; "
                             f"known: {', '.join(sorted(_KEYS))}")  # fmt: skip
        if "objects" not in d:
            raise InputError("plan: 'objects' is missing")
        if "states" in d and "theta_step" in d:
            raise InputError("plan: give 'states' or 'theta_step', not both")
        executor = d.get("executor", "local")
        if executor not in _EXECUTORS:
            raise InputError(f"plan: 'executor' must be local or ray, got {executor!r}")
        address = d.get("address")
        if address is not None and (executor != "ray" or not isinstance(address, str)):
            raise InputError("plan: 'address' (auto or HOST:PORT) needs executor ray")
        kwargs: dict[str, Any] = {}
        if d.get("profile") is not None:
            name, scene = load_profile(str(d["profile"]))
            kwargs = {"profile_name": name, "scene": scene}
        only = _states(d["states"]) if "states" in d else ()
        plan = StudyPlan(
            objects=_objects(d["objects"]),
            theta_step=1 if only else _int(d, "theta_step", 30, 1),
            runs=_int(d, "runs", None, 1), seed=_int(d, "seed", 0, 0),
            docking=_docking(d.get("docking", "copula")), only_states=only,
            leg=str(d.get("leg", "round-trip")), **kwargs,
        )  # fmt: skip
        check_plan(plan)
        store = d.get("store")
        if store is not None and not isinstance(store, str):
            raise InputError("plan: 'store' must be a path")
        return cls(plan, executor, _int(d, "workers", 1, 1), address,
                   _int(d, "chunk_size", 8, 1), Path(store) if store else None,
                   text)  # fmt: skip

    def executor_object(self):  # -> RayExecutor | None
        """The executor to start (None: local worker processes)."""
        if self.executor == "local":
            return None
        from transfertwin.study.experiment import RayExecutor

        return RayExecutor(self.address, workers=self.workers, chunk_size=self.chunk_size)


class _StopRequestedError(Exception):
    """Raised from the runner's progress callback to stop between batches."""


class StudyJob:
    """One study run into one store; `run` blocks (call it in a thread), `stop` asks it to
    end after the batch in flight, `status` is safe from any thread.

    The experiments run in a process of their own (spawned; with ``workers`` > 1 or Ray it
    hands them on): the manager's process keeps answering at full speed, and its own
    single experiments (``RunExperiment``) never share a compiled simulation with the
    study's (the per-process cache of `system_for` is not for two threads). That process
    ends when the manager's does, also on SIGKILL.

    Args:
        request: What to run.
        store: The SQLite result store.
        on_update: Called (in the job's thread) with `status()` after every change.
        own_process: False runs the experiments in the calling thread (for a caller that
            runs no simulation of its own; saves the process start).
    """

    def __init__(self, request: StudyRequest, store: Path,
                 on_update: Callable[[dict[str, Any]], None] | None = None,
                 own_process: bool = True) -> None:  # fmt: skip
        self.request = request
        self.own_process = own_process
        self.store = Path(store)
        self._on_update = on_update or (lambda status: None)
        self._stop = threading.Event()
        self._stop_child: Any = None  # the multiprocessing Event of the running process
        self._ended = threading.Event()
        self._lock = threading.Lock()
        plan = request.plan
        self._status: dict[str, Any] = {
            "state": "starting", "plan": plan.plan_hash[:12], "store": str(self.store),
            "planned": plan.n_experiments, "done": 0, "ran": 0, "fraction": 0.0,
            "rate_per_s": None, "eta_s": None, "error": None,
            "objects": list(plan.objects), "states": len(plan.states()),
            "runs": plan.runs, "executor": request.executor,
        }  # fmt: skip

    def status(self) -> dict[str, Any]:
        with self._lock:
            return dict(self._status)

    def _update(self, **changes: Any) -> None:
        with self._lock:
            self._status.update(changes)
            status = dict(self._status)
        self._on_update(status)

    def check_store(self) -> None:
        """Open (create) the store and record the plan: a store of another plan is refused
        before anything runs."""
        from transfertwin.store import SQLiteResultStore

        plan = self.request.plan
        self.store.parent.mkdir(parents=True, exist_ok=True)
        with SQLiteResultStore(self.store) as store:
            store.init_plan(plan.plan_hash, plan.to_json())
            self._update(done=store.count(), fraction=store.count() / plan.n_experiments)

    def stop(self) -> None:
        """End after the batch in flight (its results are stored)."""
        self._stop.set()
        child = self._stop_child
        if child is not None:
            child.set()
        if self.status()["state"] in ("starting", "running"):
            self._update(state="stopping")

    def wait(self, timeout_s: float) -> bool:
        """Block until `run` has returned (True) or `timeout_s` passed (False)."""
        return self._ended.wait(timeout_s)

    def run(self) -> dict[str, Any]:
        """Run what the store does not hold yet in a process of its own; the final status
        (state finished, stopped or failed with the error)."""
        import multiprocessing as mp
        import queue as queues

        try:
            if not self.own_process:
                self._update(**_run(self.request, self.store, self._stop.is_set,
                                    lambda changes: self._update(**changes)))  # fmt: skip
                return self.status()
            ctx = mp.get_context("spawn")
            updates, stop = ctx.Queue(), ctx.Event()
            self._stop_child = stop
            if self._stop.is_set():
                stop.set()
            proc = ctx.Process(target=_study_process, name="transfertwin-study",
                               args=(self.request.text, str(self.store), stop, updates,
                                     os.getpid()))  # fmt: skip
            proc.start()
            ended = False
            while not ended:
                try:
                    changes = updates.get(timeout=0.2)
                except queues.Empty:
                    if proc.is_alive():
                        continue
                    try:  # what it said last, if anything
                        changes = updates.get(timeout=1.0)
                    except queues.Empty:
                        proc.join()
                        self._update(state="failed", eta_s=None,
                                     error=f"the study's process ended with code "
                                           f"{proc.exitcode}")  # fmt: skip
                        break
                ended = changes.get("state") in ("finished", "stopped", "failed")
                self._update(**changes)
            proc.join(10.0)
            return self.status()
        finally:
            self._ended.set()


def _exit_with_parent(parent_pid: int) -> None:
    """End this process once the manager's is gone (killed with -9: no clean-up ran)."""

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


def _study_process(text: str, store: str, stop, updates, parent_pid: int) -> None:
    """The study's process: read the request again (a fitted docking model does not
    pickle; the store refuses a plan whose hash came out otherwise), run it, put status
    changes on `updates` (the last one with the end state)."""
    _exit_with_parent(parent_pid)
    try:
        request = StudyRequest.parse(text)
    except Exception as exc:
        updates.put({"state": "failed", "eta_s": None, "error": f"plan: {exc}"})
        return
    updates.put(_run(request, Path(store), stop.is_set, updates.put))


def _run(request: StudyRequest, path: Path, should_stop: Callable[[], bool],
         report: Callable[[dict[str, Any]], None]) -> dict[str, Any]:  # fmt: skip
    """Run the study into the store at `path`; `report` gets every change, the return
    value is the last one (state finished, stopped or failed)."""
    from transfertwin.store import SQLiteResultStore
    from transfertwin.study.experiment import run_study

    plan = request.plan
    t0 = time.monotonic()
    try:
        with SQLiteResultStore(path) as store:
            before = store.count()
            if should_stop():
                raise _StopRequestedError
            report({"state": "running", "done": before, "ran": 0,
                    "fraction": before / plan.n_experiments})  # fmt: skip

            def on_progress(ran: int, todo: int) -> None:
                elapsed = time.monotonic() - t0
                rate = ran / elapsed if ran and elapsed > 0 else None
                left = todo - ran
                eta = left / rate if rate else (0.0 if left == 0 else None)
                done = before + ran
                report({"done": done, "ran": ran, "fraction": done / plan.n_experiments,
                        "rate_per_s": rate, "eta_s": eta})  # fmt: skip
                if should_stop() and left > 0:
                    raise _StopRequestedError

            executor = request.executor_object()
            if executor is None:
                run_study(plan, store, workers=request.workers, on_progress=on_progress)
            else:
                with executor:
                    run_study(plan, store, on_progress=on_progress, executor=executor)
            done = store.count()
        finished = done >= plan.n_experiments
        return {"state": "finished" if finished else "stopped", "done": done,
                "eta_s": 0.0 if finished else None}  # fmt: skip
    except _StopRequestedError:
        return {"state": "stopped", "eta_s": None}
    except Exception as exc:  # the study fails; the manager keeps serving
        text = str(exc).strip().splitlines()
        return {"state": "failed", "eta_s": None,
                "error": f"{type(exc).__name__}: {text[0] if text else ''}"}  # fmt: skip


def study_opcua_values(status: dict[str, Any]) -> dict[str, object]:
    """A job's status as the Experiment Manager's OperationalData properties."""
    eta = status.get("eta_s")
    rate = status.get("rate_per_s")
    return {
        "StudyState": status["state"], "StudyPlan": status["plan"],
        "StudyStore": status["store"], "StudyDone": int(status["done"]),
        "StudyPlanned": int(status["planned"]), "StudyProgress": float(status["fraction"]),
        "StudyRate": float(rate) if rate is not None else 0.0,
        "StudyEtaS": float(eta) if eta is not None and math.isfinite(eta) else -1.0,
    }  # fmt: skip


def record_store(state_dir: Path, store: Path) -> None:
    """Add `store` to the Experiment Manager's list of study stores (`STUDY_INDEX`)."""
    index = state_dir / STUDY_INDEX
    stores = json.loads(index.read_text())["stores"] if index.is_file() else []
    if str(store) not in stores:
        state_dir.mkdir(parents=True, exist_ok=True)
        write_atomic(index, json.dumps({"stores": [*stores, str(store)]}, indent=1) + "\n")


def study_stores(workdir: Path) -> list[Path]:
    """The study stores of a process floor's Experiment Manager(s) that exist, in the
    order the studies were started."""
    out: list[Path] = []
    for index in sorted(Path(workdir).glob(f"assets/*/state/{STUDY_INDEX}")):
        try:
            stores = json.loads(index.read_text())["stores"]
        except (OSError, ValueError, KeyError):
            continue
        out += [Path(s) for s in stores if Path(s).is_file() and Path(s) not in out]
    return out
