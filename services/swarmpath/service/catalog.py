"""The catalog: what can be run (optimizers, functions, suites, planners, maps) with their
parameters, read from the registries; every optimizer, function, suite and planner with its
origin (built-in, distribution and version, file) and the sha256 digest of its code, as
``swarmpath plugins`` lists them on the coordinator's machine."""

from __future__ import annotations

import logging
from typing import Any

from swarmpath.service.util import json_safe
from swarmpath.service.util import short as _short

log = logging.getLogger("swarmpath.coordinator")


def warm_registries() -> None:
    """Import the registries once at startup (validation imports them lazily)."""
    try:
        import swarmpath.planners  # noqa: F401
    except Exception as exc:
        log.warning("planners unavailable: map jobs will be rejected (%s)", _short(exc))


def build_catalog() -> dict[str, Any]:
    from swarmpath.functions import get_function, get_suite, list_functions, list_suites
    from swarmpath.functions.registry import SUITES, function_origin
    from swarmpath.optimizers import get_optimizer, list_optimizers
    from swarmpath.optimizers.registry import REGISTRY as OPTIMIZERS
    from swarmpath.plugins.catalog import origin_fields, problems

    out: dict[str, Any] = {"optimizers": [], "functions": [], "suites": [], "planners": [],
                           "maps": []}
    for name in list_optimizers():
        cls = get_optimizer(name)
        out["optimizers"].append({
            "name": name, "summary": cls.summary, "reference": cls.reference,
            "min_agents": cls.min_agents, "params": dict(cls.defaults),
            "choices": {k: list(v) for k, v in cls.choices.items()},
            **origin_fields(OPTIMIZERS.origin(name)),
        })
    for name in list_functions():
        fn = get_function(name)
        out["functions"].append({
            "name": name, "description": fn.description, "lower": fn.lower, "upper": fn.upper,
            "f_min_per_dim": fn.f_min_per_dim, "f_min_constant": fn.f_min_constant,
            "noisy": fn.noisy, **origin_fields(function_origin(name)),
        })
    for name in list_suites():
        suite = get_suite(name)
        dims = getattr(suite.functions[0], "dimensions", None)
        out["suites"].append({
            "name": name, "description": suite.description, "members": list(suite.members),
            "functions": [f.name for f in suite.functions],
            "dims": None if dims is None else list(dims),
            "bounds": [suite.functions[0].lower, suite.functions[0].upper],
            **origin_fields(SUITES.origin(name)),
        })
    try:
        from swarmpath.planners import get_planner, list_planners
        from swarmpath.planners.base import REGISTRY as PLANNERS

        for name in list_planners():
            planner = get_planner(name)
            out["planners"].append({
                "name": name, "kind": planner.kind, "description": planner.description,
                "reference": planner.reference, "params": dict(planner.defaults),
                "choices": {k: list(v) for k, v in planner.choices.items()},
                **origin_fields(PLANNERS.origin(name)),
            })
        out["planner_families"] = [
            {"name": family.replace("<name>", "<optimizer>"), "optimizers": list_optimizers(),
             "description": "the seeds' swarm local planner driven by any registered optimizer",
             **origin_fields(PLANNERS.origin(family.replace("<name>", "PSO")))}
            for family in PLANNERS.families()]
    except Exception as exc:
        out["planners_unavailable"] = _short(exc)
    out["plugin_problems"] = problems()
    try:
        from swarmpath.world.presets import get_map, list_maps

        for name in list_maps():
            sc = get_map(name)
            out["maps"].append({
                "name": name, "description": sc.description,
                "size": [float(v) for v in sc.size], "dynamic": bool(sc.is_dynamic),
            })
    except Exception as exc:
        out["maps_unavailable"] = _short(exc)
    return json_safe(out)
