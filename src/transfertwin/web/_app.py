"""The console's ASGI app (Starlette): pages, JSON API, server-sent live values.

Routes: ``/`` (the page), ``/static/*`` (its JS/CSS, plotly.js from the installed `plotly`
package), ``/api/config``, ``/api/assets``, ``/api/assets/{id}/aas``, ``/api/live`` (SSE),
``/api/query?q=SPARQL`` (the knowledge graph's answer to a SELECT query),
``/api/orders`` (GET, POST), ``/api/orders/{id}``, ``/api/studies``,
``/api/studies/{name}/map``, ``/api/studies/{name}/analysis?object=ID``,
``/api/studies/{name}/results.{csv|parquet}``, ``/api/transfer`` (GET; POST starts a
simulated transfer), ``/api/transfer/live`` (SSE), ``/api/calibrations``,
``/api/calibrations/{name}``, ``/replay`` (the 3-D replay page) and ``/api/replay``
(its JSON document, `transfertwin.web._replay`), ``/floor3d`` (the running floor in 3-D) and
``/api/floor`` (its static layout, `transfertwin.web._floor3d`), and the floor's AAS HTTP
API under ``/aas-api/v3.0/`` (`transfertwin.web._aas_api`).

Every error is a JSON ``{"error": message}`` with a 4xx status (5xx only for a fault of the
console itself, without a traceback). Write actions need the token (header
``Authorization: Bearer T``, or a ``token`` field of the body); cookies never authorise a
write, so another site cannot make the browser place an order.
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import hmac
import json
import logging
from collections.abc import AsyncIterator, Awaitable, Callable
from datetime import UTC, datetime
from importlib import resources
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs

from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.exceptions import HTTPException
from starlette.middleware import Middleware
from starlette.middleware.trustedhost import TrustedHostMiddleware
from starlette.requests import Request
from starlette.responses import (
    FileResponse,
    HTMLResponse,
    JSONResponse,
    Response,
    StreamingResponse,
)
from starlette.routing import Mount, Route
from starlette.staticfiles import StaticFiles

from transfertwin._errors import InputError
from transfertwin.web._aas_api import AAS_API_PREFIX, AasApi
from transfertwin.web._aas_model import error_body
from transfertwin.web._calibration import calibration_view
from transfertwin.web._config import WebConfig
from transfertwin.web._floor3d import floor_layout
from transfertwin.web._gateway import CpsGateway
from transfertwin.web._live import LiveTransfer, TransferBusyError, TransferRequest
from transfertwin.web._replay import ReplayService
from transfertwin.web._studies import StudyView, StudyViews

__all__ = ["MAX_BODY_BYTES", "create_app", "plotly_js"]

log = logging.getLogger("transfertwin.web")
audit = logging.getLogger("transfertwin.web.audit")

MAX_BODY_BYTES = 16 * 1024
_COOKIE = "tt_token"
_CSP = ("default-src 'self'; script-src 'self'; style-src 'self' 'unsafe-inline'; "
        "img-src 'self' data: blob:; connect-src 'self'; frame-ancestors 'none'")  # fmt: skip


def plotly_js() -> Path:
    """plotly.min.js as the installed `plotly` Python package ships it (no CDN)."""
    import plotly

    path = Path(plotly.__file__).parent / "package_data" / "plotly.min.js"
    if not path.is_file():
        raise InputError(f"the plotly package has no bundled plotly.min.js ({path})")
    return path


def _static_dir() -> Path:
    return Path(str(resources.files("transfertwin.web").joinpath("static")))


def _error(status: int, message: str) -> JSONResponse:
    return JSONResponse({"error": message}, status_code=status)


def _parse_body(request: Request, raw: bytes) -> dict[str, Any]:
    """A write action's body (JSON or a form) as a dict; 4xx for anything else."""
    ctype = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if ctype == "application/json":
        try:
            data = json.loads(raw.decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise HTTPException(400, f"malformed JSON: {exc}") from None
    elif ctype == "application/x-www-form-urlencoded":
        try:
            form = parse_qs(raw.decode("utf-8"), keep_blank_values=True, strict_parsing=False)
        except (UnicodeDecodeError, ValueError) as exc:
            raise HTTPException(400, f"malformed form: {exc}") from None
        data = {k: v[-1] for k, v in form.items()}
    else:
        raise HTTPException(415, "send application/json or a form")
    if not isinstance(data, dict):
        raise HTTPException(400, "the body must be a JSON object")
    return data


def _api(fn: Callable[..., Awaitable[Response]]) -> Callable[[Request], Awaitable[Response]]:
    """Every failure becomes a JSON error; nothing of a traceback reaches the client."""

    @functools.wraps(fn)
    async def wrapped(request: Request) -> Response:
        try:
            return await fn(request)
        except InputError as exc:
            return _error(422, str(exc))
        except LookupError as exc:
            return _error(404, str(exc.args[0]) if exc.args else "not found")
        except HTTPException as exc:
            return _error(exc.status_code, str(exc.detail))
        except TransferBusyError as exc:
            return _error(409, str(exc))
        except (asyncio.CancelledError, KeyboardInterrupt):
            raise
        except Exception as exc:
            log.warning("internal error in %s: %s", request.url.path, exc, exc_info=True)
            return _error(500, f"internal error ({type(exc).__name__})")

    return wrapped


class _SecurityHeaders:
    """Pure ASGI middleware: CSP and friends on every response (streaming included)."""

    def __init__(self, app) -> None:
        self.app = app

    async def __call__(self, scope, receive, send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return

        async def send_with_headers(message) -> None:
            if message["type"] == "http.response.start":
                headers = list(message.get("headers", []))
                headers += [
                    (b"content-security-policy", _CSP.encode()),
                    (b"x-content-type-options", b"nosniff"),
                    (b"x-frame-options", b"DENY"),
                    (b"referrer-policy", b"no-referrer"),
                    (b"cache-control", b"no-store"),
                ]
                message = {**message, "headers": headers}
            await send(message)

        await self.app(scope, receive, send_with_headers)


def create_app(config: WebConfig, replays: dict[str, dict[str, Any]] | None = None) -> Starlette:
    """The console app for `config` (its CPS sessions open with the app's lifespan);
    `replays` are replay documents served under ``/replay?key=K``."""
    studies = StudyViews(config.dbs, config.cps)
    calibrations = {p.name: p for p in config.calibrations}
    replay_service = ReplayService({p.name: p for p in config.dbs}, replays, calibrations)
    live = LiveTransfer()
    state: dict[str, CpsGateway | None] = {"cps": None}
    aas_api: dict[str, AasApi] = {}
    token = config.session_token

    def matches(candidate: object) -> bool:
        return isinstance(candidate, str) and hmac.compare_digest(
            candidate.encode(), token.encode()
        )

    def header_token(request: Request) -> str | None:
        auth = request.headers.get("authorization", "")
        return auth[7:].strip() if auth.lower().startswith("bearer ") else None

    def check_read(request: Request) -> None:
        if not config.reads_need_token:
            return
        for candidate in (header_token(request), request.cookies.get(_COOKIE),
                          request.query_params.get("token")):  # fmt: skip
            if matches(candidate):
                return
        raise HTTPException(401, "this console needs its token (open it with ?token=...)")

    def gateway() -> CpsGateway:
        if state["cps"] is None:
            raise HTTPException(404, "no CPS: start the console with --cps WORKDIR")
        return state["cps"]

    def study(name: str) -> StudyView:
        if name not in studies:
            raise HTTPException(404, f"no study {name[:80]!r}; studies: {', '.join(studies)}")
        return studies[name]

    async def write_body(request: Request, what: str) -> tuple[dict[str, Any], str]:
        """The body of a write action and its client, refused as early as can be: without
        a valid token in the header, a body declared (Content-Length) or streamed past
        `MAX_BODY_BYTES` is refused (401) before or as soon as the limit is passed, never
        read to its end; with one, such a body gets 413 as soon as the limit is passed.
        A body within the limit may carry the token itself (a ``token`` field). Every
        refusal is a line in the audit log."""
        client = request.client.host if request.client else "?"
        authorised = matches(header_token(request))

        def refuse(status: int, why: str) -> HTTPException:
            audit.warning("%s refused: %s from %s", what, why, client)
            if status == 413:
                return HTTPException(413, f"request body over {MAX_BODY_BYTES} bytes")
            return HTTPException(401, f"{what} needs the console's token")

        def too_large(size: str) -> HTTPException:
            if authorised:
                return refuse(413, f"a body {size}")
            return refuse(401, f"no valid token (and a body {size})")

        declared = request.headers.get("content-length", "")
        if declared.isdigit() and int(declared) > MAX_BODY_BYTES:
            raise too_large(f"of {declared} bytes")  # nothing of it read
        raw = bytearray()
        async for chunk in request.stream():
            raw += chunk
            if len(raw) > MAX_BODY_BYTES:  # the rest is never read
                raise too_large(f"over {MAX_BODY_BYTES} bytes")
        body = _parse_body(request, bytes(raw))
        if not (authorised or matches(body.get("token"))):
            raise refuse(401, "no valid token")
        return body, client

    def max_events_of(request: Request) -> int:
        try:
            max_events = int(request.query_params.get("max_events", "0"))
        except ValueError:
            raise InputError("max_events must be an integer") from None
        if not 0 <= max_events <= 100000:
            raise InputError("max_events must be in 0..100000 (0: unlimited)")
        return max_events

    # -- pages ----------------------------------------------------------------------------
    async def index(request: Request) -> Response:
        given = request.query_params.get("token")
        if config.reads_need_token and not (
            matches(given) or matches(request.cookies.get(_COOKIE))
        ):
            return HTMLResponse("<h1>401</h1><p>Open the console with ?token=...</p>", 401)
        html = (_static_dir() / "index.html").read_text()
        response = HTMLResponse(html)
        if matches(given) and config.reads_need_token:
            response.set_cookie(_COOKIE, token, httponly=True, samesite="strict")
        return response

    async def favicon(request: Request) -> Response:
        return FileResponse(_static_dir() / "favicon.svg", media_type="image/svg+xml")

    def page_of(name: str) -> Callable[[Request], Awaitable[Response]]:
        async def page(request: Request) -> Response:
            given = request.query_params.get("token")
            if config.reads_need_token and not (
                matches(given) or matches(request.cookies.get(_COOKIE))
            ):
                return HTMLResponse("<h1>401</h1><p>Open this page with ?token=...</p>", 401)
            return HTMLResponse((_static_dir() / name).read_text())

        return page

    @_api
    async def api_floor(request: Request) -> Response:
        check_read(request)
        gateway()  # 404 without a CPS
        return JSONResponse(await run_in_threadpool(floor_layout, config.cps))

    @_api
    async def api_replay(request: Request) -> Response:
        check_read(request)
        params = dict(request.query_params)
        return JSONResponse(await run_in_threadpool(replay_service.payload, params))

    async def plotly(request: Request) -> Response:
        return FileResponse(plotly_js(), media_type="text/javascript")

    # -- API ------------------------------------------------------------------------------
    @_api
    async def api_config(request: Request) -> Response:
        check_read(request)
        return JSONResponse({"cps": state["cps"] is not None, "studies": list(studies),
                             "calibrations": list(calibrations),
                             "reads_need_token": config.reads_need_token,
                             "live_period_s": config.live_period_s})  # fmt: skip

    @_api
    async def api_assets(request: Request) -> Response:
        check_read(request)
        gw = gateway()
        return JSONResponse({"assets": gw.assets(), "kg_error": gw.floor_error or gw.kg_error,
                             "tms_error": gw.tms_error,
                             "objects": gw.ids_of("object"),
                             "units": gw.ids_of("transfer_unit"),
                             "groups": gw.destination_groups()})  # fmt: skip

    @_api
    async def api_aas(request: Request) -> Response:
        check_read(request)
        aid = request.path_params["aid"]
        submodels = await gateway().aas(aid)
        read = datetime.now(UTC).isoformat(timespec="seconds")
        shell = aas_api["api"].shell_path(aid) if "api" in aas_api else None
        return JSONResponse({"submodels": submodels, "read_utc": read, "aas_api": shell})

    @_api
    async def api_query(request: Request) -> Response:
        check_read(request)
        rows = await gateway().query(request.query_params.get("q", ""))
        return JSONResponse({"rows": rows})

    @_api
    async def api_live(request: Request) -> Response:
        check_read(request)
        gw = gateway()
        max_events = max_events_of(request)

        async def events() -> AsyncIterator[str]:
            n = 0
            while not max_events or n < max_events:
                payload = gw.live()
                payload["orders"] = gw.order_rows()
                payload["kpis"] = gw.kpis()
                yield f"event: live\ndata: {json.dumps(payload)}\n\n"
                n += 1
                if await request.is_disconnected():
                    return
                await asyncio.sleep(config.live_period_s)

        return StreamingResponse(events(), media_type="text/event-stream",
                                 headers={"X-Accel-Buffering": "no"})  # fmt: skip

    @_api
    async def api_orders(request: Request) -> Response:
        gw = gateway()
        if request.method == "GET":
            check_read(request)
            return JSONResponse({"orders": gw.order_rows()})
        body, client = await write_body(request, "placing an order")
        obj, source, target = await gw.validate_order(body)
        order = await gw.submit(obj, source, target, client)
        return JSONResponse(order.public(), status_code=201)

    @_api
    async def api_order(request: Request) -> Response:
        check_read(request)
        return JSONResponse(gateway().order(request.path_params["oid"]))

    @_api
    async def api_studies(request: Request) -> Response:
        check_read(request)
        views = list(studies.values())
        return JSONResponse({"studies": await run_in_threadpool(
            lambda: [v.progress() for v in views])})  # fmt: skip

    @_api
    async def api_study_map(request: Request) -> Response:
        check_read(request)
        view = study(request.path_params["name"])
        return JSONResponse(await run_in_threadpool(view.success_map))

    @_api
    async def api_study_analysis(request: Request) -> Response:
        check_read(request)
        view = study(request.path_params["name"])
        obj = request.query_params.get("object") or None
        return JSONResponse(await run_in_threadpool(view.analysis, obj))

    @_api
    async def api_calibrations(request: Request) -> Response:
        check_read(request)
        return JSONResponse({"calibrations": list(calibrations)})

    @_api
    async def api_calibration(request: Request) -> Response:
        check_read(request)
        name = request.path_params["name"]
        if name not in calibrations:
            raise HTTPException(
                404,
                f"no calibration {name[:80]!r}; calibrations: "
                f"{', '.join(calibrations) or 'none (--calibration DIR)'}",
            )
        return JSONResponse(await run_in_threadpool(calibration_view, calibrations[name]))

    @_api
    async def api_transfer(request: Request) -> Response:
        if request.method == "GET":
            check_read(request)
            return JSONResponse(live.snapshot())
        body, client = await write_body(request, "starting a transfer")
        return JSONResponse(live.start(TransferRequest.parse(body), client), status_code=201)

    @_api
    async def api_transfer_live(request: Request) -> Response:
        check_read(request)
        max_events = max_events_of(request)

        async def events() -> AsyncIterator[str]:
            n, seq, last = 0, -1, 0.0
            loop = asyncio.get_running_loop()
            while not max_events or n < max_events:
                snap = live.snapshot()
                if snap["seq"] != seq or loop.time() - last >= 1.0:  # >= 1 update/s
                    seq, last = snap["seq"], loop.time()
                    yield f"event: transfer\ndata: {json.dumps(snap)}\n\n"
                    n += 1
                if await request.is_disconnected():
                    return
                await asyncio.sleep(0.1)

        return StreamingResponse(events(), media_type="text/event-stream",
                                 headers={"X-Accel-Buffering": "no"})  # fmt: skip

    @_api
    async def api_study_export(request: Request) -> Response:
        check_read(request)
        view = study(request.path_params["name"])
        fmt = request.path_params["fmt"]
        data = await run_in_threadpool(view.export, fmt)
        media = "text/csv" if fmt == "csv" else "application/vnd.apache.parquet"
        stem = Path(view.name).stem
        return Response(data, media_type=media, headers={
            "Content-Disposition": f'attachment; filename="{stem}.{fmt}"'})  # fmt: skip

    async def aas_http(request: Request) -> Response:
        """The AAS HTTP API (`transfertwin.web._aas_api`): read-only, the console's reads'
        authentication, errors as Part 2's Result."""

        def fail(status: int, text: str, **headers: str) -> Response:
            return JSONResponse(error_body(status, text), status, headers=headers or None)

        try:
            check_read(request)
        except HTTPException as exc:
            return fail(exc.status_code, str(exc.detail))
        if request.method != "GET":
            return fail(405, "the AAS API of the floor is read-only (GET)", Allow="GET")
        if "api" not in aas_api:
            return fail(404, "no CPS: start the console with --cps WORKDIR")
        query: dict[str, list[str]] = {}
        for key, value in request.query_params.multi_items():
            query.setdefault(key, []).append(value)
        try:
            answer = await aas_api["api"].answer(request.path_params["path"], query)
        except Exception as exc:
            log.warning("internal error in %s: %s", request.url.path, exc, exc_info=True)
            return fail(500, f"internal error ({type(exc).__name__})")
        return JSONResponse(answer.body, answer.status)

    @_api
    async def not_found(request: Request) -> Response:
        raise HTTPException(404, f"no such page: {request.url.path[:80]}")

    @contextlib.asynccontextmanager
    async def lifespan(app: Starlette) -> AsyncIterator[None]:
        if config.cps is not None:
            gw = CpsGateway(config.cps, config.live_period_s)
            await gw.start()
            state["cps"] = gw
            aas_api["api"] = AasApi(gw)
        try:
            yield
        finally:
            await run_in_threadpool(live.stop)
            aas_api.clear()
            if state["cps"] is not None:
                await state["cps"].stop()
                state["cps"] = None

    routes = [
        Route("/", index),
        Route("/favicon.ico", favicon),
        Route("/static/vendor/plotly.min.js", plotly),
        Mount("/static", StaticFiles(directory=_static_dir()), name="static"),
        Route("/api/config", api_config),
        Route("/api/assets", api_assets),
        Route("/api/assets/{aid}/aas", api_aas),
        Route("/api/live", api_live),
        Route("/api/query", api_query),
        Route("/api/orders", api_orders, methods=["GET", "POST"]),
        Route("/api/orders/{oid}", api_order),
        Route("/api/studies", api_studies),
        Route("/api/studies/{name}/map", api_study_map),
        Route("/api/studies/{name}/analysis", api_study_analysis),
        Route("/api/studies/{name}/results.{fmt}", api_study_export),
        Route("/api/transfer", api_transfer, methods=["GET", "POST"]),
        Route("/api/transfer/live", api_transfer_live),
        Route("/api/calibrations", api_calibrations),
        Route("/api/calibrations/{name}", api_calibration),
        Route("/replay", page_of("replay.html")),
        Route("/floor3d", page_of("floor3d.html")),
        Route("/api/floor", api_floor),
        Route("/api/replay", api_replay),
        Route(
            AAS_API_PREFIX + "/{path:path}",
            aas_http,
            methods=["GET", "POST", "PUT", "PATCH", "DELETE"],
        ),
        Route("/{path:path}", not_found),
    ]
    hosts = ["*"] if config.reads_need_token else sorted(
        {config.host, "localhost", "127.0.0.1", "[::1]"})  # fmt: skip
    middleware = [Middleware(_SecurityHeaders), Middleware(TrustedHostMiddleware,
                                                          allowed_hosts=hosts)]  # fmt: skip

    async def http_error(request: Request, exc: Exception) -> Response:
        if isinstance(exc, HTTPException):
            return _error(exc.status_code, str(exc.detail))
        return _error(500, "internal error")

    return Starlette(routes=routes, middleware=middleware, lifespan=lifespan,
                     exception_handlers={HTTPException: http_error,
                                         Exception: http_error})  # fmt: skip
