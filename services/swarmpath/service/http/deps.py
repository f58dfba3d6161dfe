"""Dependencies shared by the routers: the coordinator of the running app, the bearer-token
check of mutating endpoints, the 404 of an unknown job."""

import secrets
from typing import Annotated

from fastapi import Depends, HTTPException, Path, Query, Request

from swarmpath.service.coordinator import Coordinator
from swarmpath.service.protocol import MAX_RUNS_PER_JOB, JobStatus

#: Paging bounds of every list route: SQLite's integers end at 2**63 - 1, and a page this far
#: down is empty anyway.
MAX_OFFSET = 1_000_000_000
MAX_LIMIT = 1000
Limit = Annotated[int, Query(ge=1, le=MAX_LIMIT, description="items per page")]
Offset = Annotated[int, Query(ge=0, le=MAX_OFFSET, description="items skipped")]
RunId = Annotated[int, Path(ge=0, lt=MAX_RUNS_PER_JOB, description="cell_index * runs + run")]


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
