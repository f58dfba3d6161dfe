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
    """Liveness, and whether the store can write (``status`` "degraded" and ``store.problem``
    while its disk is full)."""
    core = getattr(request.app.state, "core", None)
    bridge = getattr(request.app.state, "bridge", None)
    settings = request.app.state.settings
    problem = core.store.write_problem if core is not None else None
    status = "stopping" if core is None or not core.accepting else \
        "degraded" if problem is not None else "ok"
    return {
        "status": status,
        "version": __version__, "protocol": PROTOCOL_VERSION,
        "zenoh": bridge is not None, "listen": settings.zenoh_listen if bridge else [],
        "prefix": settings.prefix,
        "uptime": round(time.time() - core.started, 3) if core else 0.0,
        # while the store cannot write (disk full): no leases, POST /jobs answers 507
        "store": {"writable": problem is None, "problem": problem[1] if problem else None,
                  "since": problem[0] if problem else None},
    }


@router.get("/metrics", response_class=PlainTextResponse)
def metrics(core: CoreDep) -> Response:
    """Prometheus text exposition."""
    return PlainTextResponse(core.metrics_text(),
                             media_type="text/plain; version=0.0.4; charset=utf-8")
