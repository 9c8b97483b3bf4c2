"""Who is calling: the caller of a request, known to the handler that serves it, and the
registration services refused below the floor's security (docs/security.md, "Identities").

asyncua tells an operation's handler nothing about the session that called it, and it
serves the session-less discovery services RegisterServer and RegisterServer2 on any
secure channel, even one without security, with no user and no check. Both are closed
here, in asyncua's one place that sees the channel, the session and the request together:
its per-connection processor (`GuardedProcessor`, installed as the processor of every
server of this process; a server not `secure`'d by `guard` behaves as asyncua's).

- A handler reads `current_caller()`: the channel's security mode, the URIs of the
  client's application certificate, the session's role and, for a peer asset that
  authenticated with its certificate (an X.509 identity), its asset id. The knowledge
  graph refuses a heartbeat, or a leave, in another asset's name with it.
- On a server `guard` was given a trust list, a registration is refused with a status
  unless it comes over SignAndEncrypt (else BadSecurityModeInsufficient), from a client
  whose application certificate is trusted (BadCertificateUntrusted, ...Revoked,
  ...TimeInvalid) and names the server it registers (BadCertificateUriInvalid): asset A
  registers A, nobody registers B. A session (so any heartbeat, call, read or write) is
  refused over a channel without security too, at CreateSession and ActivateSession
  (BadSecurityModeInsufficient), not only later for its missing certificate; only
  GetEndpoints and FindServers, which say how to connect, are answered on such a channel.
"""

from __future__ import annotations

import contextvars
import logging
from dataclasses import dataclass
from weakref import WeakKeyDictionary

from asyncua import ua
from asyncua.common.utils import ServiceError
from asyncua.server import binary_server_asyncio
from asyncua.server.uaprocessor import UaProcessor
from asyncua.ua.ua_binary import struct_from_binary
from cryptography import x509

from transfertwin.cps.opcua._security import TrustList, certificate_uris

__all__ = ["Caller", "GuardedProcessor", "current_caller", "guard"]

log = logging.getLogger(__name__)

_URI_PREFIX = "urn:transfertwin:"


@dataclass(frozen=True)
class Caller:
    """The client of the request being served.

    Attributes:
        secure: Whether its channel is signed and encrypted.
        uris: The URIs its application certificate names (empty without security).
        role: Its session's role ('operator', 'viewer', a peer asset's role), None
            without a session.
        asset_id: The peer asset it authenticated as with its certificate (X.509
            identity), None for a person or without a session.
    """

    secure: bool
    uris: tuple[str, ...] = ()
    role: str | None = None
    asset_id: str | None = None


_CALLER: contextvars.ContextVar[Caller | None] = contextvars.ContextVar("caller", default=None)

#: The servers whose registrations are checked, with their trust lists.
_GUARDED: WeakKeyDictionary[object, TrustList] = WeakKeyDictionary()

_SESSION = {
    ua.NodeId(ua.ObjectIds.CreateSessionRequest_Encoding_DefaultBinary),
    ua.NodeId(ua.ObjectIds.ActivateSessionRequest_Encoding_DefaultBinary),
}

_REGISTER = {
    ua.NodeId(ua.ObjectIds.RegisterServerRequest_Encoding_DefaultBinary): ua.RegisteredServer,
    ua.NodeId(ua.ObjectIds.RegisterServer2Request_Encoding_DefaultBinary):
        ua.RegisterServer2Parameters,
}  # fmt: skip


def current_caller() -> Caller | None:
    """The caller of the request this handler serves (None outside a request)."""
    return _CALLER.get()


def guard(iserver: object, trust: TrustList) -> None:
    """Check registrations at this server (its asyncua `InternalServer`) against `trust`."""
    _GUARDED[iserver] = trust


def _uris(der: bytes | None) -> tuple[str, ...]:
    if not der:
        return ()
    try:
        return tuple(certificate_uris(x509.load_der_x509_certificate(bytes(der))))
    except ValueError:
        return ()


class GuardedProcessor(UaProcessor):
    """asyncua's processor of one connection, which also says who calls (`current_caller`)
    and refuses registrations that `guard` does not allow."""

    async def _process_message(self, typeid, requesthdr, seqhdr, body):
        policy = self._connection.security_policy
        secure = getattr(policy, "Mode", None) == ua.MessageSecurityMode.SignAndEncrypt
        der = getattr(policy, "peer_certificate", None) if secure else None
        user = self.session.user if self.session is not None else None
        caller = Caller(secure, _uris(der), getattr(user, "name", None),
                        getattr(user, "asset_id", None))  # fmt: skip
        trust = _GUARDED.get(self.iserver) if typeid in _REGISTER or typeid in _SESSION else None
        if trust is not None and typeid in _SESSION and not caller.secure:
            log.warning("refused a session over a channel without security")
            raise ServiceError(ua.StatusCodes.BadSecurityModeInsufficient)
        if trust is not None and typeid in _REGISTER:
            self._check_registration(caller, der, trust, _REGISTER[typeid], body)
        token = _CALLER.set(caller)
        try:
            return await super()._process_message(typeid, requesthdr, seqhdr, body)
        finally:
            _CALLER.reset(token)

    @staticmethod
    def _check_registration(caller: Caller, der: bytes | None, trust: TrustList,
                            kind: type, body) -> None:  # fmt: skip
        """ServiceError with the status of a registration refused (module docstring)."""
        if not caller.secure:
            log.warning("refused a registration over a channel without security (%s)",
                        "RegisterServer2" if kind is not ua.RegisteredServer
                        else "RegisterServer")  # fmt: skip
            raise ServiceError(ua.StatusCodes.BadSecurityModeInsufficient)
        status = trust.refusal(x509.load_der_x509_certificate(bytes(der)))
        if status is not None:
            log.warning("refused a registration from %s: %s", ", ".join(caller.uris) or "?",
                        ua.StatusCode(status).name)  # fmt: skip
            raise ServiceError(status)
        params = struct_from_binary(kind, body.copy())
        server = params if kind is ua.RegisteredServer else params.Server
        if server.ServerUri not in caller.uris or not server.ServerUri.startswith(_URI_PREFIX):
            log.warning("refused a registration of %s from %s", server.ServerUri,
                        ", ".join(caller.uris) or "no URI")  # fmt: skip
            raise ServiceError(ua.StatusCodes.BadCertificateUriInvalid)


# asyncua makes each connection's processor by this module-level name (no seam of its own)
binary_server_asyncio.UaProcessor = GuardedProcessor
