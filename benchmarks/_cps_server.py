"""An asset server in a child process for the CPS load and fuzz figures: the client's work
does not count against the server's memory, and the two use two cores."""

from __future__ import annotations

import asyncio
import multiprocessing as mp
import tempfile
from pathlib import Path

from _stress import WriteRecorder, rss_kib
from transfertwin.cps.aas._demo import demo_descriptors
from transfertwin.cps.aas._representation import build_representation, externally_synced
from transfertwin.cps.opcua import (
    ROLES,
    AssetServer,
    ServerConfig,
    init_ca,
    install_certificate,
    new_credentials,
    new_request,
)

PROP = ("OperationalData", "PossessedObjects")


def _serve(conn, cert_dir: Path, creds) -> None:
    async def main() -> None:
        desc = next(d for d in demo_descriptors() if d.asset_id == "TU_A")
        rep = build_representation(desc)
        writable = frozenset(("OperationalData", p) for p in externally_synced(rep))
        cfg = ServerConfig(cert_dir=cert_dir, credentials=creds)
        async with AssetServer("TU_A", rep.submodels, cfg, {}, writable) as server:
            recorder = WriteRecorder(*PROP)
            server.on_client_write(recorder)
            conn.send(server.endpoint)
            loop = asyncio.get_running_loop()
            while True:
                msg = await loop.run_in_executor(None, conn.recv)
                if msg == "reset":
                    recorder.values = type(recorder.values)("q")
                    conn.send(rss_kib())
                elif isinstance(msg, tuple) and msg[0] == "check":
                    conn.send((recorder.check(msg[1]), rss_kib(), await server.get(*PROP)))
                else:
                    conn.send(None)
                    return

    asyncio.run(main())


class ChildServer:
    """TU_A's server in a child process; `ask` sends it a message and returns the answer."""

    def __init__(self) -> None:
        self.tmp = tempfile.TemporaryDirectory(prefix="cps-bench-")
        self.cert_dir = Path(self.tmp.name) / "certs"
        self.creds = new_credentials()

        # a floor CA signs the server's and the clients' certificates; both sides trust it
        ca = init_ca(Path(self.tmp.name) / "ca")
        for name in ("TU_A", *(f"client-{role}" for role in ROLES)):
            install_certificate(self.cert_dir, name, ca.issue(new_request(self.cert_dir, name)))
        ca.install(self.cert_dir / "trusted")
        ctx = mp.get_context("spawn")
        self.conn, child = ctx.Pipe()
        self.proc = ctx.Process(target=_serve, args=(child, self.cert_dir, self.creds))
        self.proc.start()
        self.endpoint: str = self.conn.recv()

    def ask(self, msg):
        self.conn.send(msg)
        return self.conn.recv()

    def close(self) -> None:
        self.ask("stop")
        self.proc.join(30)
        self.tmp.cleanup()
