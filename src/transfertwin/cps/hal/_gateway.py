"""An asset process's session with its HAL gateway (docs/architecture.md, "Deployment").

A HAL gateway is the OPC UA server next to a machine (a PLC's, or a small bridge). The
asset opens one session to it, on first use and again after a failure:

- secure (the default): Basic256Sha256, SignAndEncrypt, with the asset's own application
  certificate (``cert_dir/client-operator.der``, which the gateway must trust). The
  gateway's certificate is checked against the asset's gateway trust list (``[hal]
  trust_dir``, default ``cert_dir/gateways``: one DER/PEM file per trusted gateway,
  pinned by its SHA-256) *before* the secure channel is opened. A gateway that offers no
  such endpoint (NoSecurity only) is refused: NoSecurity needs ``[hal] insecure = true``,
  which is for a gateway on loopback only (`HalConfig.check`).
- ``insecure = true``: NoSecurity.

Every failure is one `GatewayError` line that says what to do.
"""

from __future__ import annotations

import asyncio
import contextlib
import hashlib
import logging
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from transfertwin.cps.opcua import OperationRefused, TrustList, ensure_certificate

if TYPE_CHECKING:
    from asyncua import Client

    from transfertwin.cps.floor import AssetConfig

__all__ = ["GatewayError", "GatewayLink", "gateway_refusal", "gateway_trust_dir", "open_gateway",
           "poll_gateway"]

log = logging.getLogger("transfertwin.cps")

#: The client certificate an asset shows its gateway (in its ``cert_dir``).
GATEWAY_CLIENT_CERT = "client-operator"


class GatewayError(ConnectionError):
    """The HAL gateway cannot be used (not answering, not secure, not trusted, ...)."""


def gateway_refusal(exc: GatewayError):
    """`exc` as the refusal of an operation call (BadCommunicationError, its line)."""

    return OperationRefused(str(exc), status="BadCommunicationError")


def gateway_trust_dir(cfg: AssetConfig) -> Path:
    """The folder of the gateway certificates `cfg`'s asset trusts."""
    return cfg.hal.trust_dir if cfg.hal.trust_dir is not None else cfg.cert_dir / "gateways"


async def _secure(client: Client, cfg: AssetConfig) -> None:
    """Pick the gateway's Basic256Sha256 SignAndEncrypt endpoint, check its certificate
    against the trust list, and set up the secure channel with the asset's certificate."""
    from asyncua import ua
    from asyncua.crypto import uacrypto
    from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256
    from cryptography.hazmat.primitives.serialization import Encoding


    url = cfg.hal.endpoint
    mode = ua.MessageSecurityMode.SignAndEncrypt
    endpoints = await client.connect_and_get_server_endpoints()  # over SecurityPolicy None
    match = [e for e in endpoints
             if e.SecurityMode == mode and e.SecurityPolicyUri == SecurityPolicyBasic256Sha256.URI]
    if not match:
        offered = sorted({e.SecurityPolicyUri.rsplit("#", 1)[-1] for e in endpoints})
        raise GatewayError(f"HAL gateway {url} offers no Basic256Sha256 SignAndEncrypt "
                           f"endpoint (it offers {', '.join(offered) or 'nothing'}); "
                           "NoSecurity needs [hal] insecure = true (loopback only)")  # fmt: skip
    cert = uacrypto.x509_from_der(match[0].ServerCertificate)
    der = cert.public_bytes(Encoding.DER)
    folder = gateway_trust_dir(cfg)
    if not TrustList(folder).is_trusted(der):
        raise GatewayError(f"HAL gateway {url}: its certificate ({cert.subject.rfc4514_string()}, "
                           f"SHA-256 {hashlib.sha256(der).hexdigest()[:16]}…) is not trusted; "
                           f"put it in {folder} to trust it")  # fmt: skip
    own, key = await ensure_certificate(cfg.cert_dir, GATEWAY_CLIENT_CERT)
    await client.set_security(SecurityPolicyBasic256Sha256, str(own), str(key),
                              server_certificate=der, mode=mode)  # fmt: skip


async def poll_gateway(aid: str, read: Callable[[], Awaitable[Any]], period_s: float,
                       on_value: Callable[[Any], Awaitable[None]] | None = None) -> None:
    """Call `read` every `period_s`, for ever, and pass what it returns to `on_value`; a
    gateway away (`ConnectionError`) is said once and tried again, its return said once."""
    away = False
    while True:
        try:
            value = await read()
        except ConnectionError as exc:
            if not away:
                log.warning("%s: %s", aid, exc)
            away = True
        else:
            if away:
                log.info("%s: HAL gateway answering again", aid)
            away = False
            if on_value is not None:
                await on_value(value)
        await asyncio.sleep(period_s)


async def open_gateway(cfg: AssetConfig) -> Client:
    """A connected session with `cfg`'s HAL gateway (`GatewayError`: why not)."""
    from asyncua import Client, ua

    url = cfg.hal.endpoint
    client = Client(url, timeout=5)
    try:  # (its endpoints are read on a connection of their own, closed again)
        if not cfg.hal.insecure:
            await asyncio.wait_for(_secure(client, cfg), 10.0)
    except GatewayError:
        raise
    except Exception as exc:
        raise GatewayError(f"HAL gateway {url} not answering "
                           f"({type(exc).__name__}: {exc})") from None  # fmt: skip
    try:
        await asyncio.wait_for(client.connect(), 10.0)
    except BaseException as exc:
        with contextlib.suppress(Exception):
            await client.disconnect()
        if isinstance(exc, ua.UaStatusCodeError) and \
                exc.code == ua.StatusCodes.BadCertificateUntrusted:
            cert = cfg.cert_dir / f"{GATEWAY_CLIENT_CERT}.der"
            raise GatewayError(f"HAL gateway {url} does not trust this asset's certificate; "
                               f"trust {cert} at the gateway") from None  # fmt: skip
        if isinstance(exc, Exception):
            raise GatewayError(f"HAL gateway {url} not answering "
                               f"({type(exc).__name__}: {exc})") from None  # fmt: skip
        raise
    log.info("%s: HAL gateway %s connected (%s)", cfg.asset_id, url,
             "NoSecurity" if cfg.hal.insecure else "Basic256Sha256, SignAndEncrypt")  # fmt: skip
    return client


class GatewayLink:
    """Reads and writes of an asset's gateway nodes over one session (opened on first
    use and again after a failure; one request at a time).

    Args:
        cfg: The asset's configuration (its ``[hal]`` table says where and which nodes).
    """

    def __init__(self, cfg: AssetConfig) -> None:
        self.cfg = cfg
        self.endpoint = cfg.hal.endpoint
        self.nodes = cfg.hal.node_ids(cfg.asset_id)
        self._client: Client | None = None
        self._lock = asyncio.Lock()

    @property
    def client(self) -> Client | None:
        """The open session (None when there is none)."""
        return self._client

    async def _session(self) -> Client:
        if self._client is None:
            self._client = await open_gateway(self.cfg)
        return self._client

    async def _drop(self) -> None:
        client, self._client = self._client, None
        if client is not None:
            with contextlib.suppress(Exception):
                await asyncio.wait_for(client.disconnect(), 2.0)

    async def read(self, *keys: str) -> list[Any]:
        """The values of the gateway nodes named by `keys` (`GATEWAY_NODES`' keys)."""
        async with self._lock:
            try:
                client = await self._session()
                return await client.read_values([client.get_node(self.nodes[k]) for k in keys])
            except GatewayError:
                raise
            except Exception as exc:
                await self._drop()
                raise GatewayError(f"HAL gateway {self.endpoint}: {', '.join(keys)} not read "
                                   f"({type(exc).__name__}: {exc})") from None  # fmt: skip

    async def write(self, key: str, value: object, variant_type) -> None:
        """Write `value` as `variant_type` (`asyncua.ua.VariantType`) to node `key`."""
        from asyncua import ua

        async with self._lock:
            try:
                node = (await self._session()).get_node(self.nodes[key])
                await node.write_value(ua.DataValue(ua.Variant(value, variant_type)))
            except GatewayError:
                raise
            except Exception as exc:
                await self._drop()
                raise GatewayError(f"HAL gateway {self.endpoint}: {key} not written "
                                   f"({type(exc).__name__}: {exc})") from None  # fmt: skip

    async def close(self) -> None:
        """Close the gateway session."""
        async with self._lock:
            await self._drop()
