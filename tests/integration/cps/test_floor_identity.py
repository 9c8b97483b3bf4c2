"""An asset speaks only for itself, and only people operate (issue 41, item 2): on a secure
floor the knowledge graph refuses a registration over a channel without security, or in
another asset's name, with a status; a heartbeat or a leave in another asset's name is
refused although the caller's certificate is the floor's; no asset's certificate may call
an operator-only method (Shutdown) of another, an operator may.

One real knowledge-graph node on loopback, its floor prepared as ``cps up`` does (CA,
bundles); the callers are TU_A (its own bundle's certificate: an X.509 identity), the
operator (the floor's credentials) and a client without security.
"""

from __future__ import annotations

import asyncio
import dataclasses
import json

import pytest
from asyncua import ua

from tests.integration.cps._cli import two_module_floor


@pytest.fixture(scope="module")
def floor(tmp_path_factory):
    from transfertwin.cps import load_floor, prepare_floor

    root = tmp_path_factory.mktemp("identity")
    (root / "floor.toml").write_text(two_module_floor("identity", {"o1": "TU_A"}))
    spec = load_floor(root / "floor.toml")
    configs = prepare_floor(spec, root / "w", lease_s=30.0)
    configs["KG"] = dataclasses.replace(configs["KG"], seeds=())
    return root / "w", spec, configs


def _scenario(floor, body):
    """Run `body(kg_node, as_asset, as_operator)` with the graph's node up."""
    from transfertwin.cps import asset_node
    from transfertwin.cps.opcua import connect, load_credentials

    workdir, _, configs = floor
    kg_cfg = configs["KG"]

    def as_asset(aid: str = "TU_A"):
        cfg = configs[aid]
        return connect(kg_cfg.endpoint, "KG", credentials=None, cert_dir=cfg.cert_dir,
                       certificate=aid, trust_dir=cfg.trust_dir)  # fmt: skip

    def as_operator():
        return connect(kg_cfg.endpoint, "KG", credentials=load_credentials(
            workdir / "credentials.json"), cert_dir=workdir / "certs")  # fmt: skip

    async def main():
        async with asset_node(kg_cfg) as kg:
            return await body(kg, as_asset, as_operator)

    return asyncio.run(asyncio.wait_for(main(), 120))


def _beat(floor, aid: str) -> str:
    from transfertwin.cps.node import heartbeat_payload

    _, spec, configs = floor
    desc = {d.asset_id: d for d in spec.descriptors()}[aid]
    return heartbeat_payload(desc, configs[aid].endpoint, "Basic256Sha256_SignAndEncrypt",
                             {"state": "idle"}, "i1")  # fmt: skip


def _registration(aid: str, url: str) -> ua.RegisterServer2Parameters:
    server = ua.RegisteredServer(ServerUri=f"urn:transfertwin:{aid}",
                                 ProductUri="urn:transfertwin",
                                 ServerNames=[ua.LocalizedText(aid)],
                                 ServerType=ua.ApplicationType.Server,
                                 DiscoveryUrls=[url], IsOnline=True)  # fmt: skip
    return ua.RegisterServer2Parameters(Server=server, DiscoveryConfiguration=[])


async def _register_without_security(url: str, params) -> None:
    """RegisterServer2 over SecurityPolicy None, as any process on the network could."""
    from asyncua import Client

    client = Client(url=url, timeout=5)
    await client.connect_socket()
    try:
        await client.send_hello()
        await client.open_secure_channel()
        try:
            await client.uaclient.register_server2(params)
        finally:
            await client.close_secure_channel()
    finally:
        client.disconnect_socket()


def test_a_registration_without_security_or_in_another_name_is_refused(floor):
    """Without the fix asyncua answered both Good (the rogue entry was only dropped later,
    silently, by discovery); now each gets its status and TU_A's own registration stands."""
    _, _, configs = floor

    async def body(kg, as_asset, _as_operator):
        url = kg.server.endpoint
        rogue = "opc.tcp://127.0.0.1:1/transfertwin/TMS"
        with pytest.raises(ua.UaStatusCodeError) as plain:
            await _register_without_security(url, _registration("TMS", rogue))
        async with as_asset("TU_A") as session:
            with pytest.raises(ua.UaStatusCodeError) as other:
                await session.client.uaclient.register_server2(_registration("TMS", rogue))
            await session.client.uaclient.register_server2(
                _registration("TU_A", configs["TU_A"].endpoint))  # fmt: skip
        return plain.value.code, other.value.code, kg.server.registered_peers()

    plain, other, registered = _scenario(floor, body)
    assert plain == ua.StatusCodes.BadSecurityModeInsufficient
    assert other == ua.StatusCodes.BadCertificateUriInvalid
    assert registered == [("urn:transfertwin:TU_A", configs["TU_A"].endpoint)]


def test_a_heartbeat_without_security_is_refused_with_a_status(floor, monkeypatch):
    """A client without security that goes on past asyncua's own endpoint check (as a
    hostile one would): the graph refuses its session at once, saying why
    (BadSecurityModeInsufficient; before, CreateSession was accepted and only the activation
    refused, as BadUserAccessDenied); no heartbeat reaches the graph."""
    from asyncua import Client

    from transfertwin.cps.opcua import load_credentials

    workdir, _, _ = floor
    user, password = load_credentials(workdir / "credentials.json").for_role("operator")
    secure = ua.MessageSecurityMode.SignAndEncrypt
    monkeypatch.setattr(
        Client,
        "find_endpoint",
        staticmethod(lambda eps, _mode, _uri: next(e for e in eps if e.SecurityMode == secure)),
    )

    async def body(kg, _as_asset, _as_operator):
        client = Client(url=kg.server.endpoint, timeout=5)
        client.set_user(user)
        client.set_password(password)
        with pytest.raises(ua.UaStatusCodeError) as refused:
            await client.connect()
            try:
                await client.nodes.objects.call_method(
                    ua.NodeId("KG.ControlInterface.Heartbeat", 2), _beat(floor, "TU_A")
                )
            finally:
                await client.disconnect()
        return refused.value.code, set(kg.role.leases)

    code, leases = _scenario(floor, body)
    assert code == ua.StatusCodes.BadSecurityModeInsufficient, ua.StatusCode(code)
    assert "TU_A" not in leases


def test_an_asset_heartbeats_and_leaves_only_in_its_own_name(floor):
    """TU_A's certificate is the floor's, but it names TU_A: its heartbeat as TU_B, and its
    leave for TU_B, are refused (BadUserAccessDenied); so is a person's heartbeat (assets
    heartbeat with their own certificate). Its own heartbeat and leave are taken."""
    from transfertwin.cps.opcua import OperationRefused

    async def body(kg, as_asset, as_operator):
        refused = []
        async with as_asset("TU_B") as b:
            await b.call("Heartbeat", _beat(floor, "TU_B"))
        async with as_asset("TU_A") as a:
            reply = json.loads(await a.call("Heartbeat", _beat(floor, "TU_A")))
            for op, arg in (("Heartbeat", _beat(floor, "TU_B")), ("Leave", "TU_B")):
                with pytest.raises(OperationRefused) as exc:
                    await a.call(op, arg)
                refused.append(exc.value.status)
            async with as_operator() as person:
                with pytest.raises(OperationRefused) as exc:
                    await person.call("Heartbeat", _beat(floor, "TU_B"))
                refused.append(exc.value.status)
            leases = set(kg.role.leases)
            assert await a.call("Leave", "TU_A") is True
        return reply, refused, leases, set(kg.role.leases)

    reply, refused, leases, after = _scenario(floor, body)
    assert "directory" in reply
    assert refused == ["BadUserAccessDenied"] * 3
    assert {"TU_A", "TU_B"} <= leases
    assert "TU_A" not in after and "TU_B" in after


def test_no_asset_can_shut_another_down_an_operator_can(floor):
    """Shutdown is operator-only: TU_A's certificate (an asset's identity) is refused by
    the server's permission check; the operator's call stops the graph's node."""
    from transfertwin.cps.node import LIFECYCLE

    async def body(kg, as_asset, as_operator):
        async with as_asset("TU_A") as a:
            with pytest.raises(ua.UaStatusCodeError) as refused:
                await a.call("Shutdown", submodel=LIFECYCLE)
            assert await a.call("Status")  # its other calls are still served
        await asyncio.sleep(0.3)
        asked_by_asset = kg.shutdown.is_set()
        async with as_operator() as person:
            assert await person.call("Shutdown", submodel=LIFECYCLE) is True
        await asyncio.wait_for(kg.shutdown.wait(), 5)
        return refused.value.code, asked_by_asset

    code, asked_by_asset = _scenario(floor, body)
    assert code == ua.StatusCodes.BadUserAccessDenied
    assert not asked_by_asset
