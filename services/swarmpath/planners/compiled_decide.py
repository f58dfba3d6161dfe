"""The compiled swarm decision of ``backend = "numba"``: which optimizers have one, and the call.

A decision kernel runs the whole optimizer loop of one decision of
``SwarmLocalPlanner._decide`` (initialization, iterations, ``patience``) with the compiled
objective, and returns what the numpy loop leaves: the best value and point ever evaluated and
the number of iterations done; the planner's generator advances by the same draws. Optimizers
without a kernel (and parameter values a kernel does not implement) run the numpy loop, with
the compiled objective.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from swarmpath.optimizers import get_optimizer
from swarmpath.planners import compiled_bats, compiled_coot, compiled_hpo, local
from swarmpath.planners.compiled_score import setup

Array = np.ndarray
Decide = Callable[[np.random.Generator, local.StepContext, int, int, int, float],
                  tuple[float, Array, int]]


def _calling(kernel: Callable[..., tuple[float, Array, int]], params: Array) -> Decide:
    """The decision that calls ``kernel`` (COOT's or HPO's signature) with ``params``."""

    def decide(rng, ctx, agents, iterations, patience, tol):
        geo, k = setup(ctx)
        return kernel(rng, geo[4:6].copy(), geo[6:8].copy(), agents, iterations, params, geo,
                      _hits(ctx), k, patience, tol)

    return decide


def _coot(name: str, p: Mapping[str, Any], agents: int) -> Decide | None:
    return _calling(compiled_coot.coot_decide, compiled_coot.pack(name, p))


def _hpo(name: str, p: Mapping[str, Any], agents: int) -> Decide | None:
    params = compiled_hpo.pack(name, p)
    return None if params is None else _calling(compiled_hpo.hpo_decide, params)


def _bats(name: str, p: Mapping[str, Any], agents: int) -> Decide | None:
    params = compiled_bats.pack(name, p, agents)
    if params is None:
        return None
    decays: dict[int, Array] = {}

    def decide(rng, ctx, agents, iterations, patience, tol):
        geo, k = setup(ctx)
        decay = decays.get(iterations)
        if decay is None:
            decay = decays[iterations] = compiled_bats.levels(p, iterations)
        return compiled_bats.bats_decide(rng, geo[4:6].copy(), geo[6:8].copy(), agents,
                                         iterations, params, decay, geo, _hits(ctx), k,
                                         patience, tol)

    return decide


_KERNELS: dict[str, Callable[[str, Mapping[str, Any], int], Decide | None]] = {
    "COOT": _coot, "ICOOT": _coot, "HPO": _hpo, "IHPO": _hpo, "MFB": _bats, "HPSO-MFB": _bats,
}


def _hits(ctx: local.StepContext) -> Array:
    return np.ascontiguousarray(ctx.hits, dtype=float).reshape(-1, 2)


def names() -> list[str]:
    """Optimizers with a compiled decision."""
    return list(_KERNELS)


def decider(optimizer: str, params: Mapping[str, Any], agents: int) -> Decide | None:
    """The compiled decision of ``optimizer`` with resolved ``params`` and ``agents``, or None:
    no kernel, or a setting the optimizer refuses (the numpy loop then raises its error)."""
    make = _KERNELS.get(optimizer)
    if make is None or agents < get_optimizer(optimizer).min_agents:
        return None
    if optimizer in ("COOT", "ICOOT"):
        leaders = int(params["leaders"]) or math.ceil(float(params["leader_fraction"]) * agents)
        if not 1 <= leaders < agents:
            return None
    return make(optimizer, params, agents)


def warm(decide: Decide, repair: str, objective: str) -> None:
    """Compile or load the kernel of ``decide`` (a tiny decision on a generator of its own)."""
    ctx = local.StepContext(position=np.zeros(2), goal=np.array([2.0, 0.0]),
                            hits=np.array([[1.0, 0.0]]), margin=0.5, repair=repair,
                            objective=objective, lower=-np.ones(2), upper=np.ones(2),
                            backend="numba")
    decide(np.random.default_rng(0), ctx, 6, 2, 0, 1e-6)
