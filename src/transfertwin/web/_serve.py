"""Serving the console with uvicorn."""

from __future__ import annotations

import signal
import socket
from collections.abc import Callable
from typing import Any

from transfertwin._errors import InputError
from transfertwin.web._app import create_app
from transfertwin.web._config import WebConfig

__all__ = ["console_url", "serve"]


def console_url(config: WebConfig, port: int | None = None) -> str:
    """The URL to open, carrying the token (the page keeps it for write actions)."""
    host = f"[{config.host}]" if ":" in config.host else config.host
    return f"http://{host}:{port or config.port}/?token={config.session_token}"


def _bind(config: WebConfig) -> socket.socket:
    """Bind the listening socket up front: a busy port is bad input, not a crash later."""
    family = socket.AF_INET6 if ":" in config.host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((config.host, config.port))
    except OSError as exc:
        sock.close()
        raise InputError(f"cannot listen on {config.host}:{config.port} ({exc.strerror})") from None
    return sock


def serve(
    config: WebConfig,
    on_ready: Callable[[str], None] | None = None,
    replays: dict[str, dict[str, Any]] | None = None,
) -> None:
    """Serve the console until SIGINT/SIGTERM.

    Args:
        config: What to serve.
        on_ready: Called with the console's URL (token included) once it listens.
        replays: Replay documents served under ``/replay?key=K`` (`create_app`).
    """
    import uvicorn

    sock = _bind(config)
    port = sock.getsockname()[1]
    app = create_app(config, replays)
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", access_log=False,
                                           timeout_graceful_shutdown=2))  # fmt: skip

    startup = server.startup

    async def announce(sockets=None) -> None:
        await startup(sockets=sockets)
        if on_ready is not None and server.started:
            on_ready(console_url(config, port))

    server.startup = announce
    # uvicorn shuts down gracefully on SIGINT/SIGTERM, then raises the signal again with the
    # handlers it found: make those no-ops so that a stopped console exits normally.
    previous = {sig: signal.signal(sig, lambda *_: None) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        server.run(sockets=[sock])
    finally:
        sock.close()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
