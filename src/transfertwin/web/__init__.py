"""Web console of the twin (ASGI, Starlette on uvicorn): the running CPS's assets with live
values and AAS, transport orders, study progress and interactive success maps.

Everything the page loads is served by the console itself (its own JS/CSS and the plotly.js
bundled with the `plotly` Python package): it works without internet access.
"""

from transfertwin.web._app import MAX_BODY_BYTES, create_app, plotly_js
from transfertwin.web._config import WebConfig, is_loopback
from transfertwin.web._gateway import ASSETS_QUERY, CpsGateway, Order
from transfertwin.web._serve import console_url, serve
from transfertwin.web._studies import RATE_WINDOW, StudyView, progress_of, success_map

__all__ = [
    "ASSETS_QUERY",
    "MAX_BODY_BYTES",
    "RATE_WINDOW",
    "CpsGateway",
    "Order",
    "StudyView",
    "WebConfig",
    "console_url",
    "create_app",
    "is_loopback",
    "plotly_js",
    "progress_of",
    "serve",
    "success_map",
]
