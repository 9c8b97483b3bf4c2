"""Bounded stress of an asset server on loopback: paced writes and fuzzed requests.

Both refuse any endpoint that is not on a loopback address: they are for testing one's own
servers, never for probing others.

* `paced_writes` sends writes of the numbers 0, 1, ..., n-1 to one variable at a fixed
  rate, each as its own WriteRequest, pipelined (up to `max_in_flight` unanswered);
  `WriteRecorder` records on the server side what it applied, in order, so `check` counts
  lost, duplicated and reordered writes.
* `fuzz` sends malformed traffic (random bytes, truncated and mutated Hello and
  OpenSecureChannel messages, requests on a channel without a session) and, through a real
  session, bad node ids and values and arguments of the wrong type; every case is drawn from
  one seeded generator, so a seed names a run.
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import struct
import time
import uuid
from array import array
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import urlparse

import numpy as np
from asyncua import ua
from asyncua.common.connection import SecureConnection, TransportLimits
from asyncua.crypto.security_policies import SecurityPolicyNone
from asyncua.ua.ua_binary import nodeid_to_binary, struct_to_binary, uatcp_to_binary

from transfertwin.cps.opcua import AssetClient

__all__ = ["FuzzReport", "WriteCheck", "WriteRecorder", "fuzz", "paced_writes", "rss_kib"]


def _loopback(endpoint: str) -> tuple[str, int]:
    url = urlparse(endpoint)
    host = url.hostname or ""
    try:
        ok = host == "localhost" or ipaddress.ip_address(host).is_loopback
    except ValueError:
        ok = False
    if not ok or url.port is None:
        raise ValueError(f"{endpoint}: stress runs only against loopback servers")
    return host, url.port


def rss_kib() -> int:
    """Resident set size of this process now (KiB, from /proc/self/status)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise OSError("no VmRSS in /proc/self/status")


# -- paced writes ---------------------------------------------------------------------------
@dataclass(frozen=True)
class WriteCheck:
    """What the server applied of the writes 0..sent-1.

    Attributes:
        sent: Writes sent.
        applied: Writes the server applied (reported by its write listener).
        lost: Values sent but never applied.
        duplicated: Values applied more than once.
        reordered: Applied values smaller than the one applied before them.
    """

    sent: int
    applied: int
    lost: int
    duplicated: int
    reordered: int


@dataclass
class WriteRecorder:
    """Server-side log of the integer values written to one variable (register it with
    `AssetServer.on_client_write`)."""

    submodel: str
    prop: str
    values: array = field(default_factory=lambda: array("q"))

    def __call__(self, submodel: str, prop: str, value: Any) -> None:
        if (submodel, prop) == (self.submodel, self.prop):
            self.values.append(int(value))

    def check(self, sent: int) -> WriteCheck:
        """Compare the log with the values 0..sent-1 sent in this order."""
        v = np.frombuffer(self.values, dtype=np.int64) if len(self.values) else np.zeros(0, int)
        counts = np.bincount(v[(v >= 0) & (v < sent)], minlength=sent) if sent else v[:0]
        return WriteCheck(
            sent=sent,
            applied=len(v),
            lost=int(np.count_nonzero(counts == 0)),
            duplicated=int(np.sum(np.maximum(counts - 1, 0))),
            reordered=int(np.count_nonzero(np.diff(v) < 0)),
        )


async def paced_writes(
    client: AssetClient,
    submodel: str,
    prop: str,
    *,
    rate_hz: float,
    duration_s: float,
    max_in_flight: int = 64,
    on_second: Any = None,
) -> tuple[int, float]:
    """Write 0, 1, 2, ... to a variable at `rate_hz` for `duration_s`, one request each.

    Requests are sent in order on one secure channel and pipelined (a write does not wait
    for the previous answer; at most `max_in_flight` are unanswered), so the order on the
    wire is the order sent. A Bad answer raises.

    Args:
        client: An operator session with the server (loopback).
        submodel, prop: The (writable, Int64 or String) variable.
        rate_hz: Writes per second aimed at.
        duration_s: Seconds to write.
        max_in_flight: Bound of unanswered writes.
        on_second: Called with (seconds elapsed, writes sent) about once a second.

    Returns:
        (writes sent, seconds from the first send to the last answer).
    """
    _loopback(client.client.server_url.geturl())
    node = await client._node(submodel, prop)
    vtype = await node.read_data_type_as_variant_type()
    convert = str if vtype == ua.VariantType.String else int
    n = round(rate_hz * duration_s)
    window = asyncio.Semaphore(max_in_flight)
    pending: set[asyncio.Task] = set()
    errors: list[BaseException] = []

    async def one(k: int) -> None:
        try:
            await node.write_value(ua.DataValue(ua.Variant(convert(k), vtype)))
        except Exception as exc:  # reported after the run
            errors.append(exc)
        finally:
            window.release()

    loop = asyncio.get_running_loop()
    t0 = loop.time()
    next_report = 1.0
    for k in range(n):
        due = t0 + k / rate_hz
        if (wait := due - loop.time()) > 0:
            await asyncio.sleep(wait)
        await window.acquire()
        task = asyncio.ensure_future(one(k))
        await asyncio.sleep(0)  # let the task put its request on the wire now, in order
        pending.add(task)
        task.add_done_callback(pending.discard)
        if on_second is not None and loop.time() - t0 >= next_report:
            on_second(loop.time() - t0, k + 1)
            next_report += 1.0
    await asyncio.gather(*pending)
    elapsed = loop.time() - t0
    if errors:
        raise errors[0]
    return n, elapsed


# -- fuzz -----------------------------------------------------------------------------------
KINDS = (
    "random_bytes",
    "truncated_hello",
    "mutated_hello",
    "truncated_open",
    "mutated_open",
    "sessionless_request",
    "bad_node_id",
    "wrong_type_write",
    "wrong_call",
)


@dataclass(frozen=True)
class FuzzReport:
    """Outcome of a fuzz run.

    Attributes:
        cases: Cases sent per kind.
        outcomes: Count per (kind, outcome), outcome being what the server did: 'closed'
            (dropped the connection), 'answered' (an Error/Acknowledge/response), 'silent'
            (neither within the wait), or the Bad status a session request got.
        alive_checks: Times a fresh secure session read the asset id correctly (one after
            every `check_every` cases and one at the end).
        seconds: Duration of the run.
    """

    cases: dict[str, int]
    outcomes: dict[str, int]
    alive_checks: int
    seconds: float


def _hello(endpoint: str) -> bytes:
    hello = ua.Hello()
    hello.EndpointUrl = endpoint
    return uatcp_to_binary(ua.MessageType.Hello, hello)


def _open_request() -> bytes:
    conn = SecureConnection(SecurityPolicyNone(), TransportLimits())
    req = ua.OpenSecureChannelRequest()
    req.Parameters.RequestType = ua.SecurityTokenRequestType.Issue
    req.Parameters.SecurityMode = ua.MessageSecurityMode.None_
    req.Parameters.RequestedLifetime = 3_600_000
    req.Parameters.ClientNonce = b""
    return conn.message_to_binary(struct_to_binary(req), ua.MessageType.SecureOpen, 1)


def _mutate(rng: np.random.Generator, data: bytes) -> bytes:
    b = bytearray(data)
    for _ in range(int(rng.integers(1, 9))):
        i = int(rng.integers(0, len(b)))
        b[i] = int(rng.integers(0, 256))
    if rng.random() < 0.3:  # a lying length field
        b[4:8] = struct.pack("<I", int(rng.choice([0, 1, 7, 8, len(b) + 1000, 2**31 - 1])))
    return bytes(b)


def _session_request(rng: np.random.Generator) -> bytes:
    """A MSG chunk on a NoSecurity channel with no session: a service request type id
    (Read, Write, Call, CreateSession, ActivateSession, RegisterServer2 or any number) and
    a garbage body, on the channel the server assigned (1) or a wrong one."""
    type_id = int(rng.choice([631, 673, 712, 461, 467, 12211, int(rng.integers(0, 20000))]))
    body = nodeid_to_binary(ua.NodeId(type_id)) + rng.bytes(int(rng.integers(0, 200)))
    channel = int(rng.choice([1, 0, int(rng.integers(0, 2**32))]))
    header = struct.pack("<3scII", b"MSG", b"F", 12 + 12 + len(body), channel)
    return header + struct.pack("<III", 1, 2, 2) + body


async def _raw(host: str, port: int, payloads: list[bytes], wait_s: float) -> str:
    reader, writer = await asyncio.open_connection(host, port)
    try:
        for p in payloads:
            writer.write(p)
        await writer.drain()
        try:
            data = await asyncio.wait_for(reader.read(65536), wait_s)
        except TimeoutError:
            return "silent"
        return "answered" if data else "closed"
    except (ConnectionError, OSError):
        return "closed"
    finally:
        writer.close()
        with contextlib.suppress(ConnectionError, OSError):
            await writer.wait_closed()


def _bad_node_id(rng: np.random.Generator, ns: int) -> ua.NodeId:
    pick = int(rng.integers(0, 5))
    if pick == 0:
        return ua.NodeId(int(rng.integers(0, 2**32)), int(rng.integers(0, 2**16)))
    if pick == 1:
        return ua.NodeId(rng.bytes(int(rng.integers(1, 64))).decode("latin-1"), ns)
    if pick == 2:
        return ua.NodeId("x" * int(rng.integers(1000, 5000)), ns)
    if pick == 3:
        return ua.NodeId(bytes(rng.bytes(16)), ns, ua.NodeIdType.ByteString)
    return ua.NodeId(uuid.UUID(bytes=rng.bytes(16)), ns, ua.NodeIdType.Guid)


_WRONG = (lambda r: ua.Variant(float(r.normal()), ua.VariantType.Double),
          lambda r: ua.Variant(bool(r.integers(0, 2)), ua.VariantType.Boolean),
          lambda r: ua.Variant(r.bytes(8), ua.VariantType.ByteString),
          lambda r: ua.Variant([1, 2, 3], ua.VariantType.Int32),
          lambda r: ua.Variant(int(r.integers(-9, 9)), ua.VariantType.Int16))  # fmt: skip


async def _session_case(kind: str, rng: np.random.Generator, client: AssetClient,
                        writable: list[tuple[str, str]], methods: list[str]) -> str:  # fmt: skip
    """One case through a real session; returns the status name the server answered."""
    ns = client._ns if client._ns is not None else 2
    try:
        if kind == "bad_node_id":
            node = client.client.get_node(_bad_node_id(rng, ns))
            value = (await node.read_attribute(ua.AttributeIds.Value)).StatusCode
            return value.name
        if kind == "wrong_type_write":
            sm, prop = writable[int(rng.integers(0, len(writable)))]
            node = await client._node(sm, prop)
            await node.write_value(ua.DataValue(_WRONG[int(rng.integers(0, len(_WRONG)))](rng)))
            return "Good"
        op = methods[int(rng.integers(0, len(methods)))]
        args = [_WRONG[int(rng.integers(0, len(_WRONG)))](rng)
                for _ in range(int(rng.integers(0, 5)))]  # fmt: skip
        await client.call(op, *args)
        return "Good"
    except ua.UaStatusCodeError as exc:
        return ua.StatusCode(exc.code).name


async def fuzz(
    endpoint: str,
    session: Any,
    *,
    asset_id: str,
    seed: int,
    count: int,
    writable: list[tuple[str, str]],
    methods: list[str],
    check_every: int = 50,
    wait_s: float = 0.5,
) -> FuzzReport:
    """Send `count` malformed or invalid requests to a loopback server; check it serves.

    Args:
        endpoint: The server (loopback only).
        session: Zero-argument callable returning an async context manager that yields an
            operator `AssetClient` (a fresh secure session).
        asset_id: The served asset (the liveness check reads its Identification.AssetId).
        seed: Seed of every random choice.
        count: Number of cases (bounded).
        writable: (submodel, property) pairs the operator may write (wrong-type targets).
        methods: Operations of the ControlInterface submodel (wrong-argument targets).
        check_every: Cases between liveness checks.
        wait_s: How long to wait for the server's reaction to raw traffic.

    Raises:
        AssertionError: A liveness check did not read the asset id back (the server broke).
    """
    host, port = _loopback(endpoint)
    rng = np.random.default_rng(seed)
    hello, opn = _hello(endpoint), _open_request()
    cases: Counter[str] = Counter()
    outcomes: Counter[str] = Counter()
    alive = 0
    t0 = time.monotonic()

    async def check() -> None:
        nonlocal alive
        async with session() as s:
            got = await s.read("Identification", "AssetId")
        if got != asset_id:
            raise AssertionError(f"liveness check read {got!r}, not {asset_id!r}")
        alive += 1

    async with session() as live:
        for i in range(count):
            kind = KINDS[int(rng.integers(0, len(KINDS)))]
            cases[kind] += 1
            if kind == "random_bytes":
                out = await _raw(host, port, [rng.bytes(int(rng.integers(1, 4096)))], wait_s)
            elif kind == "truncated_hello":
                out = await _raw(host, port, [hello[: int(rng.integers(1, len(hello)))]], wait_s)
            elif kind == "mutated_hello":
                out = await _raw(host, port, [_mutate(rng, hello)], wait_s)
            elif kind == "truncated_open":
                cut = opn[: int(rng.integers(1, len(opn)))]
                out = await _raw(host, port, [hello, cut], wait_s)
            elif kind == "mutated_open":
                out = await _raw(host, port, [hello, _mutate(rng, opn)], wait_s)
            elif kind == "sessionless_request":
                out = await _raw(host, port, [hello, opn, _session_request(rng)], wait_s)
            else:
                out = await _session_case(kind, rng, live, writable, methods)
            outcomes[f"{kind}:{out}"] += 1
            if (i + 1) % check_every == 0:
                await check()
    await check()
    return FuzzReport(dict(cases), dict(outcomes), alive, time.monotonic() - t0)
