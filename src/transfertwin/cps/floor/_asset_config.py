"""One asset process's configuration file, ``assets/<id>/asset.toml`` (docs/architecture.md,
"Deployment").

```toml
[asset]
id = "TU_A"                  # an asset of the floor file below
floor = "floor.toml"         # the floor it belongs to (stations, placement, peers' kinds)

[network]
host = "127.0.0.2"           # address to bind; beyond loopback needs allow_remote = true
allow_remote = false         # (and security: never with insecure)
port = 48401
seeds = ["opc.tcp://127.0.0.5:48405/transfertwin/KG"]  # peers to join through
lease_s = 5.0                # a peer silent this long is offline

[security]
insecure = false             # NoSecurity: explicit opt-in, loopback only
cert_dir = "certs"           # this process's own application certificates
trust_dir = "trusted"        # client certificates this asset accepts
credentials = "credentials.json"

[runtime]
state_dir = "state"          # what survives a crash, written atomically
study = "study.sqlite"       # the Experiment Manager: the study store it answers from
seed = 0
time_scale = 1.0
docking = "sampled"

[hal]                        # what the asset's belts and light barriers are
kind = "virtual"             # virtual | plant | remote
# plant: the emulated plant's hidden physics (a transport module simulates its docked pair
# with it); the seed is in a file of its own, never in this one
plant_seed_file = "plant.secret"
# remote: real hardware behind a HAL gateway (OPC UA): belt speeds written, barriers read
endpoint = "opc.tcp://192.168.10.21:4840"
insecure = false             # NoSecurity at the gateway: explicit, loopback only
trust_dir = "certs/gateways" # the gateway certificates trusted (the default)
poll_s = 0.05                # how often the barriers (a module: also its pose) are read
belt_left = "ns=2;s=TU_A.BeltSpeedLeft"      # the gateway's nodes (these are the defaults)
belt_right = "ns=2;s=TU_A.BeltSpeedRight"
barrier_near = "ns=2;s=TU_A.BarrierNear"
barrier_far = "ns=2;s=TU_A.BarrierFar"
# a transport module also: pose_x, pose_y, pose_theta, command, command_state, object_state
# (ns=2;s=<id>.PoseX, .PoseY, .PoseTheta, .Command, .CommandState, .ObjectState)
```

Relative paths are resolved against the file's folder. `cps up` writes this file into the
asset's bundle (``assets/<id>/asset.toml``) with every path inside the bundle, so the folder
runs as it is on another host (``transfertwin cps asset BUNDLE``).
"""

from __future__ import annotations

import ipaddress
import math
from dataclasses import dataclass
from pathlib import Path

from transfertwin._atomic import write_atomic
from transfertwin._errors import InputError
from transfertwin.cps.floor._toml import read_toml, table, toml_value

__all__ = ["DOCKING_MODES", "HAL_KINDS", "PROVENANCE", "AssetConfig", "HalConfig",
           "load_asset_config", "write_asset_config"]  # fmt: skip

#: How a transport module gets to a station and sees the belts (docs/architecture.md,
#: "Transport operation flow"): 'sampled' puts it at the station with a docking error drawn
#: from the generator fitted to the real errors and forms the OTS from the simulation's
#: true object box; 'navigated' plans and drives on the shop floor, docks by laser (the
#: error emerges) and forms the OTS from its depth camera's workspace scan.
DOCKING_MODES = ("sampled", "navigated")

#: What an asset's hardware abstraction layer may be.
HAL_KINDS = ("virtual", "plant", "remote")

#: What an asset's AAS says its data come from, by HAL (the plant's seed and parameters are
#: not named; a remote asset's gateway is in its asset file, not in its AAS).
PROVENANCE = {"virtual": "transfertwin virtual model (MuJoCo)",
              "plant": "emulated plant (transfertwin.plant)",
              "remote": "physical asset behind a HAL gateway (OPC UA)"}  # fmt: skip

#: The HAL gateway's nodes a remote asset uses, and their default NodeIds ({id}: asset id).
#: A unit uses the belts and barriers; a transport module also its pose (localisation,
#: floor frame), its drive commands and their state, and its object sensor
#: (docs/architecture.md, "Deployment").
GATEWAY_NODES = {"belt_left": "ns=2;s={id}.BeltSpeedLeft",
                 "belt_right": "ns=2;s={id}.BeltSpeedRight",
                 "barrier_near": "ns=2;s={id}.BarrierNear",
                 "barrier_far": "ns=2;s={id}.BarrierFar",
                 "pose_x": "ns=2;s={id}.PoseX",
                 "pose_y": "ns=2;s={id}.PoseY",
                 "pose_theta": "ns=2;s={id}.PoseTheta",
                 "command": "ns=2;s={id}.Command",
                 "command_state": "ns=2;s={id}.CommandState",
                 "object_state": "ns=2;s={id}.ObjectState"}  # fmt: skip


@dataclass(frozen=True)
class HalConfig:
    """An asset's HAL: ``virtual`` (simulated by the twin), ``plant`` (the emulated plant's
    hidden physics, seed in `plant_seed_file`) or ``remote`` (a HAL gateway at `endpoint`;
    `nodes`: its NodeIds, `GATEWAY_NODES` filled in where left out; `trust_dir`: the
    gateway certificates trusted, None: ``cert_dir/gateways``)."""

    kind: str = "virtual"
    plant_seed_file: Path | None = None
    endpoint: str | None = None
    insecure: bool = False
    poll_s: float = 0.05
    nodes: tuple[tuple[str, str], ...] = ()
    trust_dir: Path | None = None

    def check(self, where: str) -> None:
        """InputError naming `where` for a HAL that cannot work."""
        if self.kind not in HAL_KINDS:
            raise InputError(f"{where}: [hal] kind must be one of {', '.join(HAL_KINDS)}, "
                             f"got {self.kind!r}")  # fmt: skip
        if self.kind == "plant" and self.plant_seed_file is None:
            raise InputError(f"{where}: [hal] kind = \"plant\" needs plant_seed_file")
        if self.kind != "remote":
            return
        if not isinstance(self.endpoint, str) or not self.endpoint.startswith("opc.tcp://"):
            raise InputError(f"{where}: [hal] kind = \"remote\" needs endpoint = "
                             f"\"opc.tcp://HOST:PORT\", got {self.endpoint!r}")  # fmt: skip
        host = self.endpoint.removeprefix("opc.tcp://").split("/")[0].rsplit(":", 1)[0]
        if self.insecure and host.strip("[]") not in ("localhost", "127.0.0.1", "::1") and \
                not host.startswith("127."):
            raise InputError(f"{where}: [hal] insecure (NoSecurity at the gateway) is for "
                             f"loopback only; {host} needs security")  # fmt: skip
        if not (math.isfinite(self.poll_s) and 0.005 <= self.poll_s <= 5.0):
            raise InputError(f"{where}: [hal] poll_s must be 0.005..5 s, got {self.poll_s}")
        unknown = sorted(set(dict(self.nodes)) - set(GATEWAY_NODES))
        if unknown:
            raise InputError(f"{where}: [hal] unknown key {unknown[0]!r}")

    def node_ids(self, asset_id: str) -> dict[str, str]:
        """The gateway's NodeIds by key (`GATEWAY_NODES`)."""
        given = dict(self.nodes)
        return {k: given.get(k, v.format(id=asset_id)) for k, v in GATEWAY_NODES.items()}


@dataclass(frozen=True)
class AssetConfig:
    """How one asset process runs (see the module docstring for the file)."""

    asset_id: str
    floor_file: Path
    host: str
    port: int
    seeds: tuple[str, ...]
    cert_dir: Path
    trust_dir: Path
    credentials_file: Path | None
    state_dir: Path
    insecure: bool = False
    allow_remote: bool = False
    lease_s: float = 5.0
    seed: int = 0
    time_scale: float = 1.0
    docking: str = "sampled"
    hal: HalConfig = HalConfig()
    study_file: Path | None = None

    def __post_init__(self) -> None:
        where = f"asset {self.asset_id}"
        try:
            address = ipaddress.ip_address(self.host)
        except ValueError:
            raise InputError(f"{where}: host must be an IP address, got {self.host!r}") from None
        if not address.is_loopback and not self.allow_remote:
            raise InputError(f"{where}: binding {self.host} (beyond loopback) needs "
                             "allow_remote = true in [network]")  # fmt: skip
        if not address.is_loopback and self.insecure:
            raise InputError(f"{where}: insecure (NoSecurity) is for loopback only; "
                             f"{self.host} needs security")  # fmt: skip
        if not 0 < self.port < 65536:
            raise InputError(f"{where}: port must be 1..65535, got {self.port}")
        if not self.insecure and self.credentials_file is None:
            raise InputError(f"{where}: a secure asset needs [security] credentials")
        if not (math.isfinite(self.lease_s) and self.lease_s >= 0.5):
            raise InputError(f"{where}: lease_s must be at least 0.5 s, got {self.lease_s}")
        if self.docking not in DOCKING_MODES:
            raise InputError(f"{where}: docking must be sampled or navigated")
        self.hal.check(where)

    @property
    def endpoint(self) -> str:
        """This asset's OPC UA endpoint URL."""
        return f"opc.tcp://{self.host}:{self.port}/transfertwin/{self.asset_id}"


def load_asset_config(path: Path | str) -> AssetConfig:
    """Read ``ASSET.toml``; one `InputError` line for anything missing or malformed."""
    path = Path(path)
    doc = read_toml(path, missing="no such asset configuration file",
                    unreadable="not a readable TOML file")  # fmt: skip
    base = path.parent
    asset, net = table(doc, "asset"), table(doc, "network")
    sec, run = table(doc, "security"), table(doc, "runtime")
    hal = table(doc, "hal")

    def rel(value: object, key: str) -> Path:
        if not isinstance(value, str) or not value:
            raise InputError(f"{path}: {key} must be a path")
        p = Path(value)
        return p if p.is_absolute() else (base / p).resolve()

    try:
        aid, floor = asset["id"], asset["floor"]
        host, port = net["host"], net["port"]
    except KeyError as exc:
        raise InputError(f"{path}: missing {exc.args[0]!r}") from None
    seeds = net.get("seeds", [])
    if not isinstance(seeds, list) or not all(isinstance(s, str) for s in seeds):
        raise InputError(f"{path}: [network] seeds must be a list of opc.tcp:// URLs")
    insecure = bool(sec.get("insecure", False))
    creds = sec.get("credentials")
    study = run.get("study")
    try:
        return AssetConfig(
            asset_id=str(aid), floor_file=rel(floor, "[asset] floor"), host=str(host),
            port=int(port), seeds=tuple(seeds),
            cert_dir=rel(sec.get("cert_dir", "certs"), "[security] cert_dir"),
            trust_dir=rel(sec.get("trust_dir", "trusted"), "[security] trust_dir"),
            credentials_file=None if creds is None else rel(creds, "[security] credentials"),
            state_dir=rel(run.get("state_dir", "state"), "[runtime] state_dir"),
            insecure=insecure, allow_remote=bool(net.get("allow_remote", False)),
            lease_s=float(net.get("lease_s", 5.0)), seed=int(run.get("seed", 0)),
            time_scale=float(run.get("time_scale", 1.0)),
            docking=str(run.get("docking", "sampled")), hal=_hal(hal, rel, path),
            study_file=None if study is None else rel(study, "[runtime] study"),
        )  # fmt: skip
    except (TypeError, ValueError) as exc:
        raise InputError(f"{path}: {exc}") from None


def _hal(table: dict, rel, path: Path) -> HalConfig:
    known = {"kind", "plant_seed_file", "endpoint", "insecure", "poll_s", "trust_dir",
             *GATEWAY_NODES}
    if unknown := sorted(set(table) - known):
        raise InputError(f"{path}: [hal] unknown key {unknown[0]!r}; known: "
                         f"{', '.join(sorted(known))}")  # fmt: skip
    seed_file = table.get("plant_seed_file")
    endpoint = table.get("endpoint")
    trust = table.get("trust_dir")
    return HalConfig(
        kind=str(table.get("kind", "virtual")),
        plant_seed_file=None if seed_file is None else rel(seed_file, "[hal] plant_seed_file"),
        endpoint=None if endpoint is None else str(endpoint),
        insecure=bool(table.get("insecure", False)), poll_s=float(table.get("poll_s", 0.05)),
        nodes=tuple((k, str(table[k])) for k in GATEWAY_NODES if k in table),
        trust_dir=None if trust is None else rel(trust, "[hal] trust_dir"),
    )  # fmt: skip


def write_asset_config(path: Path, cfg: AssetConfig, *, relative: bool = False) -> Path:
    """Write `cfg` as ``ASSET.toml`` (atomically). Paths are absolute, or with `relative`
    relative to the file's folder where they lie inside it (an asset's bundle)."""
    base = path.parent.resolve()

    def out(p: Path) -> str:
        if relative and p.resolve().is_relative_to(base):
            return p.resolve().relative_to(base).as_posix() or "."
        return str(p)

    tables = {
        "asset": {"id": cfg.asset_id, "floor": out(cfg.floor_file)},
        "network": {"host": cfg.host, "port": cfg.port, "seeds": list(cfg.seeds),
                    "lease_s": cfg.lease_s, "allow_remote": cfg.allow_remote},
        "security": {"insecure": cfg.insecure, "cert_dir": out(cfg.cert_dir),
                     "trust_dir": out(cfg.trust_dir)},
        "runtime": {"state_dir": out(cfg.state_dir), "seed": cfg.seed,
                    "time_scale": cfg.time_scale, "docking": cfg.docking},
    }
    if cfg.credentials_file is not None:
        tables["security"]["credentials"] = out(cfg.credentials_file)
    if cfg.study_file is not None:
        tables["runtime"]["study"] = out(cfg.study_file)
    hal = cfg.hal
    tables["hal"] = {"kind": hal.kind}
    if hal.plant_seed_file is not None:
        tables["hal"]["plant_seed_file"] = out(hal.plant_seed_file)
    if hal.kind == "remote":
        tables["hal"] |= {"endpoint": hal.endpoint, "insecure": hal.insecure,
                          "poll_s": hal.poll_s, **dict(hal.nodes)}  # fmt: skip
        if hal.trust_dir is not None:
            tables["hal"]["trust_dir"] = out(hal.trust_dir)
    lines = [f"# transfertwin asset process: transfertwin cps asset {path.parent.name}"
             if relative else
             f"# transfertwin asset process: transfertwin cps asset --config {path.name}"]
    for name, rows in tables.items():
        lines += ["", f"[{name}]", *(f"{k} = {toml_value(v)}" for k, v in rows.items())]
    path.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(path, "\n".join(lines) + "\n")
    return path
