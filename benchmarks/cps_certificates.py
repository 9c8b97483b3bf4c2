"""How long a process floor's trust lists take to prepare: every one of N assets trusts
every asset's client certificate (and the command-line clients'), one trust folder per
asset process (docs/scaling.md).

    PYTHONPATH=src .venv/bin/python benchmarks/cps_certificates.py --assets 50

It makes N application certificates once (`ensure_certificate`, one RSA key each: printed
as the key time, the same for both ways), then fills N + 1 fresh trust folders with the
N + 2 certificates two ways, in the same run:

- baseline: `trust_certificate` per folder and certificate, as `cps up` did (each file
  written atomically with its own fsync: (N + 1)(N + 2) fsynced files);
- now: `trust_certificates` (`cps up` since): each certificate written once, hard-linked
  into the other folders, one directory sync per folder.

Both ways are checked to give every folder the same list (`TrustList`). Prints the seconds
of each and the ratio; the host may be shared, so the load average is printed too.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import tempfile
import time
from pathlib import Path

from transfertwin.cps.opcua import (
    TrustList,
    ensure_certificate,
    read_certificate,
    trust_certificate,
    trust_certificates,
)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--assets", type=int, default=50, help="asset processes (default 50)")
    args = ap.parse_args()
    if args.assets < 1:
        ap.error("--assets must be at least 1")
    n = args.assets
    with tempfile.TemporaryDirectory(prefix="cps-certs-", dir=os.environ.get("TMPDIR")) as tmp:
        base = Path(tmp)
        t0 = time.perf_counter()
        paths = [asyncio.run(ensure_certificate(base / "clients", f"client-{r}"))[0]
                 for r in ("viewer", "operator")]  # fmt: skip
        paths += [asyncio.run(ensure_certificate(base / f"a{i}" / "certs", "client-operator"))[0]
                  for i in range(n)]  # fmt: skip
        keys_s = time.perf_counter() - t0
        certs = [read_certificate(p) for p in paths]  # as the launcher holds them

        def folders(way: str) -> list[Path]:
            return [base / way / "certs" / "trusted",
                    *(base / way / f"a{i}" / "trusted" for i in range(n))]  # fmt: skip

        t0 = time.perf_counter()
        for folder in folders("baseline"):
            for cert in certs:
                trust_certificate(folder, cert)
        baseline_s = time.perf_counter() - t0
        t0 = time.perf_counter()
        added = trust_certificates(folders("now"), certs)
        now_s = time.perf_counter() - t0
        files = (n + 1) * (n + 2)
        assert added == files, (added, files)
        ders = [p.read_bytes() for p in paths]
        for old, new in zip(folders("baseline"), folders("now"), strict=True):
            assert sorted(os.listdir(old)) == sorted(os.listdir(new))
            assert all(TrustList(new).is_trusted(d) for d in ders)
    load = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    print(f"{n} assets: {n + 1} trust folders x {n + 2} certificates = {files} files "
          f"(load average {load})")  # fmt: skip
    print(f"  keys (once, both ways):          {keys_s:8.2f} s ({keys_s / (n + 2) * 1e3:.0f} ms "
          f"per certificate)")  # fmt: skip
    print(f"  baseline (a fsynced file each):  {baseline_s:8.2f} s "
          f"({baseline_s / files * 1e3:.2f} ms per file)")  # fmt: skip
    print(f"  now (written once, hard links):  {now_s:8.2f} s ({now_s / files * 1e3:.3f} ms "
          f"per file)")  # fmt: skip
    print(f"  ratio baseline / now: {baseline_s / now_s:.0f}x")


if __name__ == "__main__":
    main()
