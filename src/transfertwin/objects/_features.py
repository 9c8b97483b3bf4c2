"""Resting features of the built-in cores: what hangs below a face and catches in the gap.

A real starter-motor core rests on flange ears, bolt heads and terminal studs; the procedural
bodies of ``o1``..``o37`` keep everything inside the can's radius. The built-in cores therefore
carry, per face, one `Protrusion` (see `transfertwin.objects.Protrusion`) read from
``data/cores/features.json``:

- the four cores with real experiments (o1, o18, o23, o32) carry the depths that
  ``transfertwin calibrate object`` inferred from their real outcomes (proxies, not scans);
- every other core draws its two faces' features from the *family prior*: the calibrated
  faces resampled with a generator seeded from the core index (`prior_features`).

``scripts/make_core_features.py`` writes the file. The plain body without features is
``load_builtin(id, features=False)``; a calibrated proxy whose base is a built-in id replaces
the features rather than adding to them.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from transfertwin.objects._proxy import Protrusion

if TYPE_CHECKING:
    from importlib.resources.abc import Traversable

__all__ = ["FACES", "FEATURES_NAME", "features_document", "prior_features", "read_features"]

#: File name of the features table in the cores' package data.
FEATURES_NAME = "features.json"

#: The two faces an object can rest on.
FACES = ("front", "back")

_PRIOR_SEED = 20_260_000


def prior_features(
    index: int, calibrated: Mapping[str, Sequence[Protrusion]]
) -> tuple[Protrusion, ...]:
    """The family prior for core ``index``: each face's feature drawn from the calibrated ones.

    Args:
        index: Core index 1..37 (seeds the generator, so a core always gets the same draw).
        calibrated: Calibrated cores' features by object id.

    Returns:
        One protrusion per face, each a copy of a randomly chosen calibrated core's
        feature on the same face.
    """
    if not calibrated:
        raise ValueError("the family prior needs at least one calibrated core")
    rng = np.random.default_rng([_PRIOR_SEED, index])
    out = []
    for face in FACES:
        pool = [p for prots in calibrated.values() for p in prots if p.face == face]
        if not pool:
            pool = [Protrusion(face, 0.0)]
        out.append(pool[int(rng.integers(len(pool)))])
    return tuple(out)


def features_document(
    calibrated: Mapping[str, Sequence[Protrusion]], ids: Sequence[str], *, note: str
) -> dict[str, object]:
    """The JSON document of ``features.json`` for the cores ``ids``."""
    cores: dict[str, object] = {}
    source: dict[str, str] = {}
    for object_id in ids:
        if object_id in calibrated:
            prots = tuple(calibrated[object_id])
            source[object_id] = "calibrated"
        else:
            prots = prior_features(int(object_id[1:]), calibrated)
            source[object_id] = "prior"
        cores[object_id] = [dataclasses.asdict(p) for p in prots]
    return {"note": note, "source": source, "cores": cores}


def read_features(directory: Traversable) -> dict[str, tuple[Protrusion, ...]]:
    """The features table in ``directory`` by object id (empty if the file is absent).

    Raises:
        ValueError: If the file exists but is malformed.
    """
    path = directory.joinpath(FEATURES_NAME)
    if not path.is_file():
        return {}
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        return {key: tuple(Protrusion(**p) for p in prots) for key, prots in doc["cores"].items()}
    except (ValueError, KeyError, TypeError) as exc:
        raise ValueError(f"malformed {FEATURES_NAME} ({exc})") from exc
