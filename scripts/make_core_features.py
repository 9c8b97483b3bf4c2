"""Write the built-in cores' resting features (``src/transfertwin/data/cores/features.json``).

The cores with real experiments take the protrusions of their calibrated proxies (made by
``transfertwin calibrate object --object oN --out DIR``); every other core draws its features
from the family prior (`transfertwin.objects.prior_features`, seeded by the core index).

Usage (with the package installed, or ``PYTHONPATH=src``)::

    .venv/bin/python scripts/make_core_features.py --calibrated DIR [--out FILE]

``DIR`` holds ``oN.proxy.json`` files; ``--command`` records how they were made.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from transfertwin._atomic import write_atomic
from transfertwin.objects import builtin_ids, features_document, is_builtin_id, read_proxy

DEFAULT_OUT = (
    Path(__file__).resolve().parents[1] / "src" / "transfertwin" / "data" / "cores"
    / "features.json"
)  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calibrated", type=Path, required=True,
                        help="folder of calibrated oN.proxy.json files")  # fmt: skip
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    parser.add_argument("--command", default="", help="how the proxies were made (recorded)")
    args = parser.parse_args(argv)
    calibrated = {}
    for path in sorted(args.calibrated.glob("o*.proxy.json")):
        spec = read_proxy(path)
        if not is_builtin_id(spec.base) or spec.base != spec.object_id:
            print(f"{path}: not a proxy of a built-in core, skipped", file=sys.stderr)
            continue
        calibrated[spec.object_id] = spec.protrusions
    if not calibrated:
        print(f"{args.calibrated}: no calibrated proxies of built-in cores", file=sys.stderr)
        return 2
    note = (
        "Resting features of the built-in cores: calibrated proxies for "
        + ", ".join(sorted(calibrated, key=lambda k: int(k[1:])))
        + "; the family prior (calibrated faces resampled, seeded by core index) for the rest."
        + (f" Calibrated with: {args.command}" if args.command else "")
    )
    doc = features_document(calibrated, builtin_ids(), note=note)
    write_atomic(args.out, json.dumps(doc, indent=1) + "\n")
    print(f"wrote {args.out} ({len(calibrated)} calibrated, "
          f"{len(doc['cores']) - len(calibrated)} from the prior)")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
