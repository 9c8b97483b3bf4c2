"""Asset servers on loopback: secure by default, a trust list of client certificates, roles
enforced on the server, robust to garbage (issue 13, item 3).

Most tests share one TU_A server and the run's certificates (see conftest.py).
"""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest
from asyncua import ua
from cryptography.hazmat.primitives.serialization import Encoding

from transfertwin.cli import main
from transfertwin.cps.opcua import (
    OperationRefused,
    RoleUserManager,
    TrustList,
    connect,
    ensure_certificate,
    new_credentials,
    read_certificate,
)


def _run(coro):
    return asyncio.run(asyncio.wait_for(coro, timeout=120))


def test_operator_calls_and_writes(tu_a, pki):
    calls = []

    async def set_speed(belt, speed):
        calls.append((belt, speed))
        await tu_a.server.set("OperationalData", "BeltSpeedLeft", speed)
        return True

    tu_a.handle("SetBeltSpeed", set_speed)

    async def scenario():
        assert tu_a.server.security_policy == "Basic256Sha256_SignAndEncrypt"
        async with connect(tu_a.endpoint, "TU_A", role="operator", **pki.client_kw()) as op:
            assert await op.call("SetBeltSpeed", "left", 0.15) is True
            assert await op.read("OperationalData", "BeltSpeedLeft") == 0.15
            await op.write("OperationalData", "PossessedObjects", "o5")

    _run(scenario())
    assert calls == [("left", 0.15)]
    assert tu_a.run(tu_a.server.get("OperationalData", "PossessedObjects")) == "o5"


def test_viewer_reads_but_its_writes_and_calls_are_refused_by_the_server(tu_a, pki):
    calls = []

    async def set_speed(belt, speed):
        calls.append((belt, speed))
        return True

    tu_a.handle("SetBeltSpeed", set_speed)
    tu_a.run(tu_a.server.set("OperationalData", "PossessedObjects", "o7"))

    async def scenario():
        async with connect(tu_a.endpoint, "TU_A", role="viewer", **pki.client_kw()) as viewer:
            assert await viewer.read("OperationalData", "PossessedObjects") == "o7"
            with pytest.raises(OperationRefused) as refused:
                await viewer.write("OperationalData", "PossessedObjects", "x")
            assert refused.value.status == "BadUserAccessDenied"
            assert str(refused.value) == (
                "BadUserAccessDenied: TU_A.write OperationalData.PossessedObjects refused: "
                "the viewer role may only read (writes and calls need the operator role)"
            )
            with pytest.raises(ua.UaStatusCodeError, match=r"BadUserAccessDenied.*viewer role"):
                await viewer.call("SetBeltSpeed", "left", 0.1)
            # the refusals did not end the session
            assert await viewer.read("Identification", "AssetId") == "TU_A"
            # the server refuses the raw request too, whatever the client library does
            node = await viewer._node("OperationalData", "PossessedObjects")
            value = ua.DataValue(ua.Variant("x", ua.VariantType.String))
            raw = ua.WriteValue(NodeId=node.nodeid, AttributeId=ua.AttributeIds.Value, Value=value)
            with pytest.raises(ua.UaStatusCodeError, match="BadUserAccessDenied"):
                await viewer.client.uaclient.write(ua.WriteParameters(NodesToWrite=[raw]))

    _run(scenario())
    assert calls == []
    assert tu_a.run(tu_a.server.get("OperationalData", "PossessedObjects")) == "o7"


def test_unknown_client_certificate_is_refused_until_cps_trust(tu_a, pki, tmp_path, capsys):
    stranger = tmp_path / "stranger"

    async def attempt() -> str:
        async with connect(tu_a.endpoint, "TU_A", role="operator", cert_dir=stranger,
                           trust_dir=pki.trust_dir, credentials=pki.credentials) as op:  # fmt: skip
            return await op.read("Identification", "AssetId")

    with pytest.raises(ua.UaStatusCodeError, match="BadCertificateUntrusted"):
        _run(attempt())  # right password, unknown application certificate
    cert = stranger / "client-operator.der"
    assert not TrustList(pki.trust_dir).is_trusted(cert.read_bytes())

    assert main(["cps", "trust", str(cert), "--workdir", str(pki.root)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("trusted ") and "CN=client-operator" in out
    added = Path(out.strip().rsplit(": ", 1)[1])
    assert added.parent == pki.trust_dir and added.read_bytes() == cert.read_bytes()
    try:
        assert _run(attempt()) == "TU_A"  # no restart: the list is read per session
    finally:
        added.unlink()
    with pytest.raises(ua.UaStatusCodeError, match="BadCertificateUntrusted"):
        _run(attempt())  # removed from the list: refused again


def test_activation_is_refused_for_a_channel_whose_certificate_is_not_trusted(pki, tmp_path):
    """The second check (ActivateSession) holds even for a client that ignores the refused
    CreateSession: the user manager looks at the channel's certificate itself."""
    own = (pki.cert_dir / "client-viewer.der").read_bytes()
    other, _ = asyncio.run(ensure_certificate(tmp_path, "client-viewer"))
    users = RoleUserManager(pki.credentials, TrustList(pki.trust_dir))
    name, password = pki.credentials.for_role("viewer")
    assert users.get_user(None, name, password, own).name == "viewer"
    assert users.get_user(None, name, password, other.read_bytes()) is None
    assert users.get_user(None, name, password, None) is None
    assert users.get_user(None, name, "wrong", own) is None


def test_unauthenticated_and_wrong_password_are_refused(tu_a, pki):
    async def scenario():
        for wrong in (None, new_credentials()):
            with pytest.raises(ua.UaError):
                async with connect(tu_a.endpoint, "TU_A", credentials=wrong,
                                   cert_dir=pki.cert_dir) as c:  # fmt: skip
                    await c.read("OperationalData", "BeltSpeedLeft")

    _run(scenario())


def test_read_only_variables_refuse_operator_writes(tu_a, pki):
    async def scenario():
        async with connect(tu_a.endpoint, "TU_A", **pki.client_kw()) as op:
            with pytest.raises(ua.UaStatusCodeError, match=r"BadUserAccessDenied|BadNotWritable"):
                await op.write("OperationalData", "BeltSpeedLeft", 9.0)

    _run(scenario())


def test_garbage_on_the_port_leaves_the_server_serving(tu_a, pki):
    async def scenario():
        port = int(tu_a.endpoint.split(":")[2].split("/")[0])
        for payload in (b"\x00" * 64, b"HEL" + b"\xff" * 500, b"GET / HTTP/1.1\r\n\r\n"):
            _, writer = await asyncio.open_connection("127.0.0.1", port)
            writer.write(payload)
            await writer.drain()
            writer.close()
        async with connect(tu_a.endpoint, "TU_A", **pki.client_kw()) as op:
            assert await op.read("Identification", "AssetId") == "TU_A"

    _run(scenario())


def test_handler_errors_and_wrong_argument_types_become_bad_status(tu_a, pki):
    async def refuse(belt, speed):
        if belt == "middle":
            raise ValueError("no such belt")
        if speed > 1:
            raise OperationRefused(f"{speed} m/s is too fast", argument="speed",
                                   status="BadOutOfRange")  # fmt: skip
        raise RuntimeError("a bug")

    tu_a.handle("SetBeltSpeed", refuse)

    async def scenario():
        async with connect(tu_a.endpoint, "TU_A", **pki.client_kw()) as op:
            with pytest.raises(ua.UaStatusCodeError, match="BadInvalidArgument") as exc:
                await op.call("SetBeltSpeed", "middle", 0.1)
            assert isinstance(exc.value, OperationRefused)
            assert exc.value.reason == "no such belt"  # the reason travels with the status
            assert (exc.value.asset, exc.value.operation) == ("TU_A", "SetBeltSpeed")
            with pytest.raises(OperationRefused, match="BadOutOfRange") as exc:
                await op.call("SetBeltSpeed", "left", 2.0)
            assert exc.value.reason == "2.0 m/s is too fast"
            with pytest.raises(OperationRefused, match="BadInternalError") as exc:
                await op.call("SetBeltSpeed", "left", 0.1)
            assert exc.value.reason == "internal error: RuntimeError: a bug"
            # wrong types never reach the handler; a whole number counts as a Double
            with pytest.raises(OperationRefused, match="BadTypeMismatch") as exc:
                await op.call("SetBeltSpeed", 3, 0.1)
            assert exc.value.reason == "belt must be a String, got Int64"
            with pytest.raises(OperationRefused, match="BadTypeMismatch"):
                await op.call("SetBeltSpeed", "left", "fast")
            with pytest.raises(OperationRefused, match="BadOutOfRange"):
                await op.call("SetBeltSpeed", "left", 2)
            with pytest.raises(OperationRefused, match="BadArgumentsMissing"):
                await op.call("SetBeltSpeed", "left")
            with pytest.raises(OperationRefused, match="BadTooManyArguments"):
                await op.call("SetBeltSpeed", "left", 0.1, 1)
            # the same refusal, raw: Bad status, the offending argument marked Bad with
            # the reason in its diagnostic info
            request = ua.CallMethodRequest()
            request.ObjectId = (await op._node("ControlInterface")).nodeid
            request.MethodId = (await op._node("ControlInterface", "SetBeltSpeed")).nodeid
            request.InputArguments = [ua.Variant("left"), ua.Variant(2.0)]
            (raw,) = await op.client.uaclient.call([request])
            assert raw.StatusCode.name == "BadOutOfRange"
            assert [r.is_good() for r in raw.InputArgumentResults] == [True, False]
            assert raw.InputArgumentDiagnosticInfos[1].AdditionalInfo == "2.0 m/s is too fast"
            assert await op.read("Identification", "AssetId") == "TU_A"

    _run(scenario())


def test_cps_trust_refuses_what_is_not_a_certificate(pki, tmp_path, capsys):
    key = pki.cert_dir / "client-viewer.pem"  # a private key, not a certificate
    for argv, reason in [
        ([str(key), "--workdir", str(pki.root)], "not an X.509 certificate"),
        ([str(tmp_path / "none.der"), "--workdir", str(pki.root)], "cannot read"),
        ([str(pki.cert_dir / "client-viewer.der"), "--workdir", str(tmp_path)], "no CPS there"),
    ]:
        before = sorted(p.name for p in pki.trust_dir.iterdir())
        assert main(["cps", "trust", *argv]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and reason in err[0], err
        assert sorted(p.name for p in pki.trust_dir.iterdir()) == before
    # PEM works as well as DER, and trusting twice changes nothing
    der, _ = asyncio.run(ensure_certificate(tmp_path / "outsider", "client-viewer"))
    pem = tmp_path / "viewer.pem"
    pem.write_bytes(read_certificate(der).public_bytes(Encoding.PEM))
    before = sorted(p.name for p in pki.trust_dir.iterdir())
    assert main(["cps", "trust", str(der), "--workdir", str(pki.root)]) == 0
    added = set(pki.trust_dir.iterdir()) - {pki.trust_dir / n for n in before}
    assert main(["cps", "trust", str(pem), "--workdir", str(pki.root)]) == 0
    assert set(pki.trust_dir.iterdir()) - {pki.trust_dir / n for n in before} == added
    assert len(added) == 1
    added.pop().unlink()


def test_a_usable_certificate_is_kept_and_a_wrong_one_is_made_anew(tmp_path):
    cert, key = asyncio.run(ensure_certificate(tmp_path, "TU_A"))
    first = (cert.read_bytes(), key.read_bytes())
    again = asyncio.run(ensure_certificate(tmp_path, "TU_A"))
    assert again == (cert, key) and (cert.read_bytes(), key.read_bytes()) == first
    # a certificate naming another application (copied over) is replaced, the key kept
    other, _ = asyncio.run(ensure_certificate(tmp_path, "TU_B"))
    cert.write_bytes(other.read_bytes())
    asyncio.run(ensure_certificate(tmp_path, "TU_A"))
    assert cert.read_bytes() not in (first[0], other.read_bytes()) and key.read_bytes() == first[1]
    # garbage where the certificate should be: made anew too
    cert.write_bytes(b"not a certificate")
    asyncio.run(ensure_certificate(tmp_path, "TU_A"))
    assert cert.read_bytes() != b"not a certificate" and key.read_bytes() == first[1]


def test_a_clients_key_is_parsed_once_and_a_rewritten_key_is_read_again(tu_a, pki, monkeypatch):
    import transfertwin.cps.opcua._security as security

    parsed: list[bytes] = []
    real = security.load_pem_private_key

    def counting(data, password=None, **kw):
        parsed.append(data)
        return real(data, password=password, **kw)

    monkeypatch.setattr(security, "load_pem_private_key", counting)
    monkeypatch.setattr(security, "_KEYS", {})

    async def session() -> float:
        async with connect(tu_a.endpoint, "TU_A", role="viewer", **pki.client_kw()) as c:
            return await c.read("OperationalData", "BeltSpeedLeft")

    for _ in range(3):
        _run(session())
    assert len(parsed) == 1  # three secure sessions, one parse
    key = pki.cert_dir / "client-viewer.pem"
    assert parsed[0] == key.read_bytes()
    key.write_bytes(key.read_bytes())  # rewritten (a new mtime): parsed again
    _run(session())
    assert len(parsed) == 2


def test_a_stopped_server_leaves_no_task_behind(pki):
    from transfertwin.cps.opcua import AssetServer

    async def scenario() -> list[asyncio.Task]:
        before = asyncio.all_tasks()
        async with AssetServer("TU_Z", (), pki.config(port=0)) as server:
            assert server._server.iserver.time_task is not None  # asyncua's clock runs
        await asyncio.sleep(0)
        return [t for t in asyncio.all_tasks() - before if not t.done()]

    assert _run(scenario()) == []


def test_a_servers_user_table_holds_no_password_and_checks_them(pki, tmp_path):
    """What an asset's bundle holds of the people's users: salted scrypt hashes only; the
    server still tells the operator's password from a wrong one."""
    from transfertwin.cps.opcua import UserTable, load_users, write_user_table

    table_file = write_user_table(tmp_path / "users.json", pki.credentials)
    text = table_file.read_text()
    assert table_file.stat().st_mode & 0o077 == 0
    assert all(password not in text for _, password in pki.credentials.users.values())
    table = load_users(table_file)
    assert isinstance(table, UserTable)
    users = RoleUserManager(table, TrustList(pki.trust_dir))
    own = (pki.cert_dir / "client-operator.der").read_bytes()
    name, password = pki.credentials.for_role("operator")
    assert users.get_user(None, name, password, own).name == "operator"
    assert users.get_user(None, name, password + "x", own) is None
    viewer, viewer_password = pki.credentials.for_role("viewer")
    assert users.get_user(None, viewer, viewer_password, own).name == "viewer"


def test_a_client_asks_for_a_session_the_server_grants(tu_a, pki, caplog):
    """A client asks for the session timeout the servers grant: asyncua's default hour was
    revised to 10 min with a warning on every connection, on every `cps` command's
    stderr (seen walking the tutorial)."""
    import logging

    from transfertwin.cps.opcua._client import SESSION_TIMEOUT_MS

    assert tu_a.server._server.iserver.max_session_timeout_ms == SESSION_TIMEOUT_MS

    async def scenario():
        async with connect(tu_a.endpoint, "TU_A", role="viewer", **pki.client_kw()) as s:
            await s.read("OperationalData", "BeltSpeedLeft")

    with caplog.at_level(logging.WARNING, logger="asyncua"):
        _run(scenario())
    assert not [r for r in caplog.records if "session timeout" in r.getMessage()]
