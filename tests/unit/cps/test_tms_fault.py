"""The TMS's run of an order (`TmsRole._run`): an order whose task raises ends as a fault of
the floor with the error as its reason (in its history, its result and the published
counters), never left queued; a cancelled run (the node stopping) is not a fault, the order
stays to be resumed. Real role and order book on the default floor; the node around them is
a stand-in that records what the role publishes."""

from __future__ import annotations

import asyncio
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from transfertwin.cps.floor import default_floor_spec
from transfertwin.cps.roles import TmsRole


@dataclass
class _Server:
    """Records the role's OperationalData as it sets them."""

    values: dict[str, Any] = field(default_factory=dict)

    async def set(self, submodel: str, prop: str, value: object) -> None:
        self.values[prop] = value


class _Node:
    """What `TmsRole` asks of its node, no OPC UA: id, state folder, floor, server, tasks."""

    def __init__(self, state_dir: Path) -> None:
        self.desc = SimpleNamespace(asset_id="TMS")
        self.cfg = SimpleNamespace(state_dir=state_dir)
        self.floor = default_floor_spec()
        self.server = _Server()
        self.tasks: list[asyncio.Task] = []

    def spawn(self, coro) -> asyncio.Task:
        task = asyncio.ensure_future(coro)
        self.tasks.append(task)
        return task


def _order(tmp_path: Path) -> tuple[TmsRole, _Node, str]:
    node = _Node(tmp_path)
    role = TmsRole(node)  # type: ignore[arg-type]
    op_id = role.book.accept("o2", "TU_C", "TU_B", None)  # o2 lies on TU_B
    return role, node, op_id


def test_an_order_whose_task_raises_ends_as_a_fault_with_the_error(tmp_path: Path) -> None:
    role, node, op_id = _order(tmp_path)

    async def broken_plan(op: dict[str, Any]) -> dict[str, Any]:
        raise ValueError("no state to load o2 in")

    role._plan = broken_plan  # type: ignore[method-assign]

    async def scenario() -> None:
        await role._run(op_id)
        await asyncio.gather(*node.tasks)

    assert role.book.running() == 1
    asyncio.run(scenario())
    op = role.ops[op_id]
    assert (op["state"], op["phase"]) == ("finished", "failed")  # not left queued
    assert op["result"]["status"] == "error: ValueError: no state to load o2 in"
    assert op["result"]["fault"] is True
    assert op["result"]["failed_step"] == "queued"  # the step it was in
    assert [h[1] for h in op["history"]] == [
        "queued",
        "error: ValueError: no state to load o2 in",
        "failed",
    ]
    assert role.book.running() == 0
    assert node.server.values["QueuedOperations"] == 0
    assert node.server.values["CompletedOperations"] == 1
    assert role._done[op_id].is_set()  # orders chained after it go on
    assert role.ledger.location("o2") == "TU_B"  # the object stays where it was


def test_a_cancelled_run_is_no_fault_and_the_order_stays_to_resume(tmp_path: Path) -> None:
    role, _, op_id = _order(tmp_path)

    async def cancelled(op: dict[str, Any]) -> dict[str, Any]:
        raise asyncio.CancelledError

    role._plan = cancelled  # type: ignore[method-assign]
    with pytest.raises(asyncio.CancelledError):
        asyncio.run(role._run(op_id))
    assert role.ops[op_id]["state"] != "finished"
    assert role.book.running() == 1


def test_an_order_no_module_can_take_says_why_it_waits_once(tmp_path: Path) -> None:
    """Every module carries an object (failed deliveries taken back): the queued order's
    history says so, with what to do, once however long it waits (no silent queue)."""
    role, node, op_id = _order(tmp_path)
    modules = [m.asset_id for m in node.floor.modules]
    others = [o for o, _ in node.floor.objects if o != "o2"]
    for obj, m in zip(others, modules, strict=False):  # each module holds an object
        role.book.ledger.move(obj, m)

    async def online(obj: str | None = None) -> list[dict[str, Any]]:
        return [{"id": m, "online": True, "admits": True, "state": "idle"} for m in modules]

    role._modules = online  # type: ignore[method-assign]

    async def scenario() -> None:
        task = asyncio.ensure_future(role._allocate(op_id))
        await asyncio.sleep(1.3)  # three rounds of the auction
        assert not task.done()
        task.cancel()
        with pytest.raises(asyncio.CancelledError):
            await task

    asyncio.run(scenario())
    said = [h[1] for h in role.ops[op_id]["history"] if h[1].startswith("waiting:")]
    held = "; ".join(f"{m} carries {o}" for o, m in zip(others, modules, strict=False))
    assert said == [f"waiting: every transport module carries an object ({held}): order "
                    "those onward or locate them"]
