"""Dependencies shared by the routers: the coordinator of the running app, the bearer-token
check of mutating endpoints, the 404 of an unknown job."""

import secrets
from typing import Annotated

from fastapi import Depends, HTTPException, Request

from swarmpath.service.coordinator import Coordinator
from swarmpath.service.protocol import JobStatus


def core_of(request: Request) -> Coordinator:
    core: Coordinator = request.app.state.core
    return core


CoreDep = Annotated[Coordinator, Depends(core_of)]


def authorized(request: Request) -> None:
    """401 unless the request carries the app's bearer token (when one is configured)."""
    token: str | None = getattr(request.app.state, "token", None)
    if token is None:
        return
    header = request.headers.get("authorization", "")
    scheme, _, given = header.partition(" ")
    if scheme.lower() != "bearer" or not secrets.compare_digest(given.strip(), token):
        raise HTTPException(
            401, "a valid 'Authorization: Bearer <token>' header is required",
            headers={"WWW-Authenticate": "Bearer"},
        )


def status_or_404(core: Coordinator, job_id: str) -> JobStatus:
    status = core.store.job_status(job_id)
    if status is None:
        raise HTTPException(404, f"unknown job {job_id!r}")
    return status
