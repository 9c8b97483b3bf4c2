"""Named physics profiles: a `SceneConfig` saved as TOML.

A profile holds the instance parameters (μ_k, d_gap) and any physics, layout or placement
setting that differs from the defaults, e.g.::

    name = "calibrated"
    [scene]
    mu = 0.489
    gap_mm = 11.88
    [physics]
    solver = "Newton"
    impratio = 1.0

Files are parsed here, at the edge; the rest of the code sees frozen configs only. A setting
that is off (None, e.g. ``stall_time_s`` of the 'reference' profile) is written as "none".
`load_profile` also accepts the name of a built-in profile (`transfertwin.sim.PROFILES`:
'fast', the defaults, 'reference' and 'lean') instead of a path.
"""

from __future__ import annotations

import tomllib
from dataclasses import asdict, fields
from pathlib import Path

from transfertwin._atomic import write_atomic
from transfertwin._errors import InputError
from transfertwin.sim import PROFILES, SceneConfig, scene_profile

__all__ = ["load_profile", "profile_toml", "save_profile", "scene_from_dict", "scene_to_dict"]

_SECTIONS = ("physics", "layout", "placement")


def scene_to_dict(cfg: SceneConfig) -> dict[str, object]:
    """A JSON/TOML-able dict of every setting (lengths of the scene section in SI)."""
    out = asdict(cfg)
    for key in _SECTIONS:
        out[key] = {k: list(v) if isinstance(v, tuple) else v for k, v in out[key].items()}
    return out


def _none(value: object) -> object:
    return None if value == "none" else value


def scene_from_dict(data: dict[str, object], *, where: str = "profile") -> SceneConfig:
    """Inverse of `scene_to_dict`; also accepts `gap_mm` for `gap_m` in the scene section."""
    flat: dict[str, object] = {}
    scene_keys = {f.name for f in fields(SceneConfig)} - set(_SECTIONS)
    for key, value in data.items():
        if key in _SECTIONS:
            if not isinstance(value, dict):
                raise InputError(f"{where}: [{key}] must be a table")
            for sub, v in value.items():
                flat[f"{key}.{sub}"] = tuple(v) if isinstance(v, list) else _none(v)
        elif key == "gap_mm":
            flat["gap_m"] = float(value) / 1000.0
        elif key in scene_keys:
            flat[key] = _none(value)
        else:
            raise InputError(f"{where}: unknown scene setting {key!r}")
    try:
        return SceneConfig().with_overrides(**flat)
    except TypeError as exc:
        raise InputError(f"{where}: {exc}") from None


def load_profile(path: str | Path) -> tuple[str, SceneConfig]:
    """Read a profile file, or a built-in profile by name; returns (name, scene)."""
    if isinstance(path, str) and path in PROFILES and not Path(path).is_file():
        return path, scene_profile(path)
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except OSError as exc:
        raise InputError(f"{path}: cannot read profile: {exc.strerror}") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{path}: not a valid TOML profile: {exc}") from None
    name = str(data.pop("name", path.stem))
    scene = dict(data.pop("scene", {}))
    for key in _SECTIONS:
        if key in data:
            scene[key] = data.pop(key)
    if data:
        raise InputError(f"{path}: unknown profile entries: {', '.join(sorted(data))}")
    return name, scene_from_dict(scene, where=str(path))


def _toml_value(value: object) -> str:
    if value is None:
        return '"none"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return repr(value)


def profile_toml(name: str, cfg: SceneConfig, comment: str | None = None) -> str:
    """The TOML text of a profile holding every setting of `cfg`, after `comment` as
    ``#`` lines (if given)."""
    data = scene_to_dict(cfg)
    lines = [f"# {line}".rstrip() for line in (comment or "").splitlines()]
    lines += [f"name = {_toml_value(name)}", "", "[scene]"]
    for key, value in data.items():
        if key not in _SECTIONS:
            lines.append(f"{key} = {_toml_value(value)}")
    for section in _SECTIONS:
        lines += ["", f"[{section}]"]
        lines += [f"{k} = {_toml_value(v)}" for k, v in data[section].items()]
    return "\n".join(lines) + "\n"


def save_profile(path: str | Path, name: str, cfg: SceneConfig, comment: str | None = None) -> Path:
    """Write a profile atomically (with `comment` as leading ``#`` lines)."""
    return write_atomic(path, profile_toml(name, cfg, comment))
