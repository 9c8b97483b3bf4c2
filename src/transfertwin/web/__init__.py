"""Web console of the twin (ASGI, Starlette on uvicorn): the running CPS's assets with live
values and AAS, transport orders, a live top-down view of a simulated transfer, study
progress and interactive results, and the real-vs-virtual calibration comparison.

Everything the page loads is served by the console itself (its own JS/CSS and the plotly.js
bundled with the `plotly` Python package): it works without internet access.
"""

from transfertwin.web._app import MAX_BODY_BYTES, create_app, plotly_js
from transfertwin.web._calibration import (
    BOOTSTRAP_REPLICATES,
    BOOTSTRAP_SEED,
    bootstrap_f05,
    calibration_view,
    check_calibration_dir,
    f05_of_counts,
)
from transfertwin.web._config import WebConfig, is_loopback
from transfertwin.web._gateway import ASSETS_QUERY, CpsGateway, Order
from transfertwin.web._live import (
    LiveTransfer,
    TransferBusyError,
    TransferRequest,
    footprint,
    scene_outline,
)
from transfertwin.web._serve import console_url, serve
from transfertwin.web._studies import (
    RATE_WINDOW,
    StudyView,
    StudyViews,
    analysis_view,
    progress_of,
    success_map,
)

__all__ = [
    "ASSETS_QUERY",
    "BOOTSTRAP_REPLICATES",
    "BOOTSTRAP_SEED",
    "MAX_BODY_BYTES",
    "RATE_WINDOW",
    "CpsGateway",
    "LiveTransfer",
    "Order",
    "StudyView",
    "StudyViews",
    "TransferBusyError",
    "TransferRequest",
    "WebConfig",
    "analysis_view",
    "bootstrap_f05",
    "calibration_view",
    "check_calibration_dir",
    "console_url",
    "create_app",
    "f05_of_counts",
    "footprint",
    "is_loopback",
    "plotly_js",
    "progress_of",
    "scene_outline",
    "serve",
    "success_map",
]
