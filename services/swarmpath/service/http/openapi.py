"""The OpenAPI document, completed: every error answer a route can give is documented, and names
are enums read from the registries (so generated clients and fuzzers build valid jobs).

* 422 on every operation (invalid parameters or body, a body over 1 MB or that does not parse, a
  job over the cost limit), with the ``{"detail": [{"loc", "msg", "type"}]}`` shape;
* 404 on every operation with a path parameter (unknown job, run or file);
* 401 on the operations that need the bearer token (when one is configured), and 507 on them
  (they write to the store, which cannot while its disk is full);
* enums: ``algorithms`` (optimizer registry), ``functions`` (function registry; ranges such as
  ``F1-F13`` are accepted too), ``planners`` (planner registry), ``maps`` (preset maps, or an
  inline scenario object), ``transform``, ``backend``; the name lists say unique items.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from fastapi import FastAPI
from fastapi.routing import APIRoute
from starlette.routing import BaseRoute

from swarmpath.service.http.deps import authorized

_ERROR = {"type": "object", "properties": {"detail": {"type": "string"}}, "required": ["detail"]}
_VALIDATION = {"$ref": "#/components/schemas/HTTPValidationError"}


def _registry_names() -> dict[str, list[str]]:
    from swarmpath.functions import list_names
    from swarmpath.functions.transforms import TRANSFORMS
    from swarmpath.optimizers import list_optimizers
    from swarmpath.optimizers.api import BACKENDS

    names = {"algorithms": list(list_optimizers()), "functions": list_names(),
             "transform": list(TRANSFORMS), "backend": list(BACKENDS)}
    try:
        from swarmpath.planners import list_planners
        from swarmpath.world.presets import list_maps

        names["planners"] = list(list_planners())
        names["maps"] = list(list_maps())
    except Exception:  # pragma: no cover - planners unavailable: map jobs are refused anyway
        pass
    return names


def _add_enums(schemas: dict[str, Any], names: dict[str, list[str]]) -> None:
    for schema in schemas.values():
        props = schema.get("properties") or {}
        for field, values in names.items():
            prop = props.get(field)
            if prop is None:
                continue
            if field in ("transform", "backend"):
                prop["enum"] = values
                continue
            prop["uniqueItems"] = True
            items = prop.get("items") or {}
            branches = items.get("anyOf")
            if branches:  # maps: a preset name or an inline scenario object
                for branch in branches:
                    if branch.get("type") == "string":
                        branch["enum"] = values
            else:
                items["enum"] = values
                prop["items"] = items
    for schema in schemas.values():  # dims: distinct too
        dims = (schema.get("properties") or {}).get("dims")
        if dims is not None and dims.get("type") == "array":
            dims["uniqueItems"] = True


def _needs_token(route: APIRoute) -> bool:
    return any(dep.call is authorized for dep in route.dependant.dependencies)


def _add_responses(routes: Sequence[BaseRoute], paths: dict[str, Any]) -> None:
    for route in routes:
        if not isinstance(route, APIRoute) or not route.include_in_schema:
            continue
        for method in route.methods:
            op = paths.get(route.path_format, {}).get(method.lower())
            if op is None:
                continue
            responses = op.setdefault("responses", {})
            responses.setdefault("422", {
                "description": "Invalid parameters or body (a body over 1 MB, one that does "
                               "not parse, a job over the cost limit): one item per problem",
                "content": {"application/json": {"schema": _VALIDATION}},
            })
            if "{" in route.path_format:
                responses.setdefault("404", {
                    "description": "Unknown job, run or file",
                    "content": {"application/json": {"schema": _ERROR}},
                })
            if _needs_token(route):  # the mutating operations write to the store
                responses.setdefault("507", {
                    "description": "The coordinator's store cannot write (its disk is full): "
                                   "nothing was stored; send it again once there is room",
                    "content": {"application/json": {"schema": _ERROR}},
                })
                responses.setdefault("401", {
                    "description": "Missing or wrong 'Authorization: Bearer <token>' (when the "
                                   "coordinator has a token)",
                    "headers": {"WWW-Authenticate": {"schema": {"type": "string"}}},
                    "content": {"application/json": {"schema": _ERROR}},
                })


def install(app: FastAPI, routes: Sequence[BaseRoute]) -> None:
    """``routes``: the application's routes (of its routers)."""
    base = app.openapi

    def openapi() -> dict[str, Any]:
        if app.openapi_schema is None:
            schema = base()
            schemas = schema.setdefault("components", {}).setdefault("schemas", {})
            schemas.setdefault("HTTPValidationError", {
                "type": "object", "properties": {"detail": {"type": "array", "items": {
                    "type": "object", "properties": {
                        "loc": {"type": "array", "items": {}}, "msg": {"type": "string"},
                        "type": {"type": "string"}},
                    "required": ["loc", "msg", "type"]}}}})
            _add_responses(routes, schema.get("paths", {}))
            _add_enums(schemas, _registry_names())
            app.openapi_schema = schema
        return app.openapi_schema

    app.openapi = openapi  # type: ignore[method-assign]
