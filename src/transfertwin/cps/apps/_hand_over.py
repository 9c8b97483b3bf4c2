"""A transport module's hand-over policy (docs/architecture.md, "Operation"): a transfer
that failed from a valid start state is taken back and tried again. One loop for every
module (`HandOverRetries`): the virtual or plant module (`cps.roles._module`, its simulation of
the docked pair) and the module on real hardware (`cps.roles._remote_module`, its HAL gateway)
differ only in how they take an object back (`take_back` with their own belts, sensor
and clock) and how they dock anew (their `dock` skill).
"""

from __future__ import annotations

import logging
from typing import Any

__all__ = ["DELIVERY_RETRIES", "PICKUP_RETRIES", "HandOverRetries", "take_back"]

log = logging.getLogger("transfertwin.cps")

#: A delivery whose transfer failed: the object is taken back onto the module (belts
#: reversed, at most `TAKE_BACK_S`) and tried again after docking anew, at most
#: `DELIVERY_RETRIES` times, then taken back once more and the operation fails with the
#: object on the module; an object that does not come back lies in the gap, and its place
#: is unknown.
DELIVERY_RETRIES = 1
#: A failed pick-up is tried again this many times: the object taken back onto the unit,
#: put down in the plan's fallback state by the station, the module docked anew.
PICKUP_RETRIES = 1
TAKE_BACK_S = 6.0
TAKE_BACK_STEP_S = 0.1
#: How far behind the receiving end's tip the object's near edge must be.
TAKE_BACK_CLEARANCE_M = 0.03


def take_back(tm, tu, observe, clock, scene, to_unit: bool) -> bool:
    """Reverse both belt pairs until the object is wholly on the module, clear of its tip
    (True) — with `to_unit`, after a failed pick-up, wholly back on the unit, clear of its
    tip — or `TAKE_BACK_S` on `clock` passed (False: it is caught in the gap); belts
    stopped either way.

    Args:
        tm, tu: The module's and the docked unit's belts (`UnitHAL`'s ``set_belt_speed``).
        observe: The object's state (a, x, y, z, s_x, s_y, s_z, θ) in F_T (Eq. 5.4), or
            None when nothing is seen.
        clock: `transfertwin.control.Clock` the pauses run on.
        scene: The twin's `SceneConfig` (belt speed, gap).
    """
    speed = scene.layout.belt_speed_m_s * (1.0 if to_unit else -1.0)
    gap = scene.gap_m  # the twin's: what the module knows of the docked pair
    for belt in ("left", "right"):
        tm.set_belt_speed(belt, speed)
        tu.set_belt_speed(belt, speed)
    clear = False
    try:
        for _ in range(round(TAKE_BACK_S / TAKE_BACK_STEP_S)):
            clock.wait(TAKE_BACK_STEP_S)
            state = observe()
            if state is None:
                continue
            if to_unit:  # wholly on the unit's belts (they start at x = gap)
                clear = bool(state[1] - state[4] > gap + TAKE_BACK_CLEARANCE_M)
            else:  # wholly on the module's belts, clear of its tip (x = 0)
                clear = bool(state[1] + state[4] < -TAKE_BACK_CLEARANCE_M)
            if clear:
                break
    finally:
        for belt in ("left", "right"):
            tm.set_belt_speed(belt, 0.0)
            tu.set_belt_speed(belt, 0.0)
    return clear


class HandOverRetries:
    """The hand-over policy as a mixin of a module's skills (`TransportSkills`): put it
    before the class whose ``transfer`` is one try. It uses the skills' ``host`` (the
    module, `transfertwin.cps.node.ModuleHost`: ``take_back``, ``undock``, ``attempt``,
    ``lost_in_gap``, ``face``, ``op``, ``state``), ``obj``, ``load_state``, ``face``,
    ``dock`` and ``form_ots``."""

    attempt = 0
    fallback: dict[str, Any] | None = None  # the state a failed pick-up is tried again in

    async def transfer(self, leg):
        """A failed hand-over is taken back and tried again: a delivery onto the module
        (its state cannot change), `DELIVERY_RETRIES` times; a pick-up onto the unit,
        where the station puts the object down in the plan's fallback state (the same
        state without one), `PICKUP_RETRIES` times."""
        from transfertwin.cps.apps import StepResult

        host = self.host
        result = await super().transfer(leg)
        pickup = leg.name == "pick-up"
        onto, retries = ("unit", PICKUP_RETRIES) if pickup else ("module", DELIVERY_RETRIES)
        tries = []
        while not result.ok and result.info.get("valid"):
            back = await host.take_back(leg.unit, to_unit=pickup)
            tries.append({"attempt": self.attempt + 1, "taken_back": back,
                          "reason": result.reason, "state": self.load_state})  # fmt: skip
            if not back:
                host.lost_in_gap = True
                return StepResult(False, f"{result.reason}; the object did not come back "
                                         f"onto the {onto}: it lies in the gap",
                                  {**result.info, "retries": tries})  # fmt: skip
            if self.attempt >= retries:
                return StepResult(False, f"{result.reason}; taken back onto the {onto} "
                                         f"after {self.attempt + 1} attempt(s)",
                                  {**result.info, "retries": tries})  # fmt: skip
            self.attempt += 1
            host.attempt = self.attempt
            if pickup and self.fallback:  # the station puts it down in the next-best state
                self._load(self.fallback)
            log.info("%s: took %s back onto the %s at %s; %sdocking again (attempt %d)",
                     host.aid, self.obj, onto, leg.unit,
                     f"loaded {state_text(self.load_state)}, " if pickup else "",
                     self.attempt + 1)  # fmt: skip
            await host.undock()
            for step in (self.dock, self.form_ots):
                pre = await step(leg)
                if not pre.ok:
                    return StepResult(False, pre.reason, {**pre.info, "retries": tries})
            result = await super().transfer(leg)
        if tries:
            return StepResult(result.ok, result.reason, {**result.info, "retries": tries})
        return result

    def _load(self, state) -> None:
        """From now on the object lies in `state` (the face the module carries it on)."""
        host = self.host
        self.load_state = dict(state)
        self.face = host.face = str(state["face"])
        host.state.data.setdefault("faces", {})[self.obj] = self.face
        if host.op is not None:
            host.op["load"] = self.load_state


#: The state an object is loaded in without the twin (nearest-idle; learning alone's first
#: order): the front face on the left conveyor at θ = 0, the first of Eq. 6.7's states at
#: θ = 0 in the study's order. It is a pre-transfer state of the twin's set, so the twin
#: predicts it and a ranking can keep it (until 2026-11-28 it was (front, both, 0), which
#: Eq. 6.7 does not admit: at |θ| ≤ 25° an object lies on one conveyor).
DEFAULT_STATE = {"face": "front", "conveyor": "left", "theta_deg": 0}


def state_text(state) -> str:
    """A load state in one line (none: the default state, `DEFAULT_STATE`)."""
    if not state:
        s = DEFAULT_STATE
        return f"as before ({s['face']}/{s['conveyor']}/{s['theta_deg']} deg)"
    return f"{state['face']}/{state['conveyor']}/{state['theta_deg']} deg"
