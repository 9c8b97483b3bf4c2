"""`transfertwin cps up|status|order|trust|experiment|export`: a floor of assets on loopback
(the demo floor or a floor file), optionally on an emulated plant (`cps up --plant-seed`)."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from transfertwin._errors import InputError
from transfertwin.cli._cps_ca import register_ca
from transfertwin.cli._cps_campaign import register as register_campaign
from transfertwin.cli._cps_client import (
    add_access,
    endpoint_of,
    floor_access,
    load_info,
    run_client,
    workdir_of,
)
from transfertwin.cli._cps_floor import (
    cmd_up_floor,
    cmd_up_local,
    floor_document,
    floor_order,
    print_floor_status,
)
from transfertwin.cli._cps_floor import register as register_floor
from transfertwin.cli._cps_study import register as register_study
from transfertwin.cli._cps_supervise import register as register_supervise

__all__ = ["register"]


def cmd_up(args: argparse.Namespace) -> int:
    """Start a floor (the built-in one or `--floor`) and serve until SIGINT/SIGTERM: one
    process per asset (`_cps_floor.cmd_up_floor`), or every asset's node in this process
    with `--single-process` (`_cps_floor.cmd_up_local`); the same nodes either way."""
    if args.floor is None:
        args.floor = "demo"
    return cmd_up_local(args) if args.single_process else cmd_up_floor(args)


def cmd_status(args: argparse.Namespace) -> int:
    """List the assets as the knowledge graph knows them, with where each object is and
    where each transport module stands on the shop floor (and the unit it is docked at)."""
    doc = floor_document(*floor_access(args))
    if args.json:
        print(json.dumps(doc, indent=2))
    else:
        print_floor_status(doc)
    return 0


def cmd_order(args: argparse.Namespace) -> int:
    """Submit a transport operation to the TMS and follow it to its end.

    A refused order (checked here first, then by the TMS against where the objects are)
    exits 2 with the reason at once. A transport that fails physically is an outcome, not
    an error: it is printed with the step and the reason, and the exit code is 3.
    """
    if not 0 < args.timeout < float("inf"):
        raise InputError(f"--timeout must be a positive number of seconds, got {args.timeout}")
    return floor_order(*floor_access(args), args)


def cmd_trust(args: argparse.Namespace) -> int:
    """Put a client certificate on the trust list of the CPS's OPC UA servers.

    The servers read the list on every new session: a running CPS accepts the client at
    once. The list is ``WORKDIR/certs/trusted`` (created by the first ``cps up``); on a
    floor with one process per asset every asset has its own list
    (``WORKDIR/assets/<id>/trusted``): the certificate goes on all of them, or with
    ``--asset`` on that asset's only. With ``--gateway --asset ID`` the certificate is a
    HAL gateway's, trusted by that asset as its gateway (`_trust_gateway`).
    """
    from cryptography.hazmat.primitives import hashes

    from transfertwin.cps.opcua import read_certificate, trust_certificate, trust_certificates

    wd = Path(args.workdir)
    if not ((wd / "cps.json").is_file() or (wd / "certs").is_dir()):
        raise InputError(f"--workdir {args.workdir}: no CPS there (no cps.json, no certs/); "
                         "start one with 'transfertwin cps up --workdir DIR'")  # fmt: skip
    try:
        cert = read_certificate(Path(args.cert))
    except ValueError as exc:
        raise InputError(str(exc)) from None
    if args.gateway:
        return _trust_gateway(wd, args.asset, cert)
    per_asset = sorted(p for p in (wd / "assets").glob("*/trusted") if p.is_dir())
    if args.asset is not None:
        per_asset = [p for p in per_asset if p.parent.name == args.asset]
        if not per_asset:
            raise InputError(f"--asset {args.asset}: no such asset process in {wd}/assets")
        folders = per_asset
    else:
        folders = [wd / "certs" / "trusted", *per_asset]
    if len(folders) == 1:
        where = trust_certificate(folders[0], cert)
    else:  # written once, hard-linked into the others
        trust_certificates(folders, [cert])
        where = f"{len(folders)} trust lists ({wd})"
    print(f"trusted {cert.subject.rfc4514_string()} "
          f"(SHA-256 {cert.fingerprint(hashes.SHA256()).hex()[:16]}...): {where}")  # fmt: skip
    info = json.loads((wd / "cps.json").read_text()) if (wd / "cps.json").is_file() else {}
    if info.get("insecure"):
        print("note: this CPS runs with --insecure (NoSecurity): it checks no certificates")
    return 0


def _trust_gateway(wd: Path, asset: str | None, cert) -> int:
    """Put a HAL gateway's certificate on `asset`'s gateway trust list (``[hal] trust_dir``
    of ``WORKDIR/assets/<asset>.toml``, default its ``cert_dir/gateways``): the asset checks
    the gateway's certificate against it before it opens the secure channel, on every new
    session (a unit that was refused connects without a restart)."""
    from cryptography.hazmat.primitives import hashes
    from cryptography.hazmat.primitives.serialization import Encoding

    from transfertwin.cps import gateway_trust_dir, load_asset_config
    from transfertwin.cps.opcua import trust_certificate

    if asset is None:
        raise InputError("--gateway: a gateway is trusted by the asset it serves; name it "
                         "with --asset ID")  # fmt: skip
    path = wd / "assets" / asset / "asset.toml"
    if Path(asset).name != asset or not path.is_file():
        raise InputError(f"--asset {asset}: no such asset file {path}")
    cfg = load_asset_config(path)
    if cfg.hal.kind != "remote":
        raise InputError(f"--asset {asset}: its hardware is [hal] kind = \"{cfg.hal.kind}\", "
                         "not \"remote\": it has no HAL gateway to trust")  # fmt: skip
    own = cfg.cert_dir / "client-operator.der"
    der = cert.public_bytes(Encoding.DER)
    if own.is_file() and own.read_bytes() == der:
        raise InputError(f"--gateway: {own} is {asset}'s own certificate; trust the one the "
                         f"gateway {cfg.hal.endpoint} shows")  # fmt: skip
    written = trust_certificate(gateway_trust_dir(cfg), cert)
    print(f"trusted HAL gateway {cfg.hal.endpoint} for {asset}: {cert.subject.rfc4514_string()} "
          f"(SHA-256 {cert.fingerprint(hashes.SHA256()).hex()[:16]}...): {written}")  # fmt: skip
    if cfg.hal.insecure:
        print(f"note: {asset} talks to its gateway with NoSecurity ([hal] insecure = true): "
              "it checks no gateway certificate")  # fmt: skip
    return 0


def _experiment_unit(info: dict, unit: str, physical: bool) -> str:
    """The transfer unit an experiment runs against: `unit`, or its physical twin."""
    units = [a["id"] for a in info["assets"]
             if a.get("role_class", a["class"]) == "transfer_unit"]  # fmt: skip
    if physical and not unit.endswith("_P"):
        unit = f"{unit}_P"
    if unit not in units:
        if unit.endswith("_P") and not any(u.endswith("_P") for u in units):
            raise InputError(f"--unit {unit}: this CPS has no physical assets; start it with "
                             "'transfertwin cps up --plant-seed N'")  # fmt: skip
        raise InputError(f"--unit {unit}: no such transfer unit; units: {', '.join(units)}")
    return unit


def _as_transfer_json(record: dict, run: int) -> dict:
    """An EM record in the form `transfer --json` prints: runs numbered 0..N-1, states as
    lists (None when not observed), NaN as null."""
    out = {k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in record.items()}
    out["run"] = run
    for key in ("state_pre", "state_end_1", "state_end_2"):
        if isinstance(out.get(key), str):
            out[key] = json.loads(out[key]) if out[key] else None
    return out


def cmd_experiment(args: argparse.Namespace) -> int:
    """Run experiments through the Experiment Manager: E^V against a virtual unit, E^P
    against a physical one (`--physical` or a ``_P`` id); one JSON record per line."""
    from transfertwin.cps.opcua import OperationRefused, connect
    from transfertwin.objects import builtin_ids
    from transfertwin.ots import state_index

    state_index(args.face, args.conveyor, args.theta)  # an experiment state (Eq. 6.7)
    if args.object not in set(builtin_ids()):
        raise InputError(f"--object {args.object}: not a built-in core (o1..o37)")
    if args.seed < 0:
        raise InputError(f"--seed must be a non-negative integer, got {args.seed}")
    if args.runs < 1:
        raise InputError(f"--runs must be at least 1, got {args.runs}")
    wd = workdir_of(args.workdir, must_exist=True)
    info, creds = load_info(wd)
    unit = _experiment_unit(info, args.unit, args.physical)

    async def run() -> None:
        async with connect(endpoint_of(info, "EM"), "EM", credentials=creds,
                           cert_dir=Path(info["cert_dir"]), insecure=info["insecure"],
                           timeout_s=300) as em:  # fmt: skip
            for i in range(args.runs):
                try:
                    record = await em.call("RunExperiment", unit, args.object, args.face,
                                           args.conveyor, args.theta, args.seed + i)  # fmt: skip
                except OperationRefused as exc:
                    raise InputError(f"the Experiment Manager refused: {exc.reason}") from None
                print(json.dumps(_as_transfer_json(json.loads(record), i)), flush=True)

    run_client(wd, run)
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
    """Add `cps up|status|order|trust|experiment|export` to the CLI."""
    cps = sub.add_parser("cps", help="demo cyber-physical system on loopback (Ch. 3, Sec. 5.3)")
    csub = cps.add_subparsers(dest="cps_command", required=True, parser_class=type(cps))
    p = csub.add_parser("up", help="start TU_A..TU_D, TM_1, objects, KG and logical assets")
    p.add_argument("--workdir", required=True)
    p.add_argument("--config", help=argparse.SUPPRESS)  # refused: a floor's physics are built in
    p.add_argument("--host", default="127.0.0.1", help=argparse.SUPPRESS)  # refused likewise
    p.add_argument("--insecure", action="store_true", help="serve NoSecurity (explicit opt-in)")
    p.add_argument("--time-scale", type=float, default=1.0,
                   help="simulated seconds per wall second (0: as fast as possible)")  # fmt: skip
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--docking", default="sampled",
                   help="sampled: docking errors drawn from the fitted generator; navigated: "
                        "the transport module drives the shop floor, docks by laser and "
                        "scans with its depth camera (default sampled)")  # fmt: skip
    p.add_argument("--plant-seed", type=int, metavar="N",
                   help="an emulated plant drawn from seed N (its parameters stay hidden): "
                        "every unit and module runs on it (hal = plant), and the plant's own "
                        "units (TU_<name>_P, kind physical) join beside them")  # fmt: skip
    # `transfertwin.plant.FLOOR_PLANT_KINDS` (not imported here: the CLI starts without physics)
    p.add_argument("--plant-kind", choices=("in-class", "mismatch", "bullet"), default="in-class",
                   help="with --plant-seed: the plant of the twin's own model class with hidden "
                        "values (in-class, the default), that plant with structural "
                        "differences the twin cannot represent (mismatch), or the in-class "
                        "plant in another physics engine, PyBullet (bullet: no depth "
                        "camera)")  # fmt: skip
    p.add_argument("--plant-mismatch-off", default="", metavar="PART,...",
                   help="with --plant-kind mismatch: parts of the mismatch switched back to the "
                        "in-class plant's (shape, mass, belts, contact, appendage, compliant, "
                        "sag), to ablate them on a floor")  # fmt: skip
    p.add_argument("--floor", metavar="FLOOR",
                   help="a floor file (examples/floor-demo.toml), default 'demo', the built-in "
                        "floor; each asset on its own loopback address")
    p.add_argument("--single-process", action="store_true",
                   help="every asset's node in this process, one event loop (the same nodes "
                        "as one process per asset); the floor stops with it")  # fmt: skip
    p.add_argument("--detach", action="store_true",
                   help="exit once the floor is up and leave it running (stop it with "
                        "'cps down')")  # fmt: skip
    p.add_argument("--prepare-only", action="store_true",
                   help="write the work folder and every asset's bundle (W/assets/<id>) and "
                        "start nothing: each bundle is copied to its host and started there "
                        "('cps asset BUNDLE'; a floor file's [bind] gives its address)")
    p.add_argument("--lease", type=float, default=None,
                   help="seconds without a heartbeat before an asset counts as "
                        "offline (default 5 up to 66 assets, then 3 s per 40 assets: 15 at "
                        "200; docs/scaling.md)")  # fmt: skip
    p.add_argument("--policy", choices=("nearest-idle", "predictive"),
                   help="how the TMS assigns orders and chooses pre-transfer "
                        "states (default: the floor file's, else predictive: the twin ranks the "
                        "object's states, learnt on by the floor's own transfers)")  # fmt: skip
    p.add_argument("--study", metavar="STORE",
                   help="a study store whose per-state success shares the "
                        "predictive policy uses (default: the floor file's)")  # fmt: skip
    p.add_argument("--start-timeout", type=float, default=120.0,
                   help="seconds to wait for every asset to join (default 120)")
    p.set_defaults(func=cmd_up)
    p = csub.add_parser("status", help="list the assets and where the objects are")
    add_access(p)
    p.add_argument("--json", action="store_true",
                   help="one JSON document: assets (id, kind, address, pid, online, state) and "
                        "every object's location")  # fmt: skip
    p.set_defaults(func=cmd_status)
    p = csub.add_parser("order", help="run a transport operation end to end over OPC UA")
    add_access(p)
    p.add_argument("--from", dest="source",
                   help="the unit (or the transport module) the object lies on; the TMS "
                        "finds it when left out")  # fmt: skip
    p.add_argument("--to", dest="target", required=True)
    p.add_argument("--object", required=True)
    p.add_argument("--timeout", type=float, default=600.0,
                   help="seconds to follow the operation (default 600)")  # fmt: skip
    p.set_defaults(func=cmd_order)
    p = csub.add_parser("trust", help="trust a client certificate (DER or PEM) for the servers")
    p.add_argument("cert", metavar="CERT", help="the client's application certificate")
    p.add_argument("--workdir", default=".", help="the CPS's workdir (default: .)")
    p.add_argument("--asset", help="on a --floor floor: trust it for this asset only "
                                   "(default: every asset of the floor)")  # fmt: skip
    p.add_argument("--gateway", action="store_true",
                   help="CERT is the HAL gateway's of --asset (hal = \"remote\"): put it on "
                        "that asset's gateway trust list ([hal] trust_dir)")  # fmt: skip
    p.set_defaults(func=cmd_trust)
    p = csub.add_parser("experiment",
                        help="run experiments through the Experiment Manager: virtual ones "
                             "(E^V) on a virtual unit, physical ones (E^P) on a physical "
                             "one")  # fmt: skip
    p.add_argument("--workdir", required=True)
    p.add_argument("--unit", required=True, help="transfer unit, e.g. TU_A (or TU_A_P)")
    p.add_argument("--physical", action="store_true",
                   help="physical experiments (E^P) on the unit's physical twin (needs "
                        "cps up --plant-seed)")  # fmt: skip
    p.add_argument("--object", required=True, help="built-in core, e.g. o2")
    p.add_argument("--face", required=True)
    p.add_argument("--conveyor", required=True)
    p.add_argument("--theta", type=int, required=True, help="yaw in degrees")
    p.add_argument("--seed", type=int, default=0,
                   help="seed of the first virtual experiment (E^V; one more per run; "
                        "recorded for physical ones, E^P)")  # fmt: skip
    p.add_argument("--runs", type=int, default=1, help="experiments in a row (default 1)")
    p.set_defaults(func=cmd_experiment)
    p = csub.add_parser("export", help="write the demo assets' AAS as JSON, XML or AASX")
    p.add_argument("--out", required=True, help="FILE.json, FILE.xml or FILE.aasx")
    p.add_argument("--with-physical", action="store_true",
                   help="also the physical twins (TU_A_P, ...) of the virtual models")  # fmt: skip
    p.set_defaults(func=cmd_export)
    register_floor(csub)
    register_study(csub)
    register_campaign(csub)
    register_supervise(csub)
    register_ca(csub)
