"""`transfertwin cps up|status|order`: the demo cyber-physical system on loopback."""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
import signal
from pathlib import Path

from transfertwin._errors import InputError
from transfertwin.cli._paths import out_dir

__all__ = ["register"]


def _workdir(path: str, must_exist: bool) -> Path:
    if not must_exist:
        return out_dir(path)
    wd = Path(path)
    if not (wd / "cps.json").is_file():
        raise InputError(f"{path}: the CPS is not running (no cps.json); start it with "
                         "'transfertwin cps up'")  # fmt: skip
    return wd


def _run_client(wd: Path, coro_fn):
    """Run a client coroutine; a CPS that does not answer is reported in one line."""
    try:
        return asyncio.run(coro_fn())
    except (TimeoutError, ConnectionError, OSError) as exc:
        raise InputError(
            f"{wd}: the CPS is not running or not answering "
            f"({type(exc).__name__}); start it with 'transfertwin cps up'"
        ) from None


def _load(wd: Path) -> tuple[dict, object]:
    from transfertwin.cps.opcua import load_credentials

    info = json.loads((wd / "cps.json").read_text())
    creds = None if info.get("insecure") else load_credentials(Path(info["credentials_file"]))
    return info, creds


def _endpoint(info: dict, asset_id: str) -> str:
    for a in info["assets"]:
        if a["id"] == asset_id:
            return a["endpoint"]
    raise InputError(f"no asset {asset_id!r} in the CPS")


def cmd_up(args: argparse.Namespace) -> int:
    """Start the demo CPS and serve until SIGINT/SIGTERM."""
    from transfertwin.cps import Cps, CpsConfig
    from transfertwin.study.experiment import load_profile

    wd = _workdir(args.workdir, must_exist=False)
    wd.mkdir(parents=True, exist_ok=True)
    scene = load_profile(args.config)[1] if args.config else None
    kwargs = {"scene": scene} if scene is not None else {}
    cfg = CpsConfig(wd, host=args.host, insecure=args.insecure, time_scale=args.time_scale,
                    seed=args.seed, **kwargs)  # fmt: skip
    handler = logging.FileHandler(wd / "cps.log")
    handler.setFormatter(logging.Formatter("%(asctime)s %(message)s"))
    logging.getLogger("transfertwin.cps").addHandler(handler)
    logging.getLogger("transfertwin.cps").setLevel(logging.INFO)

    async def serve() -> None:
        stop = asyncio.Event()
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, stop.set)
        async with Cps(cfg) as cps:
            print(f"CPS up: {len(cps.assets)} assets; {wd / 'cps.json'}", flush=True)
            await stop.wait()
        print("CPS down", flush=True)

    asyncio.run(serve())
    return 0


def cmd_status(args: argparse.Namespace) -> int:
    """List the assets as the knowledge graph knows them."""
    from rich.console import Console
    from rich.table import Table

    from transfertwin.cps.opcua import connect

    wd = _workdir(args.workdir, must_exist=True)
    info, creds = _load(wd)

    async def ask() -> list[dict]:
        async with connect(
            _endpoint(info, "KG"),
            "KG",
            credentials=creds,
            cert_dir=Path(info["cert_dir"]),
            insecure=info["insecure"],
        ) as kg:
            return json.loads(await kg.call("Query", _ASSETS_QUERY))  # fmt: skip

    rows = _run_client(wd, ask)
    table = Table(title="assets in the knowledge graph")
    for col in ("id", "class", "type", "status", "state", "endpoint"):
        table.add_column(col)
    for r in rows:
        table.add_row(*(str(r.get(c, "") or "") for c in ("id", "class", "type", "status",
                                                          "state", "endpoint")))  # fmt: skip
    Console().print(table)
    return 0


_ASSETS_QUERY = """
PREFIX tt: <https://transfertwin.dev/ontology#>
SELECT ?id (GROUP_CONCAT(DISTINCT ?cls; separator="/") AS ?class) (SAMPLE(?t) AS ?type)
       (SAMPLE(?st) AS ?status) (SAMPLE(?os) AS ?state) (SAMPLE(?ep) AS ?endpoint) WHERE {
  ?a tt:assetId ?id .
  OPTIONAL { ?a a ?c . FILTER(STRSTARTS(STR(?c), STR(tt:))) BIND(STRAFTER(STR(?c), "#") AS ?cls) }
  OPTIONAL { ?a tt:assetType ?at . BIND(STRAFTER(STR(?at), "#") AS ?t) }
  OPTIONAL { ?a tt:status ?st }
  OPTIONAL { ?a tt:operationalState ?os }
  OPTIONAL { ?a tt:endpoint ?ep }
} GROUP BY ?id ORDER BY ?id
"""


def cmd_order(args: argparse.Namespace) -> int:
    """Submit a transport operation to the TMS and follow it to its end."""
    from transfertwin.cps.opcua import connect

    wd = _workdir(args.workdir, must_exist=True)
    info, creds = _load(wd)

    async def order() -> str:
        async with connect(_endpoint(info, "TMS"), "TMS", credentials=creds,
                           cert_dir=Path(info["cert_dir"]), insecure=info["insecure"],
                           timeout_s=60) as tms:  # fmt: skip
            before = await tms.read("OperationalData", "CompletedOperations")
            done = asyncio.Event()

            class Watch:
                def datachange_notification(self, node, val, data) -> None:
                    if val > before:
                        done.set()

                def status_change_notification(self, status) -> None:
                    done.set()

            await tms.subscribe(Watch(), ("OperationalData", "CompletedOperations"))
            op = await tms.call("SubmitTransportOperation", args.source, args.target, args.object)
            print(f"submitted {op}: {args.object} {args.source} -> {args.target}", flush=True)
            await asyncio.wait_for(done.wait(), timeout=args.timeout)
            return op

    op = _run_client(wd, order)
    log = (wd / "cps.log").read_text().splitlines() if (wd / "cps.log").exists() else []
    start = min((i for i, line in enumerate(log) if f"TMS: {op} " in line), default=0)
    for line in log[start:]:
        print(line)
        if f"TMS: {op} finished" in line:
            break
    return 0


def cmd_export(args: argparse.Namespace) -> int:
    """Write the demo assets' AAS (and their physical twins') as JSON, XML or AASX."""
    from transfertwin.cps import (
        build_representation,
        demo_descriptors,
        export_aas,
        physical_twin,
        validate_export,
    )
    from transfertwin.cps.aas import AssetKind

    descs = list(demo_descriptors())
    if args.with_physical:
        descs += [physical_twin(d) for d in descs if d.kind is AssetKind.VIRTUAL_MODEL]
    path = export_aas([build_representation(d) for d in descs], Path(args.out))
    print(f"{path}: {validate_export(path)} identifiables, valid")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add `cps up|status|order` to the CLI."""
    cps = sub.add_parser("cps", help="demo cyber-physical system on loopback (Ch. 3, Sec. 5.3)")
    csub = cps.add_subparsers(dest="cps_command", required=True, parser_class=type(cps))
    p = csub.add_parser("up", help="start TU_A..TU_D, TM_1, objects, KG and logical assets")
    p.add_argument("--workdir", required=True)
    p.add_argument("--config", help="physics profile TOML of the virtual models")
    p.add_argument("--host", default="127.0.0.1", help="interface to bind (default loopback)")
    p.add_argument("--insecure", action="store_true", help="serve NoSecurity (explicit opt-in)")
    p.add_argument("--time-scale", type=float, default=1.0,
                   help="simulated seconds per wall second (0: as fast as possible)")  # fmt: skip
    p.add_argument("--seed", type=int, default=0)
    p.set_defaults(func=cmd_up)
    p = csub.add_parser("status", help="list the assets from the knowledge graph")
    p.add_argument("--workdir", required=True)
    p.set_defaults(func=cmd_status)
    p = csub.add_parser("order", help="run a transport operation end to end over OPC UA")
    p.add_argument("--workdir", required=True)
    p.add_argument("--from", dest="source", required=True)
    p.add_argument("--to", dest="target", required=True)
    p.add_argument("--object", required=True)
    p.add_argument("--timeout", type=float, default=600.0)
    p.set_defaults(func=cmd_order)
    p = csub.add_parser("export", help="write the demo assets' AAS as JSON, XML or AASX")
    p.add_argument("--out", required=True, help="FILE.json, FILE.xml or FILE.aasx")
    p.add_argument("--with-physical", action="store_true",
                   help="also the physical twins (TU_A_P, ...) of the virtual models")  # fmt: skip
    p.set_defaults(func=cmd_export)
