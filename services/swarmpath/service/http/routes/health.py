"""/healthz and /metrics."""

import time
from typing import Any

from fastapi import APIRouter, Request
from fastapi.responses import PlainTextResponse, Response

from swarmpath import __version__
from swarmpath.service.http.deps import CoreDep
from swarmpath.service.protocol import PROTOCOL_VERSION

router = APIRouter(tags=["service"])


@router.get("/healthz")
def healthz(request: Request) -> dict[str, Any]:
    core = getattr(request.app.state, "core", None)
    bridge = getattr(request.app.state, "bridge", None)
    settings = request.app.state.settings
    return {
        "status": "ok" if core is not None and core.accepting else "stopping",
        "version": __version__, "protocol": PROTOCOL_VERSION,
        "zenoh": bridge is not None, "listen": settings.zenoh_listen if bridge else [],
        "prefix": settings.prefix,
        "uptime": round(time.time() - core.started, 3) if core else 0.0,
    }


@router.get("/metrics", response_class=PlainTextResponse)
def metrics(core: CoreDep) -> Response:
    """Prometheus text exposition."""
    return PlainTextResponse(core.metrics_text(),
                             media_type="text/plain; version=0.0.4; charset=utf-8")
