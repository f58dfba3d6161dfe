"""One planner episode with the CPU time of its decisions measured (plan_time.py, planners.py).

The planner's ``decide`` is wrapped to add up process time, which a shared machine distorts less
than the wall time ``seconds`` the episode reports itself."""

from __future__ import annotations

import time
from typing import Any

from swarmpath.planners import Episode


def timed_episode(scenario: Any, planner: str, seed: int,
                  params: dict[str, Any] | None = None) -> tuple[float, Any]:
    """(CPU s of the decisions, outcome) of run 0 of ``seed``, as ``swarmpath plan`` runs it."""
    ep = Episode(scenario, planner, seed, 0, params)
    decide = ep.planner.decide
    spent = 0.0

    def timed(obs: Any) -> Any:
        nonlocal spent
        started = time.process_time()
        try:
            return decide(obs)
        finally:
            spent += time.process_time() - started

    ep.planner.decide = timed  # type: ignore[method-assign]
    out = ep.run()
    return spent, out
