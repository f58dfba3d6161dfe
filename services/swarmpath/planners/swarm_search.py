"""One decision's swarm search: the optimizer loop of the swarm local planner.

:func:`search` runs the chosen optimizer on ``local.score`` in the candidate box for
``iterations`` iterations (or until ``patience`` iterations in a row did not improve the best)
and returns the best value and point ever evaluated and the iterations done. With ``backend =
"numba"`` the optimizers that have a compiled decision (:mod:`.compiled_decide`: COOT, ICOOT,
HPO, IHPO, MFB, HPSO-MFB) run it instead, with the same draws and the same numbers to the last
bit (``tests/test_planner_compiled.py``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from swarmpath.optimizers import Problem, RunStreams, create
from swarmpath.planners import local

Array = np.ndarray
Search = Callable[[local.StepContext, int, int, int, float], tuple[float, Array, int]]


def searcher(optimizer: str, params: Mapping[str, Any], agents: int, streams: RunStreams,
             backend: str, repair: str, objective: str) -> Search:
    """The search of one decision: ``search(ctx, agents, iterations, patience, tolerance)``.
    A compiled decision is compiled, or loaded from numba's cache, here rather than in a
    decision (a tiny one with the ``repair`` and ``objective`` of the planner, on a generator
    of its own: the planner's draws are untouched)."""
    if backend == "numba":
        from swarmpath.planners import compiled_decide

        decide = compiled_decide.decider(optimizer, params, agents)
        if decide is not None:
            compiled_decide.warm(decide, repair, objective)
            rng = streams.generators[0]
            return lambda ctx, n, t, patience, tol: decide(rng, ctx, n, t, patience, tol)

    def search(ctx: local.StepContext, n: int, iterations: int, patience: int,
               tol: float) -> tuple[float, Array, int]:
        return numpy_search(optimizer, params, streams, ctx, n, iterations, patience, tol)

    return search


def numpy_search(optimizer: str, params: Mapping[str, Any], streams: RunStreams,
                 ctx: local.StepContext, agents: int, iterations: int, patience: int,
                 tol: float) -> tuple[float, Array, int]:
    """The optimizer loop with the numpy optimizers (the reference)."""

    def objective(X: Array, streams: RunStreams) -> Array:
        cost, _ = local.score(X[0], ctx)
        return cost[None, :]

    assert ctx.lower is not None and ctx.upper is not None
    # local.score treats every candidate on its own (elementwise arithmetic, per-row
    # argmin): a candidate's cost does not depend on the batch it is scored in
    problem = Problem(objective, ctx.lower[None, :], ctx.upper[None, :], rowwise=True)
    opt = create(optimizer, problem, agents, iterations, streams, params)
    opt.initialize()
    best, stalled = float(opt.best_fitness[0]), 0
    while not opt.done:
        opt.step()
        now = float(opt.best_fitness[0])
        stalled = stalled + 1 if best - now <= tol * max(1.0, abs(best)) else 0
        best = now
        if patience and stalled >= patience and best < local.PENALTY:
            break  # converged: the last ``patience`` iterations did not improve the best
    return best, opt.best_position[0], opt.t
