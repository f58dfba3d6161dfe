"""The JSON schemas of swarmpath's own MCAP topics (/results and /curves); the Foxglove
well-known ones come from :mod:`swarmpath.service.foxglove`."""

from __future__ import annotations

from typing import Any

# -------------------------------------------------------------------------- own JSON schemas
_IDENTITY = {
    "job_id": {"type": "string"},
    "run_id": {"type": "integer", "description": "cell_index * runs_per_cell + run"},
    "cell": {"type": "string"},
    "run": {"type": "integer", "description": "run index within the cell"},
    "seed": {"type": "integer", "description": "job seed"},
}

# who ran the run and how it ended: the same fields on both kinds of result
_OUTCOME: dict[str, Any] = {
    "worker": {"type": "string"},
    "status": {"type": "string", "description": "ok or failed"},
    "failure": {"type": "string", "description": "exception text; empty unless failed"},
    "seconds": {"type": "number", "description": "wall seconds of the run"},
    "cpu_seconds": {"type": "number", "description": "CPU seconds of the run (the computing "
                    "thread's); absent: not measured"},
}

# the field's path metrics of a map run (docs/metrics.md; absent when the run has no value)
_PATH_QUALITY: dict[str, Any] = {
    "clearance_mean": {"type": "number", "description": "mean body gap along the path, m"},
    "curvature_max": {"type": "number", "description": "1/m (Bench-MR)"},
    "curvature_mean": {"type": "number", "description": "1/m (Bench-MR)"},
    "cusps": {"type": "integer", "description": "turns over 60 degrees (Bench-MR)"},
    "danger_share": {"type": "number", "description": "share of the travel time within the "
                     "danger distance of an obstacle (MRPB safety)"},
    "velocity_smoothness": {"type": "number", "description": "m/s^2 (MRPB)"},
    "angular_smoothness": {"type": "number", "description": "rad/s^2"},
    "jerk": {"type": "number", "description": "mean |da/dt|, m/s^3"},
    "costmap_cost_mean": {"type": "number", "description": "nav2 maps: mean cost 0-254 of "
                          "nav2's inflated costmap along the path"},
    "costmap_cost_max": {"type": "number", "description": "nav2 maps: largest such cost"},
}

BENCHMARK_RESULT_SCHEMA: dict[str, Any] = {
    "title": "swarmpath.BenchmarkRunResult",
    "description": "One finished benchmark run (non-finite metrics are left out)",
    "type": "object",
    "properties": {
        **_IDENTITY,
        "algorithm": {"type": "string"},
        "function": {"type": "string"},
        "dim": {"type": "integer"},
        "backend": {"type": "string", "description": "the job's backend: auto, numpy (the "
                    "reference) or numba; the numbers are the same under each"},
        **_OUTCOME,
        "best_fitness": {"type": "number"},
        "evaluations": {"type": "integer"},
    },
}

MAP_RESULT_SCHEMA: dict[str, Any] = {
    "title": "swarmpath.MapRunResult",
    "description": "One finished map run: the fields of `swarmpath plan --json` except the path",
    "type": "object",
    "properties": {
        **_IDENTITY,
        "planner": {"type": "string"},
        "map": {"type": "string"},
        "bucket": {"type": "integer", "description": "MovingAI difficulty bucket of the map (a "
                   ".scen pair: optimal length in [4b, 4b + 4) cells); absent: none"},
        **_OUTCOME,
        "success": {"type": "boolean"},
        "collisions": {"type": "integer"},
        "robot_driven_contacts": {"type": "integer", "description": "collisions: robot moved in"},
        "obstacle_driven_contacts": {"type": "integer",
                                     "description": "collisions: a moving obstacle reached it"},
        "planned_length": {"type": "number", "description": "a global planner's planned length"},
        "length": {"type": "number"},
        "error": {"type": "number", "description": "final distance to the goal"},
        "smoothness": {"type": "number"},
        "min_clearance": {"type": "number"},
        "steps": {"type": "integer"},
        "iterations": {"type": "integer"},
        "optimum": {"type": "number"},
        "gap": {"type": "number"},
        "failure_class": {"type": "string",
                          "description": "why a failed run failed (docs/planners.md)"},
        "failure_detail": {"type": "string", "description": "where and for how long"},
        "travel_time": {"type": "number", "description": "simulated seconds"},
        **_PATH_QUALITY,
    },
}

CURVE_SCHEMA: dict[str, Any] = {
    "title": "swarmpath.ConvergenceCurve",
    "description": "Best fitness after each iteration of one run (Plot: best_fitness[:] by index)",
    "type": "object",
    "properties": {
        **_IDENTITY,
        "algorithm": {"type": "string"},
        "function": {"type": "string"},
        "dim": {"type": "integer"},
        "iterations": {"type": "integer"},
        "best_fitness": {"type": "array", "items": {"type": "number"}},
    },
}

RACE_SCHEMA: dict[str, Any] = {
    "title": "swarmpath.RaceBlock",
    "description": "A raced job's block (one function and dimension) as its race left it: each "
                   "cell's runs and why it stopped, each comparison's decision "
                   "(docs/statistics.md, Racing); a field without a value (a cell still "
                   "racing has no stopped_round) is left out",
    "type": "object",
    "properties": {
        "job_id": {"type": "string"},
        "block": {"type": "object", "description": "what the block's cells share"},
        "rounds": {"type": "integer"},
        "finished": {"type": "boolean"},
        "cells": {"type": "array", "items": {"type": "object", "properties": {
            "cell": {"type": "integer"}, "key": {"type": "string"},
            "algorithm": {"type": "string"}, "runs": {"type": "integer"},
            "racing": {"type": "boolean"}, "stopped_round": {"type": "integer"},
            "reason": {"type": "string"}}}},
        "duels": {"type": "array", "items": {"type": "object", "properties": {
            "a": {"type": "string"}, "b": {"type": "string"},
            "decision": {"type": "string", "description": "different, equivalent, futile "
                         "(stopped at a look: its predictive power was below the "
                         "race's futility) or open"},
            "better": {"type": "string"}, "marker": {"type": "string"},
            "round": {"type": "integer"}, "pairs": {"type": "integer"},
            "decided_after": {"type": "integer"}, "theta": {"type": "number"},
            "low": {"type": "number"}, "high": {"type": "number"},
            "final": {"type": "boolean",
                      "description": "decided by the closing look at max_runs"},
            "closing_p": {"type": "number", "description": "open at max_runs under the "
                          "rank-sum look: the rank-sum test's two-sided p there"},
            "closing_better": {"type": "string", "description": "the side its runs lean to"},
            "look": {"type": "integer", "description": "decided by the planned look (the "
                     "rank-sum test at a group-sequential level) at this many runs"},
            "power": {"type": "number", "description": "stopped for futility: its "
                      "predictive power at that look"}}}},
    },
}

OWN_SCHEMAS = {
    s["title"]: s for s in (BENCHMARK_RESULT_SCHEMA, MAP_RESULT_SCHEMA, CURVE_SCHEMA, RACE_SCHEMA)
}
