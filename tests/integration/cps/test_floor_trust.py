"""Servers authenticated both ways under the floor's CA: a client refuses a server that is
not the asset it meant (self-signed rogue, another CA, wrong URI, revoked, expired) before
it sends any credential; a peer asset's certificate is its identity; a revoked peer loses
its open session within the re-read period; discovery takes no peer it could not check.

The servers are real asyncua servers on loopback; the CA is the run's (`pki`).
"""

from __future__ import annotations

import asyncio
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest
from asyncua import Server, ua
from asyncua.crypto.permission_rules import User, UserRole

from transfertwin.cps.aas._demo import demo_descriptors
from transfertwin.cps.aas._representation import build_representation
from transfertwin.cps.opcua import (
    AssetServer,
    Discovery,
    UntrustedServer,
    connect,
    ensure_certificate,
    init_ca,
    install_certificate,
    new_request,
)

_DESCS = {d.asset_id: d for d in demo_descriptors()}


def _run(coro):
    return asyncio.run(asyncio.wait_for(coro, timeout=120))


class _Recorder:
    """A rogue's user manager: keeps every credential a client hands it."""

    def __init__(self) -> None:
        self.seen: list[tuple[object, object, object]] = []

    def get_user(self, iserver, username=None, password=None, certificate=None):
        self.seen.append((username, password, certificate))
        return User(role=UserRole.User, name="operator")


async def _bare_server(cert: Path, key: Path, uri: str, users: _Recorder) -> Server:
    """A plain asyncua server with this certificate, naming `uri`, taking any user."""
    server = Server(user_manager=users)
    await server.init()
    server.set_endpoint("opc.tcp://127.0.0.1:0/transfertwin/rogue")
    await server.set_application_uri(uri)
    await server.load_certificate(str(cert))
    await server.load_private_key(str(key))
    server.set_security_policy([ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt])
    server.set_identity_tokens([ua.UserNameIdentityToken, ua.X509IdentityToken])
    await server.start()
    return server


def _url(server: Server, aid: str) -> str:
    port = server.bserver._server.sockets[0].getsockname()[1]
    return f"opc.tcp://127.0.0.1:{port}/transfertwin/{aid}"


async def _reach(url: str, aid: str, pki, **kw) -> str:
    async with connect(url, aid, role="operator", **pki.client_kw(), **kw) as c:
        return await c.read("Identification", "AssetId")


@pytest.mark.parametrize("kind", ["self-signed", "untrusted CA", "expired"])
def test_client_refuses_a_rogue_tms_before_sending_a_credential(pki, tmp_path, kind):
    """A server that says it is the TMS: self-signed, signed by another CA, or the floor
    CA's but expired. The operator's client refuses it; the rogue sees no credential."""
    rogue = tmp_path / "rogue"
    if kind == "self-signed":
        cert, key = _run(ensure_certificate(rogue, "TMS"))
    else:
        now = datetime.now(UTC)
        ca = init_ca(tmp_path / "other-ca") if kind == "untrusted CA" else pki.ca
        window = (
            {}
            if kind == "untrusted CA"
            else {"not_before": now - timedelta(days=30), "not_after": now - timedelta(days=1)}
        )
        cert = install_certificate(rogue, "TMS", ca.issue(new_request(rogue, "TMS", "127.0.0.1"),
                                                          **window))  # fmt: skip
        key = rogue / "TMS.pem"
    users = _Recorder()
    expected = "BadCertificateTimeInvalid" if kind == "expired" else "BadCertificateUntrusted"

    async def scenario() -> None:
        server = await _bare_server(cert, key, "urn:transfertwin:TMS", users)
        try:
            with pytest.raises(UntrustedServer) as refused:
                await _reach(_url(server, "TMS"), "TMS", pki)
            assert refused.value.status == expected
        finally:
            await server.stop()

    _run(scenario())
    assert users.seen == []  # no user name, no password, no certificate token


def test_client_refuses_a_floor_server_that_is_not_the_asset_it_meant(pki, tu_a):
    """TU_A's certificate is the floor's, but the client wanted TU_B at that address."""
    assert _run(_reach(tu_a.endpoint, "TU_A", pki)) == "TU_A"
    with pytest.raises(UntrustedServer) as refused:
        _run(_reach(tu_a.endpoint, "TU_B", pki))
    assert refused.value.status == "BadCertificateUriInvalid"


def test_revoked_server_and_revoked_peer_are_refused(pki, tmp_path):
    """TU_D (a server) and TU_E (a peer asset calling with its certificate) are revoked:
    a client refuses TU_D; TU_D's server drops TU_E's open session within its re-read
    period and refuses it a new one."""
    rep = build_representation(_DESCS["TU_D"])
    peer_dir = tmp_path / "tu_e"
    install_certificate(peer_dir, "TU_E", pki.ca.issue(new_request(peer_dir, "TU_E")))

    async def scenario() -> None:
        cfg = pki.config(cert_dir=tmp_path / "tu_d", trust_dir=pki.trust_dir,
                         peer_roles=(("TU_E", "operator"),), reread_s=0.2)  # fmt: skip
        async with AssetServer("TU_D", rep.submodels, cfg) as server:
            peer = connect(server.endpoint, "TU_D", credentials=None, cert_dir=peer_dir,
                           certificate="TU_E", trust_dir=pki.trust_dir)  # fmt: skip
            async with peer as session:  # the peer's certificate is its identity
                assert await session.read("Identification", "AssetId") == "TU_D"
                pki.ca.revoke("TU_E")
                pki.ca.install(pki.trust_dir)
                with pytest.raises((ConnectionError, ua.UaError, TimeoutError)):
                    for _ in range(50):  # closed within the re-read period (0.2 s)
                        await session.read("Identification", "AssetId")
                        await asyncio.sleep(0.1)
            with pytest.raises(ua.UaStatusCodeError, match="BadCertificateRevoked"):
                async with connect(server.endpoint, "TU_D", credentials=None,
                                   cert_dir=peer_dir, certificate="TU_E",
                                   trust_dir=pki.trust_dir):  # fmt: skip
                    pass
            assert await _reach(server.endpoint, "TU_D", pki) == "TU_D"
            pki.ca.revoke("TU_D")
            pki.ca.install(pki.trust_dir)
            with pytest.raises(UntrustedServer) as refused:
                await _reach(server.endpoint, "TU_D", pki)
            assert refused.value.status == "BadCertificateRevoked"

    _run(scenario())


def test_peer_identity_needs_a_floor_asset_and_gets_its_role(pki, tmp_path, tu_a):
    """A CA-signed certificate of an asset not on the floor (TU_A's server lists no peers)
    gets no session; its user name is nothing to the server either."""
    stranger = tmp_path / "stranger"
    install_certificate(stranger, "TU_X", pki.ca.issue(new_request(stranger, "TU_X")))
    with pytest.raises(ua.UaStatusCodeError, match=r"BadIdentityTokenRejected|BadUserAccessDenied"):
        _run(_reach_as_peer(tu_a.endpoint, "TU_A", stranger, "TU_X", pki))


async def _reach_as_peer(url, aid, cert_dir, name, pki) -> str:
    async with connect(url, aid, credentials=None, cert_dir=cert_dir, certificate=name,
                       trust_dir=pki.trust_dir) as c:  # fmt: skip
        return await c.read("Identification", "AssetId")


def test_a_rogue_registering_as_the_tms_is_not_taken_or_passed_on(pki, tmp_path):
    """A self-signed rogue registers itself as the TMS at TU_A over a channel without
    security: refused with a status (BadSecurityModeInsufficient), nothing registered.
    A floor asset's certificate (TU_B's) may register only its own URI, but it points it
    at the rogue's address, where a self-signed server says it is TU_B: TU_A's discovery
    checks the candidate, refuses it, and its FindServers never names it."""
    rogue_dir = tmp_path / "rogue"
    cert, key = _run(ensure_certificate(rogue_dir, "TU_B"))
    peer_dir = tmp_path / "tu_b"
    install_certificate(peer_dir, "TU_B", pki.ca.issue(new_request(peer_dir, "TU_B")))
    users = _Recorder()

    async def scenario() -> None:
        rep = build_representation(_DESCS["TU_A"])
        rogue = await _bare_server(cert, key, "urn:transfertwin:TU_B", users)
        cfg = pki.config(cert_dir=tmp_path / "tu_a", trust_dir=pki.trust_dir)
        try:
            async with AssetServer("TU_A", rep.submodels, cfg) as server:
                agent = Discovery(server, period_s=60.0)
                with pytest.raises(ua.UaStatusCodeError, match="BadSecurityModeInsufficient"):
                    await _register_insecurely(server.endpoint, "urn:transfertwin:TMS",
                                               _url(rogue, "TMS"))  # fmt: skip
                assert server.registered_peers() == []
                async with connect(server.endpoint, "TU_A", credentials=pki.credentials,
                                   cert_dir=peer_dir, certificate="TU_B",
                                   trust_dir=pki.trust_dir) as session:  # fmt: skip
                    registered = ua.RegisteredServer(
                        ServerUri="urn:transfertwin:TU_B", ProductUri="urn:transfertwin",
                        ServerNames=[ua.LocalizedText("TU_B")],
                        ServerType=ua.ApplicationType.Server,
                        DiscoveryUrls=[_url(rogue, "TU_B")], IsOnline=True)  # fmt: skip
                    await session.client.uaclient.register_server2(ua.RegisterServer2Parameters(
                        Server=registered, DiscoveryConfiguration=[]))  # fmt: skip
                assert ("urn:transfertwin:TU_B", _url(rogue, "TU_B")) in server.registered_peers()
                for _ in range(3):
                    await agent.round()
                assert "urn:transfertwin:TU_B" not in agent.peers
                assert "urn:transfertwin:TU_B" not in agent.candidates
                assert server.registered_peers() == []  # not passed on
        finally:
            await rogue.stop()

    _run(scenario())
    assert users.seen == []


async def _register_insecurely(url: str, uri: str, rogue_url: str) -> None:
    """RegisterServer2 over SecurityPolicy None, as any process on the network could try."""
    from asyncua import Client

    registered = ua.RegisteredServer(ServerUri=uri, ProductUri="urn:transfertwin",
                                     ServerNames=[ua.LocalizedText("TMS")],
                                     ServerType=ua.ApplicationType.Server,
                                     DiscoveryUrls=[rogue_url], IsOnline=True)  # fmt: skip
    client = Client(url=url, timeout=5)
    await client.connect_socket()
    try:
        await client.send_hello()
        await client.open_secure_channel()
        params = ua.RegisterServer2Parameters(Server=registered, DiscoveryConfiguration=[])
        await client.uaclient.register_server2(params)
        await client.close_secure_channel()
    finally:
        client.disconnect_socket()


def test_the_cli_says_in_one_line_that_a_server_is_not_the_asset_meant(pki, tu_a, tmp_path):
    from transfertwin._errors import InputError
    from transfertwin.cli._cps_client import run_client

    with pytest.raises(InputError, match=r"is not TU_B of this floor \(BadCertificateUriInvalid\)"):
        run_client(tmp_path, lambda: _reach(tu_a.endpoint, "TU_B", pki))


def test_an_asset_without_a_certificate_makes_its_request_and_starts_once_issued(
        pki, tmp_path, capsys):  # fmt: skip
    """Under a CA, an asset with no certificate writes its own key and signing request and
    stops with a line naming them; `cps ca issue` signs it; then the asset serves."""
    from transfertwin._errors import InputError
    from transfertwin.cli import main

    rep = build_representation(_DESCS["TU_B"])
    cfg = pki.config(cert_dir=tmp_path / "tu_b", trust_dir=pki.trust_dir, issuer=None)
    with pytest.raises(InputError, match=r"TU_B\.csr\.pem.*cps ca issue"):
        _run(AssetServer("TU_B", rep.submodels, cfg).__aenter__())
    request = tmp_path / "tu_b" / "TU_B.csr.pem"
    key = (tmp_path / "tu_b" / "TU_B.pem").read_bytes()
    assert main(["cps", "ca", "issue", str(request), "--ca", str(pki.ca.folder)]) == 0
    assert "issued CN=TU_B" in capsys.readouterr().out
    assert (tmp_path / "tu_b" / "TU_B.pem").read_bytes() == key  # its key never moved

    async def serve() -> str:
        async with AssetServer("TU_B", rep.submodels, cfg) as server:
            return await _reach(server.endpoint, "TU_B", pki)

    assert _run(serve()) == "TU_B"


def test_a_certificate_not_valid_yet_stops_the_asset_instead_of_a_self_signed_one(
        pki, tmp_path):  # fmt: skip
    """A clock behind the CA's: the asset says so in one line and keeps the CA's
    certificate (a self-signed replacement would be trusted by no peer)."""
    from transfertwin._errors import InputError

    folder = tmp_path / "tu_c"
    soon = datetime.now(UTC) + timedelta(hours=1)
    cert = install_certificate(folder, "TU_C", pki.ca.issue(new_request(folder, "TU_C"),
                                                            not_before=soon))  # fmt: skip
    before = cert.read_bytes()
    with pytest.raises(InputError, match=r"not valid before .* set the clock"):
        _run(ensure_certificate(folder, "TU_C"))
    assert cert.read_bytes() == before


@pytest.mark.slow  # ~30-60 s: the demo floor in one process (CI: the CPS slow group)
def test_a_revoked_asset_leaves_the_floor(tmp_path, cps_certs, capsys):
    """`cps ca revoke o1` on a running floor: the graph drops o1's connection within its
    re-read period, refuses its new sessions, and o1's lease lapses; the others stay."""
    from transfertwin.cli import main
    from transfertwin.cps import LocalFloor, default_floor_spec

    async def scenario() -> float:
        wd = cps_certs(tmp_path)
        async with LocalFloor(default_floor_spec(), wd, time_scale=0.0, lease_s=2.0) as floor:
            graph = floor.nodes["KG"].role
            assert {"o1", "TU_A"} <= set(graph.leases)
            assert main(["cps", "ca", "revoke", "o1", "--workdir", str(wd)]) == 0
            t0 = asyncio.get_running_loop().time()
            while "o1" in graph.leases:
                assert asyncio.get_running_loop().time() - t0 < 30, "o1 still online"
                await asyncio.sleep(0.1)
            gone = asyncio.get_running_loop().time() - t0
            await asyncio.sleep(3 * 2.0)  # and it stays off: no heartbeat gets through
            assert "o1" not in graph.leases and "TU_A" in graph.leases
            return gone

    gone = asyncio.run(scenario())
    assert "revoked 1 certificate(s) of o1" in capsys.readouterr().out
    assert gone < 2.0 + 2.0 + 5.0  # the lease, the re-read period, a scheduling margin
