"""What the console shows of the floor's raw readings, in words (pure functions).

The assets publish some values as JSON text (``KpisJson``, ``FusedPosesJson``,
``DockingErrorsJson``, ``TransferHistoryJson``, ``PredictionsJson``) and angles in
radians; a session that fails leaves an exception's class name; the TMS's history mixes
wall-clock timestamps with modelled floor times. These functions turn each into what an
operator reads:

- `value_text`: one live value as a readable field ('TM_1 at (1.20, 0.80) m', 'θ 90.0°');
- `display_values`: an asset's values as (name, text) pairs, the KPIs left to their panel;
- `unreachable_text`: why an asset or the floor does not answer, in words;
- `step_text`: a history step with its clock named ('expected 225 s of modelled floor time').
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping
from typing import Any

__all__ = ["display_values", "step_text", "unreachable_text", "value_text"]

#: Values shown elsewhere (the KPI panel draws ``KpisJson``).
_SHOWN_ELSEWHERE = frozenset({"KpisJson"})

#: Why a session failed, by exception class, in words.
_UNREACHABLE = {
    "ConnectionRefusedError": "nothing listens at its address (is the floor running?)",
    "ConnectionResetError": "the connection was dropped",
    "ConnectionAbortedError": "the connection was dropped",
    "TimeoutError": "it did not answer in time",
    "CancelledError": "the connection was closed",
    "OSError": "the network refused the connection",
    "BadSessionClosed": "its session was closed",
    "BadUserAccessDenied": "it refused the console's credentials",
    "BadIdentityTokenRejected": "it refused the console's credentials",
    "BadSecurityChecksFailed": "it refused the console's certificate",
}

_EXPECTED = re.compile(r"\bexpected (\d+(?:\.\d+)?) s\b")


def unreachable_text(error: str | None) -> str:
    """Why something does not answer, in words, from the exception class name a failed
    session left (its name follows in brackets only when it has no words here)."""
    if not error:
        return "not answering"
    words = _UNREACHABLE.get(error)
    return f"not answering: {words}" if words else f"not answering ({error})"


def step_text(text: str) -> str:
    """A TMS history step with the clock of its duration named: the auction's 'expected
    225 s' is modelled floor time (what the modules' travel and transfers would take on the
    floor), not the wall-clock time the steps are stamped with."""
    return _EXPECTED.sub(r"expected \1 s of modelled floor time", text)


def _number(value: float, name: str = "") -> str:
    if not math.isfinite(value):
        return "–"
    if name.endswith("Theta") or name in {"Theta", "theta", "theta_rad"}:
        return f"{math.degrees(value):.1f}°"
    return f"{value:.3g}" if abs(value) < 1000 else f"{value:.0f}"


def _poses(doc: Mapping[str, Any]) -> str:
    parts = []
    for node, p in doc.items():
        if isinstance(p, Mapping) and isinstance(p.get("x"), int | float):
            sd = p.get("sd_x")
            spread = f" ± {100 * sd:.1f} cm" if isinstance(sd, int | float) else ""
            heading = f", θ {math.degrees(p.get('theta', 0.0)):.0f}°"
            parts.append(f"{node} at ({p['x']:.2f}, {p['y']:.2f}) m{spread}{heading}")
    return "; ".join(parts) if parts else "no poses yet"


def _docking(doc: Mapping[str, Any]) -> str:
    parts = []
    for module, e in doc.items():
        if isinstance(e, Mapping) and isinstance(e.get("x_m"), int | float):
            x, y, th = 1000 * e["x_m"], 1000 * e["y_m"], math.degrees(e["theta_rad"])
            parts.append(
                f"{module} at {e.get('unit', '?')}: x {x:.1f} mm, y {y:.1f} mm, θ {th:.2f}°"
            )
    return "; ".join(parts) if parts else "none measured yet"


def _history(doc: list[Any]) -> str:
    if not doc:
        return "no transfers yet"
    last = doc[-1] if isinstance(doc[-1], Mapping) else {}
    outcome = last.get("outcome") or "unknown"
    where = f" at {last['target']}" if last.get("target") else ""
    return f"{len(doc)} transfer{'s' if len(doc) != 1 else ''}, the last {outcome}{where}"


def _state_words(p: Mapping[str, Any]) -> str:
    share, low, high = p.get("share"), p.get("ci_low"), p.get("ci_high")
    odds = (f"{100 * share:.0f} % [{100 * low:.0f}, {100 * high:.0f}] of the twin's runs"
            if all(isinstance(v, int | float) for v in (share, low, high)) else "?")  # fmt: skip
    return (f"{p.get('face', '?')} face up, {p.get('conveyor', '?')} conveyor, "
            f"θ {p.get('theta_deg', '?')}°: {odds}")


def _predictions(doc: Mapping[str, Any]) -> str:
    """An object's calibrated predictions (``PredictionsJson``), best and worst in words."""
    best, worst = doc.get("best"), doc.get("worst")
    if not isinstance(best, Mapping):
        return "no campaign has predicted it yet"
    legs = "both legs" if doc.get("leg") == "operation" else "there and back"
    advice = f"{doc['advice']} " if doc.get("advice") else ""
    text = f"{advice}best {_state_words(best)} ({legs})"
    if isinstance(worst, Mapping) and worst != best:
        text += f"; worst {_state_words(worst)}"
    return text + f"; campaign {doc.get('campaign', '?')}"


def _json_text(name: str, text: str) -> str:
    try:
        doc = json.loads(text) if text else None
    except ValueError:
        return text[:80]
    if name == "FusedPosesJson" and isinstance(doc, Mapping):
        return _poses(doc)
    if name == "DockingErrorsJson" and isinstance(doc, Mapping):
        return _docking(doc)
    if name == "TransferHistoryJson" and isinstance(doc, list):
        return _history(doc)
    if name == "PredictionsJson" and isinstance(doc, Mapping):
        return _predictions(doc)
    if isinstance(doc, Mapping):
        return ", ".join(f"{k} {value_text(str(k), v)}" for k, v in list(doc.items())[:6])
    if isinstance(doc, list):
        return f"{len(doc)} entr{'ies' if len(doc) != 1 else 'y'}"
    return "–" if doc is None else str(doc)


def value_text(name: str, value: object) -> str:
    """One live value as an operator reads it: JSON summarised in words, angles (names
    ending in 'Theta', radians) in degrees, numbers to three digits, '' as '–'."""
    if name.endswith("Json") and isinstance(value, str):
        return _json_text(name, value)
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int | float):
        return _number(float(value), name)
    if value is None or value == "":
        return "–"
    if isinstance(value, list | tuple):
        return ", ".join(value_text(name, v) for v in value[:8])
    return str(value)


def display_values(values: Mapping[str, object]) -> list[tuple[str, str]]:
    """An asset's live values as (name, text) pairs in their order; the KPIs' JSON is left
    out (the KPI panel shows it) and a '…Json' name loses its suffix."""
    return [(name.removesuffix("Json"), value_text(name, v))
            for name, v in values.items() if name not in _SHOWN_ELSEWHERE]  # fmt: skip
