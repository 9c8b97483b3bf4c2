"""Load on loopback (issue 13, item 3): paced writes to one asset lose and reorder nothing;
many subscriptions all see the last value. The full runs (1,000 writes/s for 30 s with a
bound on memory growth; 100 subscriptions) are marked slow; benchmarks/cps_load.py prints
the figures."""

from __future__ import annotations

import asyncio

import pytest
from benchmarks._stress import WriteRecorder, paced_writes, rss_kib

from transfertwin.cps.opcua import connect

N_WRITES = 1000


def _paced(tu_a, pki, rate_hz: float, duration_s: float):
    recorder = WriteRecorder("OperationalData", "PossessedObjects")
    remove = tu_a.server.on_client_write(recorder)

    async def scenario():
        async with connect(
            tu_a.endpoint, "TU_A", role="operator", timeout_s=60, **pki.client_kw()
        ) as op:
            return await paced_writes(op, "OperationalData", "PossessedObjects",
                                      rate_hz=rate_hz, duration_s=duration_s)  # fmt: skip

    try:
        sent, elapsed = asyncio.run(asyncio.wait_for(scenario(), 60 + 4 * duration_s))
    finally:
        remove()
    return recorder.check(sent), elapsed


def test_one_second_of_paced_writes_loses_and_reorders_nothing(tu_a, pki):
    check, elapsed = _paced(tu_a, pki, rate_hz=1000, duration_s=1.0)
    assert (check.sent, check.applied) == (1000, 1000)
    assert (check.lost, check.duplicated, check.reordered) == (0, 0, 0)
    assert tu_a.run(tu_a.server.get("OperationalData", "PossessedObjects")) == "999"
    assert elapsed > 0.99  # paced, not a burst


@pytest.mark.slow
def test_thirty_seconds_at_a_thousand_writes_per_second(tu_a, pki):
    _paced(tu_a, pki, rate_hz=1000, duration_s=2.0)  # warm-up: sessions, caches
    before = rss_kib()
    check, elapsed = _paced(tu_a, pki, rate_hz=1000, duration_s=30.0)
    growth_mib = (rss_kib() - before) / 1024
    assert (check.sent, check.applied, check.lost, check.reordered) == (30000, 30000, 0, 0)
    assert check.sent / elapsed > 950, f"{check.sent / elapsed:.0f} writes/s"
    assert growth_mib < 32, f"RSS grew {growth_mib:.1f} MiB"


@pytest.mark.parametrize(
    "n_subs",
    # 100 subscriptions at 50 ms are 2,000 publish cycles/s on top of the writes: ~20 s here
    [pytest.param(10, marks=pytest.mark.slow), pytest.param(100, marks=pytest.mark.slow)],
)
def test_thousand_writes_and_many_subscriptions_lose_nothing(tu_a, pki, n_subs):
    async def scenario():
        async with (
            connect(
                tu_a.endpoint, "TU_A", role="viewer", timeout_s=60, **pki.client_kw()
            ) as watcher,
            connect(
                tu_a.endpoint, "TU_A", role="operator", timeout_s=60, **pki.client_kw()
            ) as writer,
        ):
            final = str(N_WRITES - 1)
            seen = [asyncio.Event() for _ in range(n_subs)]
            last: list[str | None] = [None] * n_subs

            class Handler:
                def __init__(self, i: int) -> None:
                    self.i = i

                def datachange_notification(self, node, val, data) -> None:
                    last[self.i] = val
                    if val == final:
                        seen[self.i].set()

            subs = [await watcher.subscribe(Handler(i), ("OperationalData", "PossessedObjects"))
                    for i in range(n_subs)]  # fmt: skip
            # the writes pipelined (asyncua's client does not create subscriptions concurrently)
            sent, _ = await paced_writes(writer, "OperationalData", "PossessedObjects",
                                         rate_hz=1000, duration_s=N_WRITES / 1000)  # fmt: skip
            assert sent == N_WRITES
            await asyncio.wait_for(asyncio.gather(*(e.wait() for e in seen)), 60)
            # every subscription saw the final value. (Not asserted: that it is also the last
            # notification handled. With writes faster than the 50 ms publishing interval
            # and several Publish requests in flight, asyncua's client can hand an older
            # notification over after a newer one; see docs/security.md.)
            assert all(v is not None for v in last)
            for sub in subs:
                await sub.delete()

    asyncio.run(asyncio.wait_for(scenario(), timeout=240))
    assert tu_a.run(tu_a.server.get("OperationalData", "PossessedObjects")) == str(N_WRITES - 1)
