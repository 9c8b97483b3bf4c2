"""An asset's OPC UA server, its address space generated from its AAS (Sec. 3.1, 5.3).

Structure (after the OPC UA for AAS companion specification, simplified):
``Objects/AAS_<id>/`` holds one object per submodel, named by its idShort; a Property becomes
a variable of the matching OPC UA data type, an Operation a method with the operation's input
and output variables as arguments, a Capability an object carrying its semantic id, a
SubmodelElementCollection an object holding its elements, a RelationshipElement an object
with the keys of its ends (``First``, ``Second``). All nodes live in the namespace
``urn:transfertwin:aas`` with string node ids ``<asset>.<submodel>.<element>`` (an element
inside collections: ``<asset>.<submodel>.<collection>.<element>``), so a client addresses
every asset the same way.
Deviations from the companion specification: no AAS object/variable *types* are
instantiated (plain folders, objects and variables), and references are not modelled.

Async context manager; secure by default (see `_security`: trust list of client
certificates, viewer/operator roles, peer assets' identities; `_caller`: who calls a
handler, registrations only over SignAndEncrypt from the asset registered). Variables listed
as writable accept client writes (external state synchronisation) from operators and peer
assets; all others are updated by the asset itself through `set`.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable, Mapping
from contextlib import suppress
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import basyx.aas.model as aas
from asyncua import Server, ua
from asyncua.common.callback import CallbackType
from asyncua.common.node import Node
from cryptography import x509

from transfertwin._aio import stop_tasks
from transfertwin.cps.opcua._aspace import share_standard_address_space
from transfertwin.cps.opcua._ca import CA_CERT, FloorCA, install_certificate, new_request
from transfertwin.cps.opcua._caller import guard
from transfertwin.cps.opcua._security import (
    Credentials,
    RoleRuleset,
    RoleUserManager,
    TrustList,
    UserTable,
    ensure_certificate,
    free_port,
    parsed_private_key,
)

__all__ = ["NAMESPACE", "AssetServer", "Handler", "OperationRefused", "ServerConfig", "node_id"]

log = logging.getLogger(__name__)

NAMESPACE = "urn:transfertwin:aas"
SECURE_POLICY = "Basic256Sha256_SignAndEncrypt"

Handler = Callable[..., Awaitable[Any]]

_VARIANT = {
    bool: ua.VariantType.Boolean,
    float: ua.VariantType.Double,
    int: ua.VariantType.Int64,
    str: ua.VariantType.String,
}
_DEFAULTS = {bool: False, float: 0.0, int: 0, str: ""}


class OperationRefused(ua.UaStatusCodeError):
    """An asset refused an operation call, with the reason.

    Handlers raise it (a `ValueError` counts as a refusal with status BadInvalidArgument);
    the server answers the call with the Bad status `status`, marks the offending input
    argument Bad and puts `reason` into that argument's diagnostic info
    (``AdditionalInfo``); `AssetClient.call` raises it again on the client side. It is a
    `ua.UaStatusCodeError`, so `code` is the numeric status code.

    Args:
        reason: One line saying why.
        status: Name of an OPC UA status code, e.g. 'BadInvalidArgument' (a name or value
            that is wrong) or 'BadInvalidState' (a request that conflicts with the state).
        argument: Name of the offending input argument (None: the first argument).
        asset: The refusing asset (set by the client).
        operation: The refused operation (set by the client).
    """

    def __new__(cls, *args: object, **kwargs: object) -> OperationRefused:
        return Exception.__new__(cls)  # not UaStatusCodeError's lookup by code

    def __init__(
        self,
        reason: str,
        *,
        status: str = "BadInvalidArgument",
        argument: str | None = None,
        asset: str = "",
        operation: str = "",
    ) -> None:
        Exception.__init__(self, getattr(ua.StatusCodes, status))
        self.reason = reason
        self.status = status
        self.argument = argument
        self.asset = asset
        self.operation = operation

    def __str__(self) -> str:
        where = f"{self.asset}.{self.operation}" if self.asset else self.operation
        return f"{self.status}: {where + ' refused: ' if where else ''}{self.reason}"


def _refusal(exc: OperationRefused, names: list[str]) -> ua.CallMethodResult:
    """The CallMethodResult of a refused call: Bad status, reason on the bad argument."""
    res = ua.CallMethodResult()
    res.StatusCode = ua.StatusCode(exc.code)
    bad = names.index(exc.argument) if exc.argument in names else 0
    res.InputArgumentResults = [
        ua.StatusCode(ua.StatusCodes.BadInvalidArgument if i == bad else ua.StatusCodes.Good)
        for i in range(len(names))
    ]
    res.InputArgumentDiagnosticInfos = [
        ua.DiagnosticInfo(AdditionalInfo=exc.reason if i == bad else None)
        for i in range(len(names))
    ]
    return res


def _python_type(value_type: type) -> type:
    for base in (bool, float, int, str):
        if issubclass(value_type, base):
            return base
    return str


def node_id(asset_id: str, *parts: str) -> str:
    """The string node id of an element: ``<asset>.<submodel>.<element>``."""
    return ".".join((asset_id, *parts))


@dataclass(frozen=True)
class ServerConfig:
    """How an asset server listens.

    Attributes:
        host: Interface to bind (loopback by default).
        port: TCP port; 0 picks a free one.
        insecure: Serve NoSecurity without users (explicit opt-in only).
        cert_dir: Where application certificates are created on first start.
        credentials: The people's users: passwords per role, or only their hashes
            (`UserTable`; required unless insecure).
        trust_dir: The trust list: client certificates accepted (None: ``cert_dir/trusted``);
            on a floor, the floor CA's certificate and CRL (`transfertwin.cps.opcua.FloorCA`).
        peer_roles: (asset id, role) of the peer assets that may open sessions with their
            application certificate as X.509 identity (none: only user names).
        issuer: A CA that issues the server's certificate when it has none (one host, a
            test); None: a server without one under a CA makes its key and signing request
            and stops with a line naming them (`ensure_certificate`).
        reread_s: How often the trust list is read again for revocations: the sessions
            of a client whose certificate was revoked are closed within this period.
    """

    host: str = "127.0.0.1"
    port: int = 0
    insecure: bool = False
    cert_dir: Path = Path("certs")
    credentials: Credentials | UserTable | None = None
    trust_dir: Path | None = None
    peer_roles: tuple[tuple[str, str], ...] = ()
    issuer: FloorCA | None = field(default=None, compare=False)
    reread_s: float = 2.0

    @property
    def trust_folder(self) -> Path:
        """The folder of trusted client certificates."""
        return self.trust_dir if self.trust_dir is not None else self.cert_dir / "trusted"


@dataclass
class AssetServer:
    """The OPC UA server of one asset.

    Args:
        asset_id: The asset's id.
        submodels: Its AAS submodels (basyx objects).
        config: Listening and security settings.
        handlers: Operation idShort → async callable(*inputs) returning the outputs (a
            value or a tuple in the order of the operation's output variables).
        writable: (submodel, property) pairs clients may write.
    """

    asset_id: str
    submodels: tuple[aas.Submodel, ...]
    config: ServerConfig = field(default_factory=ServerConfig)
    handlers: Mapping[str, Handler] = field(default_factory=dict)
    writable: frozenset[tuple[str, str]] = frozenset()
    endpoint: str = ""
    _server: Server | None = None
    _nodes: dict[tuple[str, str], Node] = field(default_factory=dict)
    _types: dict[tuple[str, str], type] = field(default_factory=dict)
    _ns: int = 0
    _write_listeners: list[Callable[[str, str, Any], None]] = field(default_factory=list)
    _keys: dict[ua.NodeId, tuple[str, str]] = field(default_factory=dict)
    _watch: asyncio.Task | None = None

    @property
    def security_policy(self) -> str:
        """The security policy the endpoint offers."""
        return "None" if self.config.insecure else SECURE_POLICY

    async def __aenter__(self) -> AssetServer:
        cfg = self.config
        if not cfg.insecure and cfg.credentials is None:
            raise ValueError("a secure asset server needs credentials")
        trust = None if cfg.insecure else TrustList(cfg.trust_folder)
        users = (RoleUserManager(cfg.credentials, trust, dict(cfg.peer_roles))
                 if cfg.credentials else None)  # fmt: skip
        server = Server(user_manager=users)
        share_standard_address_space(server)
        await server.init()
        port = cfg.port or free_port(cfg.host)
        self.endpoint = f"opc.tcp://{cfg.host}:{port}/transfertwin/{self.asset_id}"
        server.set_endpoint(self.endpoint)
        server.set_server_name(f"transfertwin {self.asset_id}")
        await server.set_application_uri(f"urn:transfertwin:{self.asset_id}")
        if cfg.insecure:
            server.set_security_policy([ua.SecurityPolicyType.NoSecurity])
        else:
            cert, key = await self._certificate()
            await server.load_certificate(str(cert))
            # what Server.load_private_key does, with the key parsed once per process
            server.iserver.private_key = parsed_private_key(key)
            server.set_security_policy(
                [ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt],
                permission_ruleset=RoleRuleset(),
            )
            tokens = [ua.UserNameIdentityToken]
            server.set_identity_tokens([*tokens, ua.X509IdentityToken] if cfg.peer_roles
                                       else tokens)  # fmt: skip
            server.set_certificate_validator(trust)
            guard(server.iserver, trust)  # registrations: secure, trusted, its own URI
        server.subscribe_server_callback(CallbackType.PostWrite, self._written)
        self._ns = await server.register_namespace(NAMESPACE)
        await self._build(server)
        self._keys = {n.nodeid: key for key, n in self._nodes.items()}
        await server.start()
        self._server = server
        if trust is not None:
            self._watch = asyncio.ensure_future(self._watch_revocations(trust))
        log.info("%s serving at %s (%s)", self.asset_id, self.endpoint, self.security_policy)
        return self

    async def _certificate(self) -> tuple[Path, Path]:
        """The server's application certificate and key (`ServerConfig.issuer`)."""
        cfg, name = self.config, self.asset_id
        pending = cfg.cert_dir / f"{name}.csr.pem"
        if not (cfg.cert_dir / f"{name}.der").is_file():
            if cfg.issuer is not None:
                csr = new_request(cfg.cert_dir, name, cfg.host)
                install_certificate(cfg.cert_dir, name, cfg.issuer.issue(csr))
            elif (cfg.trust_folder / CA_CERT).is_file() and not pending.is_file():
                new_request(cfg.cert_dir, name, cfg.host)  # ensure_certificate names it
        return await ensure_certificate(cfg.cert_dir, name, cfg.host)

    async def _watch_revocations(self, trust: TrustList) -> None:
        """Every `reread_s`: read the trust list again, and close the connections of
        clients whose certificates it revokes now (new ones are refused at CreateSession)."""
        seen = trust.revoked()
        while True:
            await asyncio.sleep(self.config.reread_s)
            revoked = trust.revoked()
            if revoked != seen:
                seen = revoked
                self.drop_revoked(revoked)

    def drop_revoked(self, serials: frozenset[int]) -> int:
        """Close every client connection whose certificate's serial is in `serials`."""
        dropped = 0
        for proto in list(self._server.bserver.clients if self._server.bserver else []):
            conn = getattr(getattr(proto, "processor", None), "_connection", None)
            der = conn.security_policy.peer_certificate if conn is not None else None
            if der and x509.load_der_x509_certificate(der).serial_number in serials:
                log.warning("%s: closed the connection of a revoked certificate (%s)",
                            self.asset_id, proto.peer_name)  # fmt: skip
                proto.transport.close()
                dropped += 1
        return dropped

    async def __aexit__(self, *exc: object) -> None:
        if self._watch is not None:
            await stop_tasks([self._watch])
            self._watch = None
        if self._server is not None:
            # asyncua's stop waits for its clock task to finish its 1 s sleep (each server,
            # each stop); the task only writes CurrentTime, so it is cancelled instead.
            iserver = self._server.iserver
            if iserver.time_task is not None:
                iserver.time_task.cancel()
                with suppress(asyncio.CancelledError):
                    await iserver.time_task
                iserver.time_task = None
            await self._server.stop()
            self._server = None

    # -- address space ----------------------------------------------------------------
    async def _build(self, server: Server) -> None:
        root = await server.nodes.objects.add_folder(
            ua.NodeId(node_id(self.asset_id), self._ns), f"{self._ns}:AAS_{self.asset_id}"
        )
        for sm in self.submodels:
            sm_node = await root.add_object(
                ua.NodeId(node_id(self.asset_id, sm.id_short), self._ns),
                f"{self._ns}:{sm.id_short}",
            )
            for element in sm.submodel_element:
                await self._add_element(sm_node, sm.id_short, element)

    async def _add_element(self, parent: Node, sm: str, element: aas.SubmodelElement,
                           path: tuple[str, ...] = ()) -> None:  # fmt: skip
        """Add `element` (inside the collections `path` of submodel `sm`) below `parent`; an
        element inside a collection is addressed by its dotted path, e.g.
        ``TransferRelations.Constraints.BeltWidth``."""
        key = ".".join((*path, element.id_short))
        nid = ua.NodeId(node_id(self.asset_id, sm, key), self._ns)
        name = f"{self._ns}:{element.id_short}"
        if isinstance(element, aas.Property):
            ptype = _python_type(element.value_type)
            value = element.value if element.value is not None else _DEFAULTS[ptype]
            var = await parent.add_variable(nid, name, ua.Variant(ptype(value), _VARIANT[ptype]))
            if (sm, key) in self.writable:
                await var.set_writable()
            self._nodes[(sm, key)] = var
            self._types[(sm, key)] = ptype
        elif isinstance(element, aas.Operation):
            await self._add_method(parent, nid, name, element)
        elif isinstance(element, aas.Capability):
            sem = element.semantic_id.key[0].value if element.semantic_id else ""
            await self._add_strings(await parent.add_object(nid, name), sm, key,
                                    {"SemanticId": sem})  # fmt: skip
        elif isinstance(element, aas.SubmodelElementCollection):
            folder = await parent.add_object(nid, name)
            for child in element.value:
                await self._add_element(folder, sm, child, (*path, element.id_short))
        elif isinstance(element, aas.RelationshipElement):
            # the ends as the referenced elements' keys, e.g. <submodel id>/<idShort>
            ends = {"First": element.first, "Second": element.second}
            await self._add_strings(await parent.add_object(nid, name), sm, key,
                                    {k: "/".join(x.value for x in r.key)
                                     for k, r in ends.items()})  # fmt: skip

    async def _add_strings(self, node: Node, sm: str, key: str, values: dict[str, str]) -> None:
        """Constant string properties of an object node (a capability's semantic id, a
        relationship's ends)."""
        for prop, value in values.items():
            pid = ua.NodeId(node_id(self.asset_id, sm, key, prop), self._ns)
            await node.add_property(pid, f"{self._ns}:{prop}", value)

    async def _add_method(self, parent: Node, nid: ua.NodeId, name: str, op: aas.Operation) -> None:
        ins = [(v.id_short, _python_type(v.value_type)) for v in op.input_variable]
        outs = [(v.id_short, _python_type(v.value_type)) for v in op.output_variable]
        handler = self.handlers.get(op.id_short)

        async def call(_parent: ua.NodeId, *args: ua.Variant) -> Any:
            # A bad request becomes a status code (and the reason) for the caller, never a
            # server failure.
            if len(args) < len(ins):
                return ua.StatusCode(ua.StatusCodes.BadArgumentsMissing)
            if len(args) > len(ins):
                return ua.StatusCode(ua.StatusCodes.BadTooManyArguments)
            try:
                values = [_coerce(n, t, a) for (n, t), a in zip(ins, args, strict=True)]
                if handler is None:
                    return ua.StatusCode(ua.StatusCodes.BadNotImplemented)
                result = await handler(*values)
            except OperationRefused as exc:
                refused = exc
            except (ValueError, KeyError, TypeError) as exc:
                refused = OperationRefused(str(exc).strip("'\""))
            except Exception as exc:  # a bug in the asset: say so, keep serving
                log.exception("%s.%s failed", self.asset_id, op.id_short)
                refused = OperationRefused(f"internal error: {type(exc).__name__}: {exc}",
                                           status="BadInternalError")  # fmt: skip
            else:
                result = result if isinstance(result, tuple) else (result,)
                return [ua.Variant(t(v), _VARIANT[t])
                        for (_, t), v in zip(outs, result, strict=True)]  # fmt: skip
            log.info("%s.%s refused: %s", self.asset_id, op.id_short, refused.reason)
            return _refusal(refused, [n for n, _ in ins])

        in_args = [_argument(n, t) for n, t in ins]
        out_args = [_argument(n, t) for n, t in outs]
        await parent.add_method(nid, name, call, in_args, out_args)

    # -- discovery ------------------------------------------------------------------------
    def register_peer(self, uri: str, url: str, name: str) -> None:
        """Answer FindServers with this peer too (decentralised discovery)."""
        registered = ua.RegisteredServer()
        registered.ServerUri = uri
        registered.ProductUri = "urn:transfertwin"
        registered.ServerNames = [ua.LocalizedText(name)]
        registered.ServerType = ua.ApplicationType.Server
        registered.DiscoveryUrls = [url]
        registered.IsOnline = True
        self._server.iserver.register_server(registered)

    def registered_peers(self) -> list[tuple[str, str]]:
        """(application URI, discovery URL) of every server registered here."""
        out = []
        for uri, desc in list(self._server.iserver._known_servers.items()):
            urls = desc.Server.DiscoveryUrls
            if uri != f"urn:transfertwin:{self.asset_id}" and urls:
                out.append((uri, urls[0]))
        return out

    def unregister_peer(self, uri: str) -> None:
        """Stop answering FindServers with a peer that left."""
        self._server.iserver._known_servers.pop(uri, None)

    # -- values ---------------------------------------------------------------------------
    def on_client_write(self, listener: Callable[[str, str, Any], None]) -> Callable[[], None]:
        """Call `listener(submodel, property, value)` for every accepted client write, in the
        order the server applied them (a write the server refused is not reported).

        Returns:
            A function that removes the listener again.
        """
        self._write_listeners.append(listener)
        return lambda: self._write_listeners.remove(listener)

    def _written(self, event: Any, _dispatcher: Any) -> None:
        if not self._write_listeners:
            return
        results = event.response_params or []
        for wv, status in zip(event.request_params.NodesToWrite, results, strict=False):
            key = self._keys.get(wv.NodeId)
            if key is not None and status.is_good():
                for listener in self._write_listeners:
                    listener(*key, wv.Value.Value.Value)

    async def set(self, submodel: str, prop: str, value: Any) -> None:
        """Update a variable (the asset synchronising its own state)."""
        ptype = self._types[(submodel, prop)]
        await self._nodes[(submodel, prop)].write_value(ua.Variant(ptype(value), _VARIANT[ptype]))

    async def get(self, submodel: str, prop: str) -> Any:
        """Current value of a variable."""
        return await self._nodes[(submodel, prop)].read_value()


def _coerce(name: str, ptype: type, arg: ua.Variant) -> Any:
    """An input argument as the declared Python type; any integer type is accepted for an
    Int64 and integers and Floats for a Double. Anything else is refused (BadTypeMismatch
    on that argument)."""
    vtype = arg.VariantType
    if not arg.is_array:
        if vtype == _VARIANT[ptype]:
            return arg.Value
        if ptype is int and vtype in _INTS:
            return int(arg.Value)
        if ptype is float and (vtype in _INTS or vtype == ua.VariantType.Float):
            return float(arg.Value)
    raise OperationRefused(
        f"{name} must be a {_VARIANT[ptype].name}, got {vtype.name}"
        + (" array" if arg.is_array else ""), status="BadTypeMismatch", argument=name,
    )  # fmt: skip


_INTS = frozenset(
    getattr(ua.VariantType, t)
    for t in ("SByte", "Byte", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64")
)


def _argument(name: str, ptype: type) -> ua.Argument:
    arg = ua.Argument()
    arg.Name = name
    arg.DataType = ua.NodeId(_VARIANT[ptype].value)
    arg.ValueRank = -1
    arg.Description = ua.LocalizedText(name)
    return arg
