"""/jobs: submit, list, read and cancel jobs."""

from typing import Annotated, Any, Literal

from fastapi import APIRouter, Body, Depends, HTTPException
from pydantic import BaseModel, ConfigDict, Field

from swarmpath.service.cost import check as check_cost
from swarmpath.service.http.deps import CoreDep, Limit, Offset, authorized, status_or_404
from swarmpath.service.http.models import JobCreated
from swarmpath.service.maps import resolve_refs
from swarmpath.service.protocol import (
    MAX_RUNS_PER_CELL,
    BenchmarkJobSpec,
    FieldProblems,
    JobStatus,
    MapJobSpec,
)
from swarmpath.service.store import ExtendError

router = APIRouter(tags=["jobs"])

_STATE = Literal["queued", "running", "done", "failed", "cancelled", "waiting"]


@router.post("/jobs", status_code=201, dependencies=[Depends(authorized)],
             response_model=JobCreated)
def submit_job(
    spec: Annotated[BenchmarkJobSpec | MapJobSpec, Body(discriminator="kind")],
    core: CoreDep,
) -> dict[str, Any]:
    """Submit a benchmark or map job (a JobSpec). 201 with its id, state and runs_total; 422
    when the job is invalid, or larger than this coordinator's cost limit (the detail gives the
    estimate, the limit and how to raise it). A map job's uploaded maps (``{"map": id, ...}``)
    are replaced by their scenarios first, so the job keeps its maps."""
    if isinstance(spec, MapJobSpec):
        try:
            spec = resolve_refs(spec, core.store.map_scenario, core.store.map_pairs)
        except FieldProblems as exc:
            raise HTTPException(422, [{"loc": ["body", "maps", *loc], "msg": msg,
                                       "type": "value_error"} for loc, msg in exc.problems]
                                ) from None
    settings = core.settings
    problem = check_cost(spec, settings.max_job_evaluations, settings.max_job_steps)
    if problem is not None:
        raise HTTPException(422, [problem])
    status = core.submit(spec)
    return {"id": status.id, "state": status.state, "runs_total": status.runs_total}


@router.get("/jobs")
def list_jobs(
    core: CoreDep,
    state: _STATE | None = None,
    limit: Limit = 100,
    offset: Offset = 0,
) -> list[JobStatus]:
    """Jobs, newest first, optionally only those in one state."""
    return core.store.list_jobs(state, limit, offset)


@router.get("/jobs/{job_id}")
def job_status(job_id: str, core: CoreDep) -> JobStatus:
    status = status_or_404(core, job_id)
    return status.model_copy(update={"contents": core.store.job_contents(job_id)})


@router.delete("/jobs/{job_id}", dependencies=[Depends(authorized)])
def cancel_job(job_id: str, core: CoreDep) -> JobStatus:
    """Cancel a queued or running job (a finished job is returned unchanged)."""
    status = core.cancel(job_id)
    if status is None:
        raise HTTPException(404, f"unknown job {job_id!r}")
    return status


class Extension(BaseModel):
    """``POST /jobs/{id}/extend``: the runs per cell of the new job."""

    model_config = ConfigDict(extra="forbid")
    runs: int = Field(ge=1, le=MAX_RUNS_PER_CELL, strict=True,
                      description="runs per cell of the new job (a raced job: its max_runs)")


@router.post("/jobs/{job_id}/extend", status_code=201, dependencies=[Depends(authorized)])
def extend_job(job_id: str, body: Extension, core: CoreDep) -> dict[str, Any]:
    """A new job with the ended job's spec and ``runs`` runs per cell, reusing every result the
    old job has (run r of a cell is the same run in both); a raced job's race goes on from its
    runs. 201 with the new id, state, runs_total and ``reused``; 404 for an unknown job; 422
    naming ``runs`` when the job has not ended or ``runs`` is below its runs."""
    status_or_404(core, job_id)
    try:
        status, reused = core.extend(job_id, body.runs)
    except ExtendError as exc:
        raise HTTPException(422, [{"loc": ["body", "runs"], "msg": str(exc),
                                   "type": "value_error"}]) from None
    return {"id": status.id, "state": status.state, "runs_total": status.runs_total,
            "extends": job_id, "reused": reused}


@router.get("/jobs/{job_id}/race")
def job_race(job_id: str, core: CoreDep) -> dict[str, Any]:
    """A raced job's race: its settings and, per block (function and dimension), the rounds,
    each cell's runs and state, each comparison's decision (docs/statistics.md, Racing); 404 for
    an unknown job or one that does not race."""
    status_or_404(core, job_id)
    race = core.store.race(job_id)
    if race is None:
        raise HTTPException(404, f"job {job_id} does not race")
    return race
