"""`stop_tasks`: a task that swallows its cancellation (as ``wait_for`` on Python 3.11 can,
gh-86296) is cancelled again until it ends; one that never ends is given up on, named."""

from __future__ import annotations

import asyncio
import logging

from transfertwin._aio import stop_tasks


async def _swallows_once(state: dict) -> None:
    """A poll loop that drops its first cancellation, as the 3.11 race does."""
    while True:
        try:
            await asyncio.sleep(0.01)
        except asyncio.CancelledError:
            state["cancels"] += 1
            if state["cancels"] == 1:
                asyncio.current_task().uncancel()
                continue
            raise


def test_a_task_that_swallows_a_cancellation_is_cancelled_again_until_it_ends():
    async def scenario() -> None:
        state = {"cancels": 0}
        task = asyncio.ensure_future(_swallows_once(state))
        await asyncio.sleep(0.03)
        # one cancel and a wait for the task, as before: the task runs on
        task.cancel()
        done, _ = await asyncio.wait({task}, timeout=0.2)
        assert not done and state["cancels"] == 1
        left = await stop_tasks([task], deadline_s=5.0, retry_s=0.05)
        assert left == set() and task.cancelled() and state["cancels"] == 2

    asyncio.run(scenario())


def test_a_task_that_never_ends_is_left_after_the_deadline_and_named(caplog):
    release = {"now": False}

    async def stubborn() -> None:
        while not release["now"]:
            try:
                await asyncio.sleep(0.01)
            except asyncio.CancelledError:
                asyncio.current_task().uncancel()

    async def scenario() -> None:
        task = asyncio.ensure_future(stubborn())
        task.set_name("stubborn-poll")
        await asyncio.sleep(0.02)
        with caplog.at_level(logging.WARNING, logger="transfertwin"):
            left = await stop_tasks([task], deadline_s=0.3, retry_s=0.05)
        assert left == {task} and not task.done()
        assert "stubborn-poll" in caplog.text
        release["now"] = True  # let it end, so that the loop can close
        await asyncio.wait({task}, timeout=2.0)
        assert task.done()

    asyncio.run(scenario())


def test_exceptions_of_ended_tasks_are_retrieved_not_raised():
    async def fails() -> None:
        raise RuntimeError("gateway away")

    async def scenario() -> None:
        task = asyncio.ensure_future(fails())
        await asyncio.sleep(0)
        assert await stop_tasks([task]) == set()
        assert isinstance(task.exception(), RuntimeError)

    asyncio.run(scenario())
