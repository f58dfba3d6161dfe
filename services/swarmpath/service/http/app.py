"""The FastAPI application factory: lifespan (store, crash recovery, Zenoh bridge, ticker),
middleware, error handlers and the routers."""

import asyncio
import logging
import os
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse

from swarmpath import __version__
from swarmpath.service.bridge import ZenohBridge
from swarmpath.service.catalog import warm_registries
from swarmpath.service.coordinator import Coordinator
from swarmpath.service.http import handlers, openapi
from swarmpath.service.http.errors import validation_detail
from swarmpath.service.http.middleware import BodyLimit, HostCheck, SecurityHeaders
from swarmpath.service.http.routes import ROUTERS
from swarmpath.service.protocol import MAX_BODY_BYTES
from swarmpath.service.settings import CoordinatorSettings
from swarmpath.service.store import StoreFull
from swarmpath.service.ticker import Ticker

log = logging.getLogger("swarmpath.coordinator")


def create_app(
    settings: CoordinatorSettings | None = None,
    *,
    use_zenoh: bool = True,
    on_started: Callable[[], None] | None = None,
    on_stopping: Callable[[], None] | None = None,
) -> FastAPI:
    """The FastAPI application. ``use_zenoh=False`` serves REST only (tests); ``on_started`` runs
    once the router is up (``swarmpath up`` starts its workers there) and ``on_stopping`` before
    it goes down."""

    settings = settings or CoordinatorSettings()
    token = settings.token if settings.token is not None else os.environ.get("SWARMPATH_TOKEN")

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        core = await asyncio.to_thread(Coordinator, settings)
        bridge: ZenohBridge | None = None
        ticker = Ticker(core, settings.tick_seconds)
        try:
            await asyncio.to_thread(core.startup)
            await asyncio.to_thread(warm_registries)
            if use_zenoh:
                bridge = ZenohBridge(core, settings.zenoh_config())
                await asyncio.to_thread(bridge.start)
            ticker.start()
            app.state.core = core
            app.state.bridge = bridge
            if on_started is not None:
                await asyncio.to_thread(on_started)
            yield
        finally:
            core.accepting = False
            if on_stopping is not None:
                try:
                    await asyncio.to_thread(on_stopping)
                except Exception:
                    log.exception("stopping the local workers failed")
            ticker.stop()
            if bridge is not None:
                await asyncio.to_thread(bridge.close)
            await asyncio.to_thread(core.close)
            log.info("coordinator stopped")

    app = FastAPI(
        title="swarmpath coordinator",
        version=__version__,
        summary="Benchmark and map studies of swarm optimizers and path planners, run by workers.",
        lifespan=lifespan,
    )
    app.state.settings = settings
    app.state.token = token or None
    app.add_middleware(BodyLimit, limit=MAX_BODY_BYTES, routes={("POST", "/maps"): (
        settings.max_map_upload_bytes,
        f"max_map_upload_bytes={settings.max_map_upload_bytes} "
        "(SWARMPATH_MAX_MAP_UPLOAD_BYTES)")})
    if settings.allowed_hosts is not None:  # the CLI always sets them (tests may not)
        app.add_middleware(HostCheck, names=settings.allowed_hosts)
    app.add_middleware(SecurityHeaders)  # outermost: on every answer, refusals included

    @app.exception_handler(RequestValidationError)
    async def _invalid(request: Request, exc: RequestValidationError) -> JSONResponse:
        return JSONResponse({"detail": validation_detail(list(exc.errors()))}, status_code=422)

    @app.exception_handler(StoreFull)
    async def _full(request: Request, exc: StoreFull) -> JSONResponse:
        """A write the store could not make (disk full): 507, nothing was stored."""
        return JSONResponse({"detail": f"{exc}: nothing was stored; free space on the "
                                       "coordinator's disk and send it again"},
                            status_code=507, headers={"Retry-After": "30"})

    routes = [route for router in ROUTERS for route in router.routes]
    handlers.install(app, routes)
    for router in ROUTERS:
        app.include_router(router)
    openapi.install(app, routes)
    return app
