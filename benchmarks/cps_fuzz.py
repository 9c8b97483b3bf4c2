"""Fuzz an asset server on loopback (issue 13, item 3): malformed and invalid requests.

TU_A's server runs in a child process; this process sends `--count` cases drawn with
`--seed` (random bytes, truncated/mutated Hello and OpenSecureChannel messages, requests
without a session, bad node ids, writes of the wrong type, calls with wrong arguments) and
opens a fresh secure session every 50 cases to check the server still answers. Prints the
cases per kind, what the server did, the liveness checks passed, cases/s and the server's
RSS before and after; baseline in the same run: the time of a liveness check alone.

    PYTHONPATH=src .venv/bin/python benchmarks/cps_fuzz.py [--seed 1] [--count 2000]
"""

from __future__ import annotations

import argparse
import asyncio
import time
from collections import Counter

from _cps_server import ChildServer
from _stress import fuzz
from transfertwin.cps.aas._demo import demo_descriptors
from transfertwin.cps.aas._representation import build_representation, externally_synced
from transfertwin.cps.opcua import connect


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--count", type=int, default=2000)
    args = parser.parse_args()
    rep = build_representation(next(d for d in demo_descriptors() if d.asset_id == "TU_A"))
    writable = sorted(("OperationalData", p) for p in externally_synced(rep))
    methods = [e.id_short for e in rep.submodel("ControlInterface").submodel_element
               if type(e).__name__ == "Operation"]  # fmt: skip
    server = ChildServer()
    try:

        def session():
            return connect(server.endpoint, "TU_A", role="operator", timeout_s=30,
                           credentials=server.creds, cert_dir=server.cert_dir)  # fmt: skip

        async def run():
            t0 = time.perf_counter()
            async with session() as s:
                await s.read("Identification", "AssetId")
            check_s = time.perf_counter() - t0
            rss0 = server.ask("reset")
            report = await fuzz(server.endpoint, session, asset_id="TU_A", seed=args.seed,
                                count=args.count, writable=writable, methods=methods)  # fmt: skip
            return check_s, rss0, report

        check_s, rss0, report = asyncio.run(run())
        _, rss1, _ = server.ask(("check", 0))
        alive = server.proc.is_alive()
    finally:
        server.close()
    print(f"seed {args.seed}: {args.count} cases in {report.seconds:.1f} s "
          f"({args.count / report.seconds:.1f} cases/s)")  # fmt: skip
    by_kind: dict[str, Counter] = {}
    for key, n in report.outcomes.items():
        kind, outcome = key.split(":")
        by_kind.setdefault(kind, Counter())[outcome] += n
    for kind, n in sorted(report.cases.items()):
        print(f"  {kind:20s} {n:5d}  " + ", ".join(f"{o} {c}" for o, c in
                                                   by_kind[kind].most_common()))  # fmt: skip
    print(f"liveness checks    : {report.alive_checks} passed; server process alive: {alive}")
    print(f"server RSS         : {rss0 / 1024:.1f} MiB before, {rss1 / 1024:.1f} MiB after")
    print(f"baseline           : one liveness check alone {check_s * 1000:.0f} ms; fuzz "
          f"{report.seconds / args.count * 1000:.0f} ms per case "
          f"({report.seconds / args.count / check_s:.2f}x)")  # fmt: skip


if __name__ == "__main__":
    main()
