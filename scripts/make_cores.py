"""Generate the built-in starter-motor cores o1..o37 as package data.

Writes ``src/transfertwin/data/cores/oN.stl`` (binary STL, metres, frame F_O),
``oN.hulls.npz`` (CoACD convex hulls) and ``manifest.json`` (spec, mass and
SHA-256 of every file). The meshes are deterministic; CoACD is not, so hulls
are computed once and kept on later runs as long as the STL hash and the CoACD
parameters are unchanged (``--force`` recomputes them).

Usage (with the package installed, or ``PYTHONPATH=src``)::

    .venv/bin/python scripts/make_cores.py [--jobs 2] [--only 1 5] [--force]

All 37 cores take about 5 minutes with 2 worker processes (CoACD 9–46 s per
core at threshold 0.05, at most 24 hulls).
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import logging
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from importlib import metadata
from pathlib import Path

import numpy as np

from transfertwin._atomic import write_bytes_atomic
from transfertwin.objects._builtin import MANIFEST_NAME
from transfertwin.objects._core_draw import core_spec
from transfertwin.objects._core_spec import BUILTIN_COUNT
from transfertwin.objects._cores import core_stl_bytes, mesh_from_stl_bytes
from transfertwin.objects._hulls import coacd_hulls, coacd_params, hulls_to_npz_bytes

logger = logging.getLogger("make_cores")

DEFAULT_OUT = Path(__file__).resolve().parents[1] / "src" / "transfertwin" / "data" / "cores"
FORMAT_VERSION = 1


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def make_core(index: int, params: dict, out_dir: Path, previous: dict | None, force: bool) -> dict:
    """Write one core's STL (and hulls unless reusable); return its manifest entry."""
    spec = core_spec(index)
    stl = core_stl_bytes(index)
    stl_sha = _sha256(stl)
    name = spec.object_id
    mesh = mesh_from_stl_bytes(stl, f"{name}.stl")
    if not (mesh.is_watertight and mesh.is_volume):
        raise RuntimeError(f"{name}: generated mesh is not a closed volume")
    write_bytes_atomic(out_dir / f"{name}.stl", stl)
    hull_path = out_dir / f"{name}.hulls.npz"
    reusable = (
        not force
        and previous is not None
        and previous.get("stl_sha256") == stl_sha
        and previous.get("coacd") == params
        and hull_path.is_file()
        and _sha256(hull_path.read_bytes()) == previous.get("hulls_sha256")
    )
    if reusable:
        n_hulls, seconds = previous["n_hulls"], previous["coacd_seconds"]
        logger.info("%s: STL unchanged, keeping %d hulls", name, n_hulls)
    else:
        start = time.perf_counter()
        hulls = coacd_hulls(mesh, params)
        seconds = round(time.perf_counter() - start, 1)
        n_hulls = len(hulls)
        meta = {"object_id": name, "stl_sha256": stl_sha, "coacd": params}
        write_bytes_atomic(hull_path, hulls_to_npz_bytes(hulls, meta))
        logger.info("%s: %d faces, %d hulls in %.1f s", name, len(mesh.faces), n_hulls, seconds)
    extents = mesh.extents
    return {
        "index": index,
        "spec": dataclasses.asdict(spec),
        "wear": list(spec.wear),
        "mass_kg": spec.mass_kg,
        "volume_m3": round(float(mesh.volume), 9),
        "extents_m": [round(float(v), 6) for v in extents],
        "n_faces": len(mesh.faces),
        "stl": f"{name}.stl",
        "stl_sha256": stl_sha,
        "hulls": hull_path.name,
        "hulls_sha256": _sha256(hull_path.read_bytes()),
        "n_hulls": n_hulls,
        "n_hull_vertices": _hull_vertex_count(hull_path),
        "coacd": params,
        "coacd_seconds": seconds,
    }


def _hull_vertex_count(path: Path) -> int:
    with np.load(path, allow_pickle=False) as npz:
        return int(sum(len(npz[n]) for n in npz.files if n.startswith("hull_")))


def _parse_args(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="output directory")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes")
    parser.add_argument("--threshold", type=float, default=0.05, help="CoACD concavity threshold")
    parser.add_argument("--max-hulls", type=int, default=24, help="CoACD max_convex_hull")
    parser.add_argument("--seed", type=int, default=0, help="CoACD seed")
    parser.add_argument("--only", type=int, nargs="+", help="core indices to (re)make")
    parser.add_argument("--force", action="store_true", help="recompute hulls even if unchanged")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    """Generate the cores; returns the exit code."""
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    args = _parse_args(sys.argv[1:] if argv is None else argv)
    os.environ.setdefault("OMP_NUM_THREADS", "1")  # one CoACD thread per worker process
    params = coacd_params(args.threshold, args.max_hulls, args.seed)
    args.out.mkdir(parents=True, exist_ok=True)
    manifest_path = args.out / MANIFEST_NAME
    old = json.loads(manifest_path.read_text()) if manifest_path.is_file() else {"cores": {}}
    indices = args.only or list(range(1, BUILTIN_COUNT + 1))
    start = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        futures = {
            i: pool.submit(make_core, i, params, args.out, old["cores"].get(f"o{i}"), args.force)
            for i in indices
        }
        entries = {f"o{i}": future.result() for i, future in futures.items()}
    cores = {**old["cores"], **entries}
    manifest = {
        "format_version": FORMAT_VERSION,
        "generator": "scripts/make_cores.py",
        "units": "m",
        "frame": "F_O: +x to the pinion, +y away from the solenoid, +z up on face 'front', "
        "origin at the centre of mass",
        "versions": {p: metadata.version(p) for p in ("coacd", "manifold3d", "numpy", "trimesh")},
        "cores": dict(sorted(cores.items(), key=lambda kv: kv[1]["index"])),
    }
    text = json.dumps(manifest, indent=1, sort_keys=False) + "\n"
    write_bytes_atomic(manifest_path, text.encode())
    logger.info("%d cores in %.0f s -> %s", len(entries), time.perf_counter() - start, args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
