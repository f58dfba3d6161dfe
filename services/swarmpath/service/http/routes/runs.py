"""A job's results: the summary tables, the runs, one run, the MCAP file."""

from typing import Annotated, Any, Literal

from fastapi import APIRouter, HTTPException, Query
from fastapi.responses import FileResponse, PlainTextResponse

from swarmpath.service.http.deps import CoreDep, status_or_404
from swarmpath.service.util import json_safe

router = APIRouter(tags=["results"])


@router.get("/jobs/{job_id}/summary")
def job_summary(
    job_id: str, core: CoreDep, format: Literal["json", "csv"] = "json"
) -> Any:
    """The statistics tables (partial while the job runs); ``?format=csv`` for CSV."""
    summary = core.store.summary(job_id)
    if summary is None:
        raise HTTPException(404, f"unknown job {job_id!r}")
    if format == "csv":
        from swarmpath.service.store import summary_to_csv

        return PlainTextResponse(summary_to_csv(summary), media_type="text/csv")
    return json_safe(summary)


@router.get("/jobs/{job_id}/runs")
def job_runs(
    job_id: str,
    core: CoreDep,
    limit: Annotated[int, Query(ge=1, le=1000)] = 100,
    offset: Annotated[int, Query(ge=0)] = 0,
) -> dict[str, Any]:
    """One item per run (finished or not), in run_id order."""
    status = status_or_404(core, job_id)
    items = core.store.runs(job_id, limit, offset) or []
    return {"job_id": job_id, "total": status.runs_total, "limit": limit, "offset": offset,
            "items": json_safe(items)}


@router.get("/jobs/{job_id}/runs/{run_id}")
def job_run(job_id: str, run_id: int, core: CoreDep) -> dict[str, Any]:
    """One run with its convergence curve (benchmark) or path rows [x, y, t] (map)."""
    status_or_404(core, job_id)
    item = core.store.run(job_id, run_id)
    if item is None:
        raise HTTPException(404, f"job {job_id} has no run {run_id}")
    result: dict[str, Any] = json_safe(item)
    return result


@router.get("/jobs/{job_id}/mcap", response_class=FileResponse,
            responses={409: {"description": "the job has not ended yet"}})
def job_mcap(job_id: str, core: CoreDep) -> Any:
    """The job's MCAP file, once the job has ended (409 with the reason before)."""
    status_or_404(core, job_id)
    path, reason = core.mcap_path(job_id)
    if path is None:
        raise HTTPException(409, reason)
    return FileResponse(path, media_type="application/octet-stream",
                        filename=f"{job_id}.mcap")
