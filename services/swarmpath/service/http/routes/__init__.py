"""One router per resource; :func:`swarmpath.service.http.app.create_app` includes them in this
order (the order of the OpenAPI document)."""

from swarmpath.service.http.routes import (
    catalog,
    dashboard,
    health,
    jobs,
    maps,
    pages,
    runs,
    workers,
)

ROUTERS = (jobs.router, maps.router, runs.router, workers.router, catalog.router, health.router,
           dashboard.router, pages.router)

__all__ = ["ROUTERS"]
