"""Malformed and invalid requests leave an asset server serving (issue 13, item 3): a fixed
seed and a bounded count here; scripts/cps_fuzz.py runs more."""

from __future__ import annotations

import asyncio

import pytest
from benchmarks._stress import KINDS, fuzz

from transfertwin.cps.opcua import connect

SESSION_OK = {
    # a read of a node that does not exist, a write of the wrong type, a call with wrong
    # arguments: each gets its Bad status, never Good, never a dropped session
    "bad_node_id": {"BadNodeIdUnknown", "BadNodeIdInvalid"},
    "wrong_type_write": {"BadTypeMismatch"},
    "wrong_call": {"BadTypeMismatch", "BadArgumentsMissing", "BadTooManyArguments",
                   "BadInvalidArgument"},
}  # fmt: skip


def test_fuzzed_requests_leave_the_server_serving(tu_a, pki):
    # wait_s: how long a raw case waits for the server's reaction. The answers come within
    # milliseconds; the 28 cases that get none (a truncated Hello: the server waits for
    # the rest) cost the whole wait each. 0.1 s and 0.3 s give the same outcomes here.
    async def go():
        def session():
            return connect(tu_a.endpoint, "TU_A", role="operator", timeout_s=30,
                           **pki.client_kw())  # fmt: skip

        return await fuzz(tu_a.endpoint, session, asset_id="TU_A", seed=13, count=120,
                          writable=tu_a.writable, methods=tu_a.methods,
                          wait_s=0.1)  # fmt: skip

    before = tu_a.run(tu_a.server.get("OperationalData", "PossessedObjects"))
    report = asyncio.run(asyncio.wait_for(go(), 300))
    assert sum(report.cases.values()) == 120 and set(report.cases) == set(KINDS)
    assert report.alive_checks == 120 // 50 + 1
    for key, n in report.outcomes.items():
        kind, outcome = key.split(":")
        if kind in SESSION_OK:
            assert outcome in SESSION_OK[kind], (key, n)
    # no fuzzed write went through
    assert tu_a.run(tu_a.server.get("OperationalData", "PossessedObjects")) == before


def test_stress_refuses_servers_off_loopback():
    with pytest.raises(ValueError, match="only against loopback"):
        asyncio.run(fuzz("opc.tcp://192.0.2.1:4840/x", None, asset_id="x", seed=0, count=1,
                         writable=[], methods=[]))  # fmt: skip
