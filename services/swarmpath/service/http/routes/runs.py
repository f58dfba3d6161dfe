"""A job's results: the summary tables, the runs, one run, the MCAP file."""

from typing import Any, Literal

import pydantic_core
from fastapi import APIRouter, HTTPException
from fastapi.responses import FileResponse, PlainTextResponse, StreamingResponse

from swarmpath.evidence.legend import legend
from swarmpath.service.http.deps import CoreDep, Limit, Offset, RunId, status_or_404
from swarmpath.service.http.models import Run, RunsPage, Summary
from swarmpath.service.util import json_safe

router = APIRouter(tags=["results"])
# The response models (Summary, RunsPage, Run) are documented in /openapi.json through
# ``responses``, not validated per request: the routes stay as fast as they were.


@router.get("/jobs/{job_id}/summary",
            responses={200: {"model": Summary, "content": {"text/csv": {}}}})
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
    summary["legend"] = dict(legend(summary["columns"]))
    return json_safe(summary)


@router.get("/jobs/{job_id}/runs", responses={200: {"model": RunsPage, "content": {
    "text/csv": {}, "application/vnd.apache.parquet": {}, "application/x-ndjson": {}}}})
def job_runs(
    job_id: str,
    core: CoreDep,
    limit: Limit = 100,
    offset: Offset = 0,
    format: Literal["json", "csv", "parquet", "jsonl"] = "json",
) -> Any:
    """One item per run (finished or not), in run_id order: a page of JSON items, or every
    run streamed as CSV or Parquet (one row per run, :mod:`swarmpath.evidence.exports` columns) or
    as JSON lines (each item with its cell ``spec`` and series: curve and best position, or path).
    """
    status = status_or_404(core, job_id)
    if format == "json":
        items = core.store.runs(job_id, limit, offset) or []
        return {"job_id": job_id, "total": status.runs_total, "limit": limit, "offset": offset,
                "items": json_safe(items)}
    return _stream(core, job_id, status.kind, format)


def _stream(core: Any, job_id: str, kind: str, format: str) -> StreamingResponse:
    from swarmpath.evidence import exports

    items = core.store.iter_runs(job_id, series=True)
    name = f"{job_id}-runs.{format}"
    headers = {"Content-Disposition": f'attachment; filename="{name}"'}
    if format == "jsonl":
        lines = (pydantic_core.to_json(json_safe(item)) + b"\n" for item in items)
        return StreamingResponse(lines, media_type="application/x-ndjson", headers=headers)
    rows = exports.rows(items, job_id)
    if format == "csv":
        return StreamingResponse(exports.csv_chunks(kind, rows), media_type="text/csv",
                                 headers=headers)
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise HTTPException(501, f"Parquet {exports.NEEDS_DATA_EXTRA} on the coordinator"
                            ) from None
    return StreamingResponse(exports.parquet_chunks(kind, rows),
                             media_type="application/vnd.apache.parquet", headers=headers)


@router.get("/jobs/{job_id}/runs/{run_id}", responses={200: {"model": Run}})
def job_run(job_id: str, run_id: RunId, core: CoreDep) -> Any:
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
