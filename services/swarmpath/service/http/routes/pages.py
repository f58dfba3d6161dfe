"""The dashboard's pages: the HTML shells and their scripts and styles (package data in
``swarmpath/service/web/static/``; the pages draw themselves from the JSON routes of
:mod:`.dashboard`).

``GET /`` jobs, ``/ui/jobs/{id}`` a job, ``/ui/jobs/{id}/runs/{run_id}`` a run, ``/ui/workers``,
``/ui/submit``; ``/static/{name}`` serves only the files shipped in ``static/``, and
``/favicon.ico`` their icon."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from fastapi import APIRouter, HTTPException
from fastapi.responses import FileResponse

router = APIRouter(include_in_schema=False)

STATIC = Path(str(resources.files("swarmpath.service.web") / "static"))
_TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
          ".css": "text/css; charset=utf-8", ".txt": "text/plain; charset=utf-8",
          ".svg": "image/svg+xml"}
#: Every file the pages may load (nothing else under the package is reachable).
ASSETS = {p.name: p for p in STATIC.iterdir() if p.suffix in _TYPES} if STATIC.is_dir() else {}


def _page(name: str) -> FileResponse:
    return FileResponse(ASSETS[f"{name}.html"], media_type=_TYPES[".html"],
                        headers={"Cache-Control": "no-cache"})


@router.get("/")
def jobs_page() -> FileResponse:
    return _page("jobs")


@router.get("/ui/jobs/{job_id}")
def job_page(job_id: str) -> FileResponse:
    return _page("job")


@router.get("/ui/jobs/{job_id}/runs/{run_id}")
def run_page(job_id: str, run_id: int) -> FileResponse:
    return _page("run")


@router.get("/ui/workers")
def workers_page() -> FileResponse:
    return _page("workers")


@router.get("/ui/submit")
def submit_page() -> FileResponse:
    return _page("submit")


@router.get("/favicon.ico")
def favicon() -> FileResponse:
    """The icon browsers ask for on their own (the pages name /static/favicon.svg)."""
    return FileResponse(ASSETS["favicon.svg"], media_type=_TYPES[".svg"],
                        headers={"Cache-Control": "max-age=86400"})


@router.get("/static/{name}")
def static_file(name: str) -> FileResponse:
    path = ASSETS.get(name)
    if path is None:
        raise HTTPException(404, f"no static file {name!r}")
    return FileResponse(path, media_type=_TYPES[path.suffix],
                        headers={"Cache-Control": "no-cache"})
