"""Clients of asset servers: secure sessions and AAS-addressed reads, writes and calls."""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any

from asyncua import Client, ua
from asyncua.common.utils import ServiceError
from asyncua.crypto import uacrypto
from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256

from transfertwin.cps.opcua._security import (
    Credentials,
    TrustList,
    ensure_certificate,
    parsed_private_key,
    read_certificate,
)
from transfertwin.cps.opcua._server import NAMESPACE, OperationRefused, node_id

__all__ = ["AssetClient", "UntrustedServer", "connect", "trust_list"]


_DENIED = ua.StatusCodes.BadUserAccessDenied
#: The session timeout a client asks for: asyncua's servers grant at most 10 min
#: (``max_session_timeout_ms``), and a client asking for its default hour was revised
#: down with a warning on every connection (every `cps` command's stderr showed it).
SESSION_TIMEOUT_MS = 600_000


class AssetClient:
    """A session with one asset server, addressing nodes by AAS idShorts.

    Args:
        client: The connected asyncua client.
        asset_id: The asset served.
        role: The role the session was opened with (for error messages).
    """

    def __init__(self, client: Client, asset_id: str, role: str = "operator") -> None:
        self.client = client
        self.asset_id = asset_id
        self.role = role
        self._ns: int | None = None
        self._vtypes: dict[tuple[str, ...], ua.VariantType] = {}

    def _denied(self, what: str) -> OperationRefused:
        return OperationRefused(
            f"the {self.role} role may only read (writes and calls need the operator role)",
            status="BadUserAccessDenied", asset=self.asset_id, operation=what,
        )  # fmt: skip

    async def _node(self, *parts: str):
        if self._ns is None:
            self._ns = await self.client.get_namespace_index(NAMESPACE)
        return self.client.get_node(ua.NodeId(node_id(self.asset_id, *parts), self._ns))

    async def read(self, submodel: str, prop: str) -> Any:
        """Value of a property."""
        return await (await self._node(submodel, prop)).read_value()

    async def write(self, submodel: str, prop: str, value: Any) -> None:
        """Write a property (needs the operator role and a writable variable).

        Raises:
            OperationRefused: BadUserAccessDenied for a session without the operator role.
            ua.UaStatusCodeError: Other Bad statuses (e.g. BadNotWritable, BadTypeMismatch).
        """
        node = await self._node(submodel, prop)
        vtype = self._vtypes.get((submodel, prop))
        if vtype is None:
            vtype = self._vtypes[(submodel, prop)] = await node.read_data_type_as_variant_type()
        try:
            await node.write_value(ua.DataValue(ua.Variant(value, vtype)))
        except ua.UaStatusCodeError as exc:
            if exc.code == _DENIED and not isinstance(exc, OperationRefused):
                raise self._denied(f"write {submodel}.{prop}") from None
            raise

    async def call(self, operation: str, *args: Any, submodel: str = "ControlInterface") -> Any:
        """Call an operation; returns its single output or a list of outputs.

        Raises:
            OperationRefused: The asset answered with a Bad status; the reason is the
                diagnostic info the asset attached (or the status code's description).
        """
        parent = await self._node(submodel)
        method = await self._node(submodel, operation)
        request = ua.CallMethodRequest()
        request.ObjectId = parent.nodeid
        request.MethodId = method.nodeid
        request.InputArguments = [a if isinstance(a, ua.Variant) else ua.Variant(a) for a in args]
        try:
            (result,) = await self.client.uaclient.call([request])
        except ua.UaStatusCodeError as exc:
            if exc.code == _DENIED:
                raise self._denied(operation) from None
            raise
        if not result.StatusCode.is_good():
            infos = result.InputArgumentDiagnosticInfos or []
            reason = next((d.AdditionalInfo for d in infos if d and d.AdditionalInfo), None)
            name = result.StatusCode.name
            raise OperationRefused(
                reason or ua.status_codes.get_name_and_doc(result.StatusCode.value)[1].rstrip("."),
                status=name, asset=self.asset_id, operation=operation,
            )  # fmt: skip
        outputs = [v.Value for v in result.OutputArguments or []]
        if not outputs:
            return None
        return outputs[0] if len(outputs) == 1 else outputs

    async def subscribe(self, handler: object, *props: tuple[str, str], period_ms: int = 50):
        """Subscribe `handler.datachange_notification` to (submodel, property) pairs."""
        sub = await self.client.create_subscription(period_ms, handler)
        nodes = [await self._node(sm, p) for sm, p in props]
        await sub.subscribe_data_change(nodes)
        return sub


class UntrustedServer(ua.UaError):
    """The server a client reached is not the one it meant: its certificate is not
    trusted (no CA here signed it, or it is revoked or outside its validity) or names
    another application. Raised before the client sends any credential.

    Attributes:
        status: The OPC UA status code's name (BadCertificateUntrusted, ...UriInvalid, ...).
        endpoint: The server's URL.
    """

    def __init__(self, endpoint: str, asset_id: str, status: int) -> None:
        self.status = ua.StatusCode(status).name
        self.endpoint = endpoint
        super().__init__(f"{endpoint} is not {asset_id} of this floor ({self.status}): "
                         "refused before any credential was sent")  # fmt: skip


_TRUST: dict[Path, TrustList] = {}


def trust_list(folder: Path) -> TrustList:
    """The `TrustList` of `folder`, one per folder and process (it caches what it read)."""
    folder = Path(folder).resolve()
    trust = _TRUST.get(folder)
    if trust is None:
        if len(_TRUST) >= 256:
            _TRUST.clear()
        trust = _TRUST[folder] = TrustList(folder)
    return trust


async def _secure(client: Client, cert: Path, key: Path, endpoint_url: str,
                  asset_id: str) -> None:  # fmt: skip
    """What `Client.set_security(Basic256Sha256, cert, key)` does in SignAndEncrypt mode,
    with the server's certificate checked first (the client's ``certificate_validator``:
    `TrustList.server_validator`, before the secure channel is opened; asyncua checks it
    again at CreateSession) and the private key parsed once per process: asyncua parses the
    key file on every connection, and an RSA key's validation costs ~45 ms."""
    mode = ua.MessageSecurityMode.SignAndEncrypt
    endpoints = await client.connect_and_get_server_endpoints()  # over SecurityPolicy None
    endpoint = Client.find_endpoint(endpoints, mode, SecurityPolicyBasic256Sha256.URI)
    # x509_from_der takes the server's certificate, also where its chain follows it
    server_cert = uacrypto.x509_from_der(endpoint.ServerCertificate)
    try:
        await client.certificate_validator(server_cert, endpoint.Server)
    except ServiceError as exc:
        raise UntrustedServer(endpoint_url, asset_id, exc.code) from None
    policy = SecurityPolicyBasic256Sha256(
        server_cert, read_certificate(cert), parsed_private_key(key), mode
    )
    client.security_policy = policy
    client.uaclient.set_security(policy)


@asynccontextmanager
async def connect(
    endpoint: str,
    asset_id: str,
    *,
    credentials: Credentials | None,
    role: str = "operator",
    cert_dir: Path = Path("certs"),
    insecure: bool = False,
    timeout_s: float = 10.0,
    watchdog_s: float | None = None,
    trust_dir: Path | None = None,
    certificate: str | None = None,
) -> AsyncIterator[AssetClient]:
    """A session with asset `asset_id`'s server (secure unless `insecure`).

    The client's application certificate is ``cert_dir/<certificate>.der`` (default
    ``client-<role>``; created self-signed on first use where no CA issued one); the server
    accepts it only if it trusts it. The server's certificate is checked before anything
    is sent: trusted by ``trust_dir`` (default ``cert_dir/trusted``: on a floor, the CA
    and its CRL) and naming ``urn:transfertwin:<asset_id>`` (`UntrustedServer` otherwise).
    The user is `role` with `credentials` (a person), or, with ``credentials=None`` on a
    secure session, the application certificate itself (an X.509 identity: a peer asset).
    asyncua probes an open session every `watchdog_s` seconds (default: 10 s or
    `timeout_s`, the longer).

    Raises:
        UntrustedServer: The server is not `asset_id` of this floor.
        ua.UaStatusCodeError: BadCertificateUntrusted (the server does not trust this
            client's certificate), BadUserAccessDenied (wrong credentials), ...
    """
    # asyncua probes the connection every `watchdog_intervall` seconds and drops it when a
    # probe takes longer than that (1 s by default): a busy server (load test, 14 servers on
    # two cores, an event loop that also runs the simulation) lost its clients mid-operation.
    # A probe may take as long as any request, and runs at most every 10 s.
    watchdog = max(10.0, timeout_s) if watchdog_s is None else watchdog_s
    client = Client(url=endpoint, timeout=timeout_s, watchdog_intervall=watchdog)
    client.session_timeout = SESSION_TIMEOUT_MS
    name = certificate or f"client-{role}"
    client.application_uri = f"urn:transfertwin:{name}"
    if not insecure:
        cert, key = await ensure_certificate(cert_dir, name)
        trust = trust_list(trust_dir if trust_dir is not None else cert_dir / "trusted")
        client.certificate_validator = trust.server_validator(f"urn:transfertwin:{asset_id}")
        await _secure(client, cert, key, endpoint, asset_id)
        if credentials is None:  # the application's certificate is the user (a peer asset)
            client.user_certificate = read_certificate(cert)
            client.user_private_key = parsed_private_key(key)
    if credentials is not None:
        user, password = credentials.for_role(role)
        client.set_user(user)
        client.set_password(password)
    async with client:
        yield AssetClient(client, asset_id, role)
