"""One run of ``swarmpath plan`` as a JSON-ready dict, the task its worker processes compute.

Kept out of the ``cli`` package: a ``plan -j`` child unpickles :func:`episode_task` and so imports
this module and the planners only (:mod:`swarmpath.parallel`).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Mapping
from typing import Any, NamedTuple


class EpisodeTask(NamedTuple):
    """Everything one run depends on (the results are the same in any process)."""

    scenario: Any
    planner: str
    seed: int
    run: int
    params: Mapping[str, Any] | None
    optimum_budget: float | None


def run_episode(task: EpisodeTask, on_step: Callable[[], None] | None = None) -> dict[str, Any]:
    """One run as a JSON-ready dict (``RunOutcome`` fields).

    A planner that raises (a bug: planners report failures as results) gives a failed run whose
    reason names the exception; the error is also noted on stderr.
    """
    from swarmpath.planners import Episode

    scenario, planner, run = task.scenario, task.planner, task.run
    ep = None
    try:
        ep = Episode(scenario, planner, task.seed, run, task.params,
                     optimum_budget=task.optimum_budget)
        while not ep.done:
            ep.step()
            if on_step is not None:
                on_step()
        return ep.outcome().to_dict()
    except Exception as exc:  # recorded as a failed run, never hidden
        reason = f"internal error: {type(exc).__name__}: {exc}"
        print(f"swarmpath plan: warning: {planner} on {scenario.name} run {run}: {reason}",
              file=sys.stderr, flush=True)
        if ep is not None:
            try:
                out = ep.outcome().to_dict()
                out.update(success=False, reason=reason, failure_class="error",
                           failure_detail=reason)
                return out
            except Exception:
                pass
        return {
            "planner": planner, "map": scenario.name, "run": run, "seed": task.seed,
            "success": False, "reason": reason, "collisions": 0, "length": 0.0,
            "error": math.dist(scenario.start, scenario.goal), "smoothness": 0.0,
            "ompl_smoothness": 0.0, "min_clearance": None, "steps": 0, "iterations": 0,
            "seconds": 0.0, "travel_time": 0.0, "optimum": None, "gap": None,
            "planned_length": None, "robot_driven_contacts": 0, "obstacle_driven_contacts": 0,
            "failure_class": "error", "failure_detail": reason,
            "cpu_seconds": 0.0,
            "path": [[float(scenario.start[0]), float(scenario.start[1]), 0.0]],
        }


def episode_task(task: EpisodeTask, report: Callable[[int], None]) -> dict[str, Any]:
    """:func:`run_episode` as a :func:`swarmpath.parallel.run_tasks` compute function (one unit
    of progress per simulated step), JSON-safe."""
    from swarmpath.planners.summary import json_safe

    return dict(json_safe(run_episode(task, lambda: report(1))))
