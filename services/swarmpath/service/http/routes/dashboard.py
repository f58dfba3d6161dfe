"""The dashboard's data: JSON and event routes behind its pages (thin: the work is in
:class:`~swarmpath.service.web.live.Dashboard` and :mod:`~swarmpath.service.web.aggregates`).

* ``GET /events`` - Server-Sent Events: ``event: jobs`` with the jobs list (progress, runs/s,
  ETA) once a second when it changed; every client shares one snapshot. A stream ends after
  ``STREAM_SECONDS`` (the browser reconnects), and within a second of ``app.state.stopping``
  (set by ``swarmpath coordinator``/``up`` on SIGTERM) so it does not hold a shutdown up.
* ``GET /ui/jobs`` - the same snapshot, for clients without EventSource.
* ``GET /ui/jobs/{id}/data`` - the job page's aggregates, with an ETag (304 when unchanged).
* ``GET /ui/jobs/{id}/scene?cell=N`` (run 0's world) or ``?run=RUN_ID`` - a map cell's scene.
* ``GET /ui/config`` - whether mutating requests need a token, the job specs' defaults and the
  limits the submit form checks before it sends (the API checks them again).
"""

from __future__ import annotations

import asyncio
import json
import threading
import time
from collections.abc import AsyncIterator
from typing import Annotated, Any

from fastapi import APIRouter, HTTPException, Query, Request
from fastapi.responses import Response, StreamingResponse

from swarmpath.service.http.deps import CoreDep
from swarmpath.service.util import json_safe

router = APIRouter(tags=["dashboard"])

EVENT_SECONDS = 1.0  # the jobs list is pushed at most this often
KEEPALIVE_SECONDS = 15.0
STREAM_SECONDS = 60.0  # a stream ends after this long; EventSource reconnects
MAX_STREAMS = 200  # concurrent /events clients; more get 503


class _Streams:
    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.open = 0


_STREAMS = _Streams()


def _json(data: Any, status: int = 200, headers: dict[str, str] | None = None) -> Response:
    body = json.dumps(json_safe(data), separators=(",", ":"))
    return Response(body, status, headers=headers, media_type="application/json")


@router.get("/ui/config")
def config(request: Request) -> dict[str, Any]:
    """Whether submit/cancel need a bearer token, the defaults of the job specs' fields, the
    registered function transforms (the benchmark form's choices), and ``limits``: the most
    ``.scen`` pairs one map entry of a job may name (the pairs picker's count)."""
    from swarmpath.functions.transforms import TRANSFORMS
    from swarmpath.service.jobspec_map import MAX_SCEN_PAIRS_PER_MAP
    from swarmpath.service.protocol import BenchmarkJobSpec, MapJobSpec

    token = getattr(request.app.state, "token", None)  # create_app resolved $SWARMPATH_TOKEN

    def defaults(cls: Any) -> dict[str, Any]:
        return {name: f.get_default(call_default_factory=True)
                for name, f in cls.model_fields.items() if not f.is_required()}

    return {"token_required": bool(token),
            "defaults": {"benchmark": defaults(BenchmarkJobSpec), "map": defaults(MapJobSpec)},
            "transforms": list(TRANSFORMS),
            "limits": {"scen_pairs_per_map": MAX_SCEN_PAIRS_PER_MAP}}


@router.get("/ui/jobs")
def jobs(core: CoreDep) -> Response:
    """The jobs list (newest 200) with progress, runs/s and ETA."""
    data = core.dashboard.jobs_snapshot()
    return Response(data, media_type="application/json")


@router.get("/events")
async def events(request: Request, core: CoreDep) -> StreamingResponse:
    """Server-Sent Events: ``jobs`` (the /ui/jobs list) when it changes, at most once a second."""
    with _STREAMS.lock:
        if _STREAMS.open >= MAX_STREAMS:
            raise HTTPException(503, f"too many event streams (at most {MAX_STREAMS})")
        _STREAMS.open += 1

    async def stream() -> AsyncIterator[bytes]:
        try:
            yield b"retry: 1000\n\n"
            last, quiet, started = b"", time.monotonic(), time.monotonic()
            while (core.accepting and not getattr(request.app.state, "stopping", False)
                   and time.monotonic() - started < STREAM_SECONDS):
                if await request.is_disconnected():
                    return
                data = await asyncio.to_thread(core.dashboard.jobs_snapshot)
                body = data.split(b',"jobs":', 1)[-1]  # unchanged jobs: nothing to send
                if body != last:
                    last, quiet = body, time.monotonic()
                    yield b"event: jobs\ndata: " + data + b"\n\n"
                elif time.monotonic() - quiet > KEEPALIVE_SECONDS:
                    quiet = time.monotonic()
                    yield b": keepalive\n\n"
                await asyncio.sleep(EVENT_SECONDS)
        finally:
            with _STREAMS.lock:
                _STREAMS.open -= 1

    return StreamingResponse(stream(), media_type="text/event-stream",
                             headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"})


@router.get("/ui/jobs/{job_id}/data", responses={304: {"description": "unchanged"}})
def job_data(job_id: str, request: Request, core: CoreDep) -> Response:
    """The job page's aggregates (see :meth:`JobAggregates.view`); ETag = the job's version."""
    data = core.dashboard.page_data(job_id)
    if data is None:
        raise HTTPException(404, f"unknown job {job_id!r}")
    version, body = data
    etag = f'"{job_id}-{version}"'
    if request.headers.get("if-none-match") == etag:
        return Response(status_code=304, headers={"ETag": etag})
    return Response(body, headers={"ETag": etag, "Cache-Control": "no-cache"},
                    media_type="application/json")


@router.get("/ui/jobs/{job_id}/scene")
def job_scene(
    job_id: str,
    core: CoreDep,
    cell: Annotated[int | None, Query(ge=0)] = None,
    run: Annotated[int | None, Query(ge=0, description="run_id")] = None,
    t_end: Annotated[float, Query(ge=0, le=1e6)] = 0.0,
) -> Response:
    """A map cell's scene and (for ``run``, else its cell's run 0) the moving obstacles' and
    goal's tracks up to ``t_end`` seconds (at most as long as that run's path, or the cell's
    longest path: the tracks are simulated, so their length is bounded by what ran)."""
    spec = core.store.job_spec(job_id)
    status = core.store.job_status(job_id)
    if spec is None or status is None:
        raise HTTPException(404, f"unknown job {job_id!r}")
    if status.kind != "map":
        raise HTTPException(404, f"job {job_id} is a {status.kind} job: it has no map")
    if (cell is None) == (run is None):
        raise HTTPException(422, [{"loc": ["query", "cell"], "type": "value_error",
                                   "msg": "give either cell or run"}])
    path = None
    if run is not None:
        if run >= status.runs_total:
            raise HTTPException(404, f"job {job_id} has no run {run}")
        cell, within = divmod(run, spec.runs)
        path = (core.store.run(job_id, run) or {}).get("path")
        t_end = min(t_end, float(path[-1][2]) if path else 0.0)
    else:
        within = 0
        t_end = min(t_end, core.dashboard.longest_path(job_id, cell))
    assert cell is not None
    out = core.dashboard.scene(job_id, cell, within, t_end, spec.seed, path)
    if out is None:
        raise HTTPException(404, f"job {job_id} has no map cell {cell}")
    return _json(out)
