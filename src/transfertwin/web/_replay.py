"""The console's replays: which experiment a `/replay?...` page shows, computed on demand.

`ReplayService.payload(params)` answers `/api/replay?...` with the JSON document of
`transfertwin.replay.replay_payload`. The query names the experiment:

- ``study=NAME&object=o1&face=front&conveyor=both&theta=90&run=3``: a row of a study the
  console shows (rebuilt from the store's plan; the document says whether the replay has
  the stored row's bits);
- ``object=o1&face=..&conveyor=..&theta=..[&seed=0][&dock_error=X,Y,T][&gap_mm=..][&mu=..]``:
  a `transfer` with a built-in core (a mesh path is not taken from a URL);
- ``calibration=NAME&row=I&run=R``: real row I of a `calibrate run` folder the console
  shows, as its run R replayed it (the document says whether the outcome agrees with the
  run's prediction);
- ``key=K``: a replay the `transfertwin replay` command computed before serving.

Replays are computed one at a time in fresh systems and the last few are kept.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from transfertwin._errors import InputError
from transfertwin.objects import is_builtin_id
from transfertwin.replay import (
    calibration_source,
    calibration_spec,
    compare_with_row,
    record_experiment,
    replay_payload,
    study_spec,
    transfer_spec,
)

__all__ = ["CACHED_REPLAYS", "ReplayService", "replay_query"]

#: How many computed replays the console keeps.
CACHED_REPLAYS = 8
_STUDY_KEYS = ("object", "face", "conveyor", "theta", "run")


def _int(params: Mapping[str, str], name: str, default: int | None = None) -> int:
    text = params.get(name)
    if text is None or text == "":
        if default is None:
            raise InputError(f"the replay needs {name}=...")
        return default
    try:
        return int(text)
    except ValueError:
        raise InputError(f"{name} must be an integer, got {text[:40]!r}") from None


def _float(params: Mapping[str, str], name: str) -> float | None:
    text = params.get(name)
    if text is None or text == "":
        return None
    try:
        return float(text)
    except ValueError:
        raise InputError(f"{name} must be a number, got {text[:40]!r}") from None


def replay_query(study: str, row: Mapping[str, object]) -> str:
    """The `/replay` query string of a study's result row (the console's links)."""
    from urllib.parse import urlencode

    return urlencode({"study": study, "object": row["object_id"], "face": row["face"],
                      "conveyor": row["conveyor"], "theta": row["theta_deg"],
                      "run": row["run"]})  # fmt: skip


class ReplayService:
    """Replays for the console (see the module doc).

    Args:
        studies: Study store file name → path (the console's ``--db``).
        preload: Replay documents by key (`transfertwin replay` serves its own this way).
        calibrations: Calibration folder name → path (the console's ``--calibration``).
    """

    def __init__(
        self,
        studies: Mapping[str, Path],
        preload: Mapping[str, dict[str, Any]] | None = None,
        calibrations: Mapping[str, Path] | None = None,
    ) -> None:
        self._studies = dict(studies)
        self._calibrations = dict(calibrations or {})
        self._preload = dict(preload or {})
        self._cache: OrderedDict[tuple, dict[str, Any]] = OrderedDict()
        self._lock = threading.Lock()

    def payload(self, params: Mapping[str, str]) -> dict[str, Any]:
        """The replay document `params` name (blocking: seconds for a long experiment)."""
        params = {k: v for k, v in params.items() if k != "token"}
        if "key" in params:
            if params["key"] not in self._preload:
                raise LookupError(f"no replay {params['key'][:40]!r}")
            return self._preload[params["key"]]
        key = tuple(sorted(params.items()))
        with self._lock:
            if key in self._cache:
                self._cache.move_to_end(key)
                return self._cache[key]
            doc = self._compute(params)
            self._cache[key] = doc
            while len(self._cache) > CACHED_REPLAYS:
                self._cache.popitem(last=False)
            return doc

    def _compute(self, params: Mapping[str, str]) -> dict[str, Any]:
        if "calibration" in params:
            name = params["calibration"]
            if name not in self._calibrations:
                raise LookupError(f"no calibration {name[:80]!r}; calibrations: "
                                  f"{', '.join(self._calibrations) or 'none'}")  # fmt: skip
            found = calibration_spec(self._calibrations[name], _int(params, "row"),
                                     _int(params, "run", 0))  # fmt: skip
            replay = record_experiment(found.spec)
            source = calibration_source(name, _int(params, "row"), found, replay.result)
            return replay_payload(replay, source=source)
        for name in ("face", "conveyor"):
            if not params.get(name):
                raise InputError(f"the replay needs {name}=...")
        if "study" in params:
            name = params["study"]
            if name not in self._studies:
                raise LookupError(f"no study {name[:80]!r}; studies: {', '.join(self._studies)}")
            if not params.get("object"):
                raise InputError("the replay needs object=...")
            found = study_spec(self._studies[name], params["object"], params["face"],
                               params["conveyor"], _int(params, "theta"),
                               _int(params, "run"))  # fmt: skip
            replay = record_experiment(found.spec)
            check = compare_with_row(replay.result, found.row) if found.row else None
            source = {"kind": "study", "study": name, "stored": found.row is not None,
                      "check": check, "runs": found.runs}  # fmt: skip
            return replay_payload(replay, source=source)
        ref = params.get("object", "")
        if not is_builtin_id(ref):
            raise InputError(f"object must be a built-in core id (o1..o37), got {ref[:40]!r}")
        spec = transfer_spec(
            ref, params["face"], params["conveyor"], _int(params, "theta"),
            seed=_int(params, "seed", 0), dock_error=params.get("dock_error") or "0,0,0",
            gap_mm=_float(params, "gap_mm"), mu=_float(params, "mu"),
        )  # fmt: skip
        return replay_payload(record_experiment(spec), source={"kind": "transfer"})
