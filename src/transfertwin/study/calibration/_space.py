"""The search space of `calibrate tune`: scene settings and proxy depths, searched jointly.

A space is written as ``NAME=LO:HI[:log],...``, e.g.::

    mu=0.3:0.8,gap_mm=8:16,layout.pulley_radius_m=0.010:0.025,physics.solref[0]=0.002:0.02:log,
    object.o1.front_depth_mm=0:30,object.o1.com_shift_mm=-20:20

Names:

- any numeric `SceneConfig` setting by the dotted name a profile uses (``mu``, ``gap_m``,
  ``t_max_s``, ``physics.impratio``, ``layout.pulley_radius_m``, ``placement.sigma_xy_m``...);
  ``gap_mm`` is accepted for ``gap_m`` in millimetres; one element of a tuple setting by its
  index, ``physics.solref[0]``. Integer settings are searched over integers.
- ``object.<id>.<face>_depth_mm``: the depth (mm, 0..100) of a protrusion below face 'front'
  or 'back' of the real object ``<id>`` (a `transfertwin.objects.Protrusion`; 0 is the family
  prior, the base object without protrusion). All depths of one object form one proxy of its
  base object (the object map's reference, by default the built-in core of the same id).
- ``object.<id>.com_shift_mm``: the shift (mm, -50..50) of that proxy's centre of mass along
  the object's x axis (`transfertwin.objects.ProxySpec.com_shift_m`, a two-density body of
  the same mass; 0 is the family prior, uniform density).

``:log`` samples log-uniformly (LO > 0). Everything is checked up front: an unknown name,
``LO >= HI``, a value the scene refuses at either end (integers: at every value) is an
`InputError`. Dimensions are kept sorted by name, so the order of the entries does not
matter.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from pathlib import Path

from transfertwin._errors import InputError
from transfertwin.objects import (
    MAX_COM_SHIFT_M,
    Protrusion,
    ProxySpec,
    builtin_features,
    builtin_ids,
)
from transfertwin.sim import SceneConfig

__all__ = [
    "Dimension",
    "SearchSpace",
    "default_space",
    "parse_space",
    "scene_with",
    "trial_proxies",
]

_SECTIONS = ("physics", "layout", "placement")
_OBJECT = re.compile(r"^object\.([A-Za-z0-9_\-]+)\.(front|back)_depth_mm$")
_SHIFT = re.compile(r"^object\.([A-Za-z0-9_\-]+)\.com_shift_mm$")
_INDEX = re.compile(r"^(.+)\[(\d+)\]$")
_MAX_DEPTH_MM = 100.0


@dataclass(frozen=True)
class Dimension:
    """One searched parameter: its name as written in a space, bounds and scale."""

    name: str
    low: float
    high: float
    log: bool = False
    integer: bool = False

    @property
    def object_face(self) -> tuple[str, str] | None:
        """(object id, face) of a proxy depth, None for a scene setting."""
        m = _OBJECT.match(self.name)
        return (m.group(1), m.group(2)) if m else None

    @property
    def shifted_object(self) -> str | None:
        """The object id of a proxy's centre-of-mass shift, None otherwise."""
        m = _SHIFT.match(self.name)
        return m.group(1) if m else None

    def text(self) -> str:
        """``name=lo:hi[:log]`` (canonical: repr of the bounds)."""
        lo, hi = (int(self.low), int(self.high)) if self.integer else (self.low, self.high)
        return f"{self.name}={lo!r}:{hi!r}" + (":log" if self.log else "")

    def value(self, x: float) -> float | int:
        """`x` as used in a trial: an int, or a float rounded to 6 significant digits."""
        return round(x) if self.integer else float(f"{float(x):.6g}")


@dataclass(frozen=True)
class SearchSpace:
    """The dimensions of a joint search, sorted by name."""

    dims: tuple[Dimension, ...]

    def text(self) -> str:
        """Canonical text of the space (parses back to the same space)."""
        return ",".join(d.text() for d in self.dims)

    def names(self) -> list[str]:
        return [d.name for d in self.dims]

    def object_dims(self) -> list[Dimension]:
        """Proxy depth dimensions."""
        return [d for d in self.dims if d.object_face is not None]

    def shift_dims(self) -> list[Dimension]:
        """Proxy centre-of-mass shift dimensions."""
        return [d for d in self.dims if d.shifted_object is not None]

    def object_ids(self) -> list[str]:
        """Real object ids with a tuned proxy, sorted."""
        ids = {d.object_face[0] for d in self.object_dims()}
        return sorted(ids | {d.shifted_object for d in self.shift_dims()})

    def depth_penalty(
        self, params: Mapping[str, object], rows: Sequence[Mapping[str, object]]
    ) -> float:
        """Regularisation towards the family prior (no protrusion): for every proxy depth,
        its depth as a fraction of its upper bound, weighted by the share of `rows` on that
        object and face, summed. Multiply by the penalty weight (the weight is then the
        objective's cost of the deepest protrusion on every row). A centre-of-mass shift
        adds its size as a fraction of its largest bound, weighted by the object's share."""
        n = len(rows)
        total = 0.0
        for d in self.object_dims():
            oid, face = d.object_face
            share = sum(str(r["object_id"]) == oid and str(r["face"]) == face for r in rows) / n
            total += share * float(params[d.name]) / d.high
        for d in self.shift_dims():
            share = sum(str(r["object_id"]) == d.shifted_object for r in rows) / n
            total += share * abs(float(params[d.name])) / max(abs(d.low), abs(d.high))
        return total


def _field_kind(section: object, name: str) -> str | None:
    """'int', 'float', 'tuple' or None (not numeric) for a field of a config dataclass."""
    for f in fields(section):
        if f.name == name:
            kind = str(f.type).replace(" ", "")
            if kind.startswith("tuple["):
                return "tuple"
            if kind in ("int", "int|None"):
                return "int"
            if kind in ("float", "float|None"):
                return "float"
            return None
    raise KeyError(name)


def _scene_kind(name: str, base: SceneConfig) -> str:
    """'int' or 'float' for a dotted scene name (with an optional tuple index)."""
    index = None
    m = _INDEX.match(name)
    key = name
    if m:
        key, index = m.group(1), int(m.group(2))
    if key == "gap_mm":
        key = "gap_m"
    head, _, tail = key.partition(".")
    owner: object = base
    if tail:
        if head not in _SECTIONS or "." in tail:
            sections = ", ".join(_SECTIONS)
            raise InputError(f"--space: unknown setting {name!r} (sections: {sections})")
        owner, key = getattr(base, head), tail
    try:
        kind = _field_kind(owner, key)
    except KeyError:
        raise InputError(f"--space: unknown setting {name!r}") from None
    if kind == "tuple":
        size = len(getattr(owner, key))
        if index is None:
            raise InputError(f"--space: {name} is a tuple; name one element, e.g. {name}[0]")
        if index >= size:
            raise InputError(f"--space: {name} has {size} elements (index 0..{size - 1})")
        return "float"
    if index is not None or kind is None:
        raise InputError(f"--space: {name!r} is not a numeric setting")
    return kind


def scene_with(base: SceneConfig, params: Mapping[str, object]) -> SceneConfig:
    """`base` with the scene settings of `params` (dotted names, ``gap_mm`` in mm, tuple
    elements as ``name[i]``); proxy depths (``object.*``) are ignored here."""
    changes: dict[str, object] = {}
    elements: dict[str, dict[int, object]] = {}
    for key, value in params.items():
        if _OBJECT.match(key) or _SHIFT.match(key):
            continue
        m = _INDEX.match(key)
        if m:
            elements.setdefault(m.group(1), {})[int(m.group(2))] = value
        elif key == "gap_mm":
            changes["gap_m"] = float(value) / 1000.0
        else:
            changes[key] = value
    for key, items in elements.items():
        head, _, tail = key.partition(".")
        current = list(getattr(getattr(base, head), tail) if tail else getattr(base, head))
        for i, value in items.items():
            current[i] = value
        changes[key] = tuple(current)
    return base.with_overrides(**changes)


def _check_scene_values(dim: Dimension, base: SceneConfig) -> None:
    if dim.integer and dim.high - dim.low <= 64:
        values = range(int(dim.low), int(dim.high) + 1)
    else:
        values = (dim.low, dim.high)
    for v in values:
        try:
            scene_with(base, {dim.name: v})
        except InputError as exc:
            raise InputError(f"--space: {dim.name}={v:g} is refused: {exc}") from None


def _number(text: str, entry: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"--space entry {entry!r}: {text!r} is not a number") from None
    if not math.isfinite(value):
        raise InputError(f"--space entry {entry!r}: bounds must be finite")
    return value


def parse_space(text: str, base: SceneConfig) -> SearchSpace:
    """Parse ``NAME=LO:HI[:log],...`` (see the module doc) and check it against `base`."""
    dims: dict[str, Dimension] = {}
    settings: set[str] = set()
    for entry in text.split(","):
        entry = entry.strip()
        if not entry:
            continue
        name, sep, bounds = entry.partition("=")
        name = name.strip()
        parts = [p.strip() for p in bounds.split(":")]
        shape_ok = len(parts) == 2 or (len(parts) == 3 and parts[2] == "log")
        if not sep or not name or not shape_ok:
            raise InputError(f"--space entry {entry!r} is not NAME=LO:HI or NAME=LO:HI:log")
        lo, hi = _number(parts[0], entry), _number(parts[1], entry)
        log = len(parts) == 3
        if not lo < hi:
            raise InputError(f"--space entry {entry!r}: LO must be below HI")
        if log and lo <= 0:
            raise InputError(f"--space entry {entry!r}: a log scale needs LO > 0")
        if _OBJECT.match(name):
            if lo < 0 or hi > _MAX_DEPTH_MM:
                raise InputError(f"--space entry {entry!r}: depths lie in 0..100 mm")
            dim = Dimension(name, lo, hi, log)
            setting = name
        elif _SHIFT.match(name):
            limit = MAX_COM_SHIFT_M * 1000.0
            if log or lo < -limit or hi > limit:
                raise InputError(
                    f"--space entry {entry!r}: shifts lie in -{limit:g}..{limit:g} mm (no log)"
                )
            dim = Dimension(name, lo, hi)
            setting = name
        elif name.startswith("object."):
            raise InputError(
                f"--space: unknown object parameter {name!r}; use object.<id>.front_depth_mm, "
                "object.<id>.back_depth_mm or object.<id>.com_shift_mm"
            )
        else:
            integer = _scene_kind(name, base) == "int"
            if integer and (lo != int(lo) or hi != int(hi)):
                raise InputError(f"--space entry {entry!r}: {name} is an integer setting")
            dim = Dimension(name, lo, hi, log, integer)
            _check_scene_values(dim, base)
            setting = "gap_m" if name == "gap_mm" else name
        if setting in settings:
            raise InputError(f"--space names {setting} twice")
        settings.add(setting)
        dims[name] = dim
    if not dims:
        raise InputError("--space is empty")
    return SearchSpace(tuple(dims[k] for k in sorted(dims)))


def default_space(
    mu: tuple[float, float] = (0.2, 0.8), gap_mm: tuple[float, float] = (5.0, 40.0)
) -> str:
    """The space of the study's instance parameters (Sec. 6.5.2): μ_k and d_gap."""
    return f"mu={mu[0]!r}:{mu[1]!r},gap_mm={gap_mm[0]!r}:{gap_mm[1]!r}"


def trial_proxies(
    params: Mapping[str, object], object_map: Mapping[str, str]
) -> dict[str, ProxySpec]:
    """Real object id → the proxy described by the ``object.*`` depths in `params`: the
    object's reference in `object_map` (a built-in id, or a file, stored as an absolute
    path) with one protrusion per tuned face, faces in order front, back; a face that is not
    tuned keeps a built-in core's shipped feature (`transfertwin.objects.builtin_features`);
    ``object.<id>.com_shift_mm`` sets the proxy's centre-of-mass shift (default 0)."""
    depths: dict[str, dict[str, float]] = {}
    shifts: dict[str, float] = {}
    for key, value in params.items():
        m = _OBJECT.match(key)
        if m:
            depths.setdefault(m.group(1), {})[m.group(2)] = float(value) / 1000.0
        elif m := _SHIFT.match(key):
            shifts[m.group(1)] = float(value) / 1000.0
            depths.setdefault(m.group(1), {})
    proxies = {}
    known = set(builtin_ids())
    for oid, faces in sorted(depths.items()):
        ref = object_map.get(oid, oid)
        base = ref if ref in known else str(Path(ref).resolve())
        shipped = {p.face: p for p in builtin_features(ref)} if ref in known else {}
        prots = tuple(
            Protrusion(face, faces[face]) if face in faces else shipped[face]
            for face in ("front", "back")
            if face in faces or face in shipped
        )
        proxies[oid] = ProxySpec(oid, base, prots, note="tuned proxy (calibrate tune), not a scan",
                                 com_shift_m=shifts.get(oid, 0.0))  # fmt: skip
    return proxies
