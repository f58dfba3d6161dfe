"""Error answers the framework would get wrong: bodies that do not parse, and 405s.

* FastAPI answers 400 "There was an error parsing the body" when reading the JSON body raises
  anything but a JSONDecodeError: invalid UTF-8 (UnicodeDecodeError), nesting deeper than the
  parser's recursion limit (RecursionError), integers of more than 4,300 digits (ValueError).
  Those are bad input like any other: 422, naming the problem.
* Starlette's 405 lists in ``Allow`` only the methods of the first route matching the path; one
  path has several routes here (GET and DELETE /jobs/{job_id}), so the header is rebuilt from
  every route of the path. ``OPTIONS`` on a known path answers 204 with the same header.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from fastapi import FastAPI, Request
from fastapi.responses import JSONResponse, Response
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.routing import BaseRoute, Match

PARSE_ERROR = "There was an error parsing the body"


def body_problem(exc: BaseException | None) -> str:
    """Plain words for why a request body could not be read as JSON."""
    if isinstance(exc, UnicodeDecodeError):
        return f"the body is not valid UTF-8 (byte {exc.start})"
    if isinstance(exc, RecursionError):
        return "the body's JSON nests too deeply"
    if isinstance(exc, ValueError) and "digits" in str(exc):
        return "the body holds an integer with too many digits (at most 4300)"
    return "the body is not valid JSON"


def allowed_methods(routes: Sequence[BaseRoute], scope: dict[str, Any]) -> list[str]:
    """Every method of every route whose path matches the request's (with HEAD for GET and
    OPTIONS); [] for an unknown path."""
    methods: set[str] = set()
    for route in routes:
        match, _child = route.matches({**scope, "method": "GET", "type": "http"})
        if match != Match.NONE:
            methods |= set(getattr(route, "methods", None) or ())
    if "GET" in methods:
        methods.add("HEAD")
    return sorted(methods | {"OPTIONS"}) if methods else []


def install(app: FastAPI, routes: Sequence[BaseRoute]) -> None:
    """``routes``: the application's routes (of its routers)."""
    @app.exception_handler(StarletteHTTPException)
    async def _http_error(request: Request, exc: StarletteHTTPException) -> Response:
        headers = dict(exc.headers or {})
        if exc.status_code == 400 and exc.detail == PARSE_ERROR:
            detail = [{"loc": ["body"], "msg": body_problem(exc.__cause__),
                       "type": "body_unreadable"}]
            return JSONResponse({"detail": detail}, status_code=422, headers=headers)
        if exc.status_code == 405:
            allow = allowed_methods(routes, request.scope)
            if request.method == "OPTIONS" and allow:
                return Response(status_code=204, headers={"Allow": ", ".join(allow)})
            headers["Allow"] = ", ".join(allow)
        if exc.status_code in (204, 304):
            return Response(status_code=exc.status_code, headers=headers)
        return JSONResponse({"detail": exc.detail}, status_code=exc.status_code, headers=headers)
