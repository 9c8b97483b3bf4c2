"""CPS load on loopback: 1,000 writes/s to one asset for 30 s (issue 13, item 3).

TU_A's OPC UA server (Basic256Sha256 SignAndEncrypt, trust list, operator session) runs in
a child process; this process writes 0, 1, 2, ... to OperationalData.PossessedObjects, one
WriteRequest each, paced and pipelined. The server logs every write it applies; the run
prints writes/s achieved, lost, duplicated and reordered writes, and the server's RSS before
and after. Baseline in the same run: the same writes one at a time (each waits for its
answer) for a few seconds, i.e. what a client that does not pipeline gets.

    PYTHONPATH=src .venv/bin/python benchmarks/cps_load.py [--rate 1000] [--seconds 30]
"""

from __future__ import annotations

import argparse
import asyncio
import time

from _cps_server import PROP, ChildServer
from _stress import paced_writes
from transfertwin.cps.opcua import connect


async def _sequential(op, seconds: float) -> float:
    t0, k = time.perf_counter(), 0
    while time.perf_counter() - t0 < seconds:
        await op.write(*PROP, str(k))
        k += 1
    return k / (time.perf_counter() - t0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rate", type=float, default=1000.0, help="writes/s aimed at")
    parser.add_argument("--seconds", type=float, default=30.0)
    parser.add_argument("--baseline-seconds", type=float, default=3.0)
    args = parser.parse_args()
    server = ChildServer()
    try:

        async def run():
            kw = {"credentials": server.creds, "cert_dir": server.cert_dir}
            async with connect(server.endpoint, "TU_A", role="operator", timeout_s=60, **kw) as op:
                seq = await _sequential(op, args.baseline_seconds)
                await paced_writes(op, *PROP, rate_hz=args.rate, duration_s=1.0)  # warm-up
                rss0 = server.ask("reset")
                sent, elapsed = await paced_writes(
                    op, *PROP, rate_hz=args.rate, duration_s=args.seconds,
                    on_second=lambda t, n: print(f"  {t:5.1f} s: {n} sent", flush=True)
                    if int(t) % 10 == 0 else None,
                )  # fmt: skip
                return seq, rss0, sent, elapsed

        seq, rss0, sent, elapsed = asyncio.run(run())
        check, rss1, final = server.ask(("check", sent))
    finally:
        server.close()
    rate = sent / elapsed
    print(f"target             : {args.rate:.0f} writes/s for {args.seconds:g} s ({sent} writes)")
    print(f"achieved           : {rate:8.1f} writes/s ({elapsed:.2f} s to the last answer)")
    print(f"applied by server  : {check.applied}  lost {check.lost}  duplicated "
          f"{check.duplicated}  reordered {check.reordered}  (final value {final})")  # fmt: skip
    print(f"server RSS         : {rss0 / 1024:.1f} MiB before, {rss1 / 1024:.1f} MiB after "
          f"({(rss1 - rss0) / 1024:+.1f} MiB)")  # fmt: skip
    print(f"baseline sequential: {seq:8.1f} writes/s (one at a time); achieved/baseline "
          f"{rate / seq:.2f}x")  # fmt: skip


if __name__ == "__main__":
    main()
