"""Asset servers on loopback: secure by default, roles enforced, robust to garbage."""

from __future__ import annotations

import asyncio

import pytest
from asyncua import ua

from transfertwin.cps.aas._demo import demo_descriptors
from transfertwin.cps.aas._representation import build_representation, externally_synced
from transfertwin.cps.opcua._client import connect
from transfertwin.cps.opcua._security import new_credentials
from transfertwin.cps.opcua._server import AssetServer, OperationRefused, ServerConfig


def _tu():
    return next(d for d in demo_descriptors() if d.asset_id == "TU_A")


async def _serve(tmp_path, creds, **handlers):
    rep = build_representation(_tu())
    writable = frozenset(("OperationalData", p) for p in externally_synced(rep))
    cfg = ServerConfig(cert_dir=tmp_path / "certs", credentials=creds)
    return AssetServer("TU_A", rep.submodels, cfg, handlers, writable)


def _run(coro):
    return asyncio.run(asyncio.wait_for(coro, timeout=120))


def test_operator_calls_and_writes_observer_only_reads(tmp_path):
    creds = new_credentials()

    async def scenario():
        calls = []

        async def set_speed(belt, speed):
            calls.append((belt, speed))
            await server.set("OperationalData", "BeltSpeedLeft", speed)
            return True

        server = await _serve(tmp_path, creds, SetBeltSpeed=set_speed)
        async with server:
            assert server.security_policy == "Basic256Sha256_SignAndEncrypt"
            kw = {"credentials": creds, "cert_dir": tmp_path / "certs"}
            async with connect(server.endpoint, "TU_A", role="operator", **kw) as op:
                assert await op.call("SetBeltSpeed", "left", 0.15) is True
                assert await op.read("OperationalData", "BeltSpeedLeft") == 0.15
                await op.write("OperationalData", "PossessedObjects", "o5")
            async with connect(server.endpoint, "TU_A", role="observer", **kw) as obs:
                assert await obs.read("OperationalData", "PossessedObjects") == "o5"
                with pytest.raises(ua.UaStatusCodeError, match="BadUserAccessDenied"):
                    await obs.write("OperationalData", "PossessedObjects", "x")
                with pytest.raises(ua.UaStatusCodeError, match="BadUserAccessDenied"):
                    await obs.call("SetBeltSpeed", "left", 0.1)
            assert calls == [("left", 0.15)]
            assert await server.get("OperationalData", "PossessedObjects") == "o5"

    _run(scenario())


def test_unauthenticated_and_wrong_password_are_refused(tmp_path):
    creds, other = new_credentials(), new_credentials()

    async def scenario():
        async with await _serve(tmp_path, creds) as server:
            for wrong in (None, other):
                with pytest.raises(ua.UaError):
                    async with connect(server.endpoint, "TU_A", credentials=wrong,
                                       cert_dir=tmp_path / "certs") as c:  # fmt: skip
                        await c.read("OperationalData", "BeltSpeedLeft")

    _run(scenario())


def test_read_only_variables_refuse_operator_writes(tmp_path):
    creds = new_credentials()

    async def scenario():
        async with (
            await _serve(tmp_path, creds) as server,
            connect(server.endpoint, "TU_A", credentials=creds, cert_dir=tmp_path / "certs") as op,
        ):
            with pytest.raises(ua.UaStatusCodeError):
                await op.write("OperationalData", "BeltSpeedLeft", 9.0)

    _run(scenario())


def test_garbage_on_the_port_leaves_the_server_serving(tmp_path):
    creds = new_credentials()

    async def scenario():
        async with await _serve(tmp_path, creds) as server:
            port = int(server.endpoint.split(":")[2].split("/")[0])
            for payload in (b"\x00" * 64, b"HEL" + b"\xff" * 500, b"GET / HTTP/1.1\r\n\r\n"):
                _, writer = await asyncio.open_connection("127.0.0.1", port)
                writer.write(payload)
                await writer.drain()
                writer.close()
            async with connect(server.endpoint, "TU_A", credentials=creds,
                               cert_dir=tmp_path / "certs") as op:  # fmt: skip
                assert await op.read("Identification", "AssetId") == "TU_A"

    _run(scenario())


def test_handler_errors_become_bad_status_not_crashes(tmp_path):
    creds = new_credentials()

    async def refuse(belt, speed):
        if belt == "middle":
            raise ValueError("no such belt")
        if speed > 1:
            raise OperationRefused(f"{speed} m/s is too fast", argument="speed",
                                   status="BadOutOfRange")  # fmt: skip
        raise RuntimeError("a bug")

    async def scenario():
        async with (
            await _serve(tmp_path, creds, SetBeltSpeed=refuse) as server,
            connect(server.endpoint, "TU_A", credentials=creds, cert_dir=tmp_path / "certs") as op,
        ):
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
