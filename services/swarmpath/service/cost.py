"""The job cost guard: what a job would cost before it is queued, and the coordinator's limit.

A benchmark job costs function evaluations: runs x agents x iterations per cell (each iteration
evaluates every agent once), summed over its cells. A map job costs simulated time steps: per run
at most the episode's time limit (six times the straight-line travel time plus 60 s, see
:class:`swarmpath.planners.Episode`) divided by the map's time step, summed over its cells. Both
are upper bounds of the work (a run may end early), cheap to compute and independent of the
machine. Limits come from :class:`~swarmpath.service.settings.CoordinatorSettings`
(``max_job_evaluations``, ``max_job_steps``; environment ``SWARMPATH_MAX_JOB_EVALUATIONS`` and
``SWARMPATH_MAX_JOB_STEPS``)."""

from __future__ import annotations

import math
from typing import Any

from swarmpath.service.protocol import BenchmarkJobSpec, MapJobSpec, runs_total

#: Defaults: about 2 CPU-hours of vectorized benchmark runs, or of map episodes, on a 2-core
#: machine like the project's (the ICOOT paper's whole Table 2 at 1000 runs per cell is
#: 1.2e9 evaluations).
DEFAULT_MAX_EVALUATIONS = 20_000_000_000
DEFAULT_MAX_STEPS = 50_000_000


def benchmark_evaluations(spec: BenchmarkJobSpec) -> int:
    """runs x agents x iterations; with ``budget_evals``, runs x the budget of each dim."""
    if getattr(spec, "budget_evals", None) is not None:
        per_dim = sum(spec.evaluations(d) or 0 for d in spec.dims)
        return len(spec.algorithms) * len(spec.functions) * spec.runs * per_dim
    return runs_total(spec) * spec.agents * spec.iterations


def _scenario_steps(entry: Any) -> float:
    from swarmpath.planners.episode import DEFAULT_TIME_FACTOR
    from swarmpath.world.presets import get_map
    from swarmpath.world.scenario_io import scenario_from_dict

    scenario = get_map(entry) if isinstance(entry, str) else scenario_from_dict(dict(entry))
    straight = math.dist(scenario.start, scenario.goal)
    limit = DEFAULT_TIME_FACTOR * straight / scenario.robot.linear_speed + 60.0
    return math.ceil(limit / scenario.time_step)


def map_steps(spec: MapJobSpec) -> int:
    per_run = sum(_scenario_steps(entry) for entry in spec.maps)
    return int(per_run * spec.runs * len(spec.planners))


def check(spec: BenchmarkJobSpec | MapJobSpec, max_evaluations: float,
          max_steps: float) -> dict[str, Any] | None:
    """None when the job is within the limits, else a 422 detail item naming the estimate."""
    if isinstance(spec, BenchmarkJobSpec):
        cost, limit = benchmark_evaluations(spec), max_evaluations
        what = "function evaluations (runs x agents x iterations over its cells)"
        knob, loc = "max_job_evaluations / SWARMPATH_MAX_JOB_EVALUATIONS", "iterations"
    else:
        cost, limit = map_steps(spec), max_steps
        what = "simulated time steps (runs x time limit / time step over its cells)"
        knob, loc = "max_job_steps / SWARMPATH_MAX_JOB_STEPS", "runs"
    if cost <= limit:
        return None
    return {
        "loc": ["body", loc], "type": "job_too_costly",
        "msg": f"this job would cost up to {cost:.3g} {what}; this coordinator accepts at most "
               f"{limit:.3g}. Submit fewer runs, agents or iterations (or several smaller jobs), "
               f"or raise the limit where the coordinator starts ({knob}).",
        "estimate": cost, "limit": limit,
    }
