"""How long a process floor's credentials take to prepare, two ways in one run (docs/scaling.md,
docs/security.md "Floor CA"):

    PYTHONPATH=src .venv/bin/python benchmarks/cps_certificates.py --assets 200

- pinned (the way before the floor CA, its code kept here): one self-signed application
  certificate per asset and command-line client (`ensure_certificate`, one RSA key each,
  one after the other), then every certificate on every asset's trust list (N + 1 folders
  x N + 2 certificates, each written once and hard-linked into the others:
  `trust_certificates`);
- CA (what ``cps up`` does now: `transfertwin.cps._pki.prepare_certificates`): the floor's
  CA, each asset's own key and signing request (made in parallel, one process per core,
  while the main process makes the CA's key and signs each request as it comes back), and
  in every trust folder the CA certificate and its CRL only.

Both results are checked: every pinned folder trusts every certificate, and every CA trust
folder trusts every asset's certificate (`TrustList`, chain and CRL). Prints the seconds of
each (wall clock, and the CPU seconds of the process and its workers: on a shared host the
wall clock grows with the others' load, the CPU seconds do not, and CPU / cores is what the
wall clock would be on idle cores), the files in the trust folders and the ratios; the load
average is printed too. ``--cores 0,1`` pins the run (workers included) to those cores.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import tempfile
import time
from pathlib import Path

from transfertwin.cps._pki import prepare_certificates
from transfertwin.cps.floor import AssetConfig
from transfertwin.cps.opcua import (
    ROLES,
    TrustList,
    ensure_certificate,
    read_certificate,
    trust_certificates,
)


def _cpu() -> float:
    """CPU seconds of this process and its reaped children (the CA's workers) so far."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def pinned(base: Path, n: int) -> tuple[float, float, int]:
    """The way before the CA: (key seconds, trust list seconds, files in the lists)."""
    t0 = time.perf_counter()
    paths = [asyncio.run(ensure_certificate(base / "certs", f"client-{r}"))[0] for r in ROLES]
    paths += [asyncio.run(ensure_certificate(base / f"a{i}" / "certs", "client-operator"))[0]
              for i in range(n)]  # fmt: skip
    keys_s = time.perf_counter() - t0
    certs = [read_certificate(p) for p in paths]
    folders = [base / "certs" / "trusted", *(base / f"a{i}" / "trusted" for i in range(n))]
    t0 = time.perf_counter()
    added = trust_certificates(folders, certs)
    lists_s = time.perf_counter() - t0
    ders = [p.read_bytes() for p in paths]
    for folder in (folders[0], folders[-1]):
        assert all(TrustList(folder).is_trusted(d) for d in ders)
    return keys_s, lists_s, added


def with_ca(base: Path, n: int) -> tuple[float, int]:
    """The floor CA: (seconds for everything, files in the trust folders)."""
    configs = [AssetConfig(asset_id=f"a{i}", floor_file=base / "floor.toml",
                           host=f"127.0.{1 + i // 250}.{2 + i % 250}", port=4840, seeds=(),
                           cert_dir=base / f"a{i}" / "certs", trust_dir=base / f"a{i}" / "trusted",
                           credentials_file=base / "credentials.json",
                           state_dir=base / f"a{i}" / "state")
               for i in range(n)]  # fmt: skip
    t0 = time.perf_counter()
    prepare_certificates(base, configs)
    total_s = time.perf_counter() - t0
    files = sum(len(os.listdir(c.trust_dir)) for c in configs)
    files += len(os.listdir(base / "certs" / "trusted"))
    for cfg in (configs[0], configs[-1]):
        trust = TrustList(cfg.trust_dir)
        assert all(trust.is_trusted((c.cert_dir / f"{c.asset_id}.der").read_bytes())
                   for c in configs)  # fmt: skip
    return total_s, files


def compare(n: int) -> list[str]:
    """Prepare `n` assets' credentials both ways (in a temporary folder) and say how long
    each took, in lines (also `benchmarks/cps_scale.py --credentials`)."""
    cores = len(os.sched_getaffinity(0))
    with tempfile.TemporaryDirectory(prefix="cps-certs-", dir=os.environ.get("TMPDIR")) as tmp:
        c0 = _cpu()
        keys_s, lists_s, files = pinned(Path(tmp) / "pinned", n)
        c1 = _cpu()
        ca_s, ca_files = with_ca(Path(tmp) / "ca", n)
        c2 = _cpu()
    load = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    old_s, old_cpu, ca_cpu = keys_s + lists_s, c1 - c0, c2 - c1
    return [
        f"{n} assets, {cores} cores (load average {load})",
        f"  pinned, hard-linked lists: {old_s:8.2f} s, CPU {old_cpu:6.2f} s (keys "
        f"{keys_s:.2f} s, trust lists {lists_s:.2f} s; {files} files in {n + 1} trust "
        "folders)",
        f"  floor CA:                  {ca_s:8.2f} s, CPU {ca_cpu:6.2f} s (CA, {n + 2} keys "
        f"and requests, signing, CA + CRL copied; {ca_files} files in {n + 1} trust "
        "folders)",
        f"  ratio pinned / CA: {old_s / ca_s:.1f}x wall clock, {old_cpu / ca_cpu:.1f}x CPU; "
        f"CA on {cores} idle cores: ~{ca_cpu / cores:.1f} s",
    ]  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--assets", type=int, default=50, help="asset processes (default 50)")
    ap.add_argument("--cores", default="", help="run on these cores only, e.g. 0,1")
    args = ap.parse_args()
    if args.assets < 1:
        ap.error("--assets must be at least 1")
    if args.cores:
        try:
            os.sched_setaffinity(0, {int(c) for c in args.cores.split(",")})
        except (ValueError, OSError) as exc:
            ap.error(f"--cores {args.cores}: {exc}")
    print("\n".join(compare(args.assets)))


if __name__ == "__main__":
    main()
