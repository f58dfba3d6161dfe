"""One swarm decision of the ICOOT and COOT planners compiled: the optimizer's whole loop.

The reference is the numpy loop of ``SwarmLocalPlanner._decide`` (``create``, ``initialize``,
``step`` until done or ``patience`` stalls) with :class:`~swarmpath.optimizers.icoot.ICOOT`
(or COOT) on one run whose objective is ``local.score``. The iteration is that of the
optimizers' own compiled COOT kernel (:mod:`swarmpath.optimizers.compiled.coot`, bit for bit
the numpy reference's numbers, ``tests/test_compiled_coot.py``; both call the phases of
:mod:`swarmpath.optimizers.compiled.coot_phases`) with two changes: the draws go
straight to the planner's generator (its ``RunStreams`` does not buffer), one ``rng.random``
per draw of the reference, in its order and sizes; and the objective is the compiled score
(:func:`.compiled_score.score_into`). A decision gives the same best point, value and number
of iterations as the numpy loop, and leaves the generator where the loop leaves it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numba import njit

import swarmpath.optimizers.compiled  # noqa: F401 - first: numba's versioned cache directory
from swarmpath.optimizers.compiled.coot_phases import (
    accelerate,
    accept_leaders,
    move_coots,
    offsets,
    propose_leaders,
    split,
    swap,
)
from swarmpath.planners.compiled_score import score_into

Array = np.ndarray
_RANDOMS = ("mixed", "vector", "scalar")
_TARGETS = ("centred", "literal", "offset", "midpoint")


def pack(name: str, p: Mapping[str, Any]) -> Array:
    """The kernel's parameter vector of COOT or ICOOT's resolved parameters."""
    icoot = name == "ICOOT"
    power_ = float(p.get("density_power", 2.0))
    omega = math.pi ** (power_ / 2.0) / math.gamma(power_ / 2.0 + 1.0)  # as icoot.py
    return np.array([
        icoot, int(p["leaders"]), float(p["leader_fraction"]), _RANDOMS.index(str(p["randoms"])),
        p["gbest"] == "any", p["mirror"] == "minus", p["leader_update"] == "code",
        p["counter"] == "code", _TARGETS.index(str(p.get("random_target", "centred"))),
        icoot and p["acc"] == "density", float(p.get("cell", 0.1)), power_,
        float(p.get("leader_gain", 1.0)), omega,
    ], dtype=np.float64)


@njit(cache=True)
def record(F: Array, X: Array, m: int, best: Array, best_x: Array) -> None:
    """``Optimizer.record``: NaN counts as +inf (in F too), the first minimum, strict <."""
    k = 0
    for i in range(m):
        if np.isnan(F[i]):
            F[i] = np.inf
        if F[i] < F[k]:
            k = i
    if F[k] < best[0]:
        best[0] = F[k]
        best_x[:] = X[k]


@njit(cache=True)
def stalled_after(before: float, now: float, stalled: int, tol: float) -> int:
    """The planner's count of iterations in a row without improvement (``patience``)."""
    if before - now <= tol * max(1.0, abs(before)):
        return stalled + 1
    return 0


@njit(cache=True)
def initialize(rng: Any, lb: Array, ub: Array, N: int, geo: Array, hits: Array, k: Array,
               best: Array, best_x: Array) -> tuple[Array, Array]:
    """``Optimizer.initialize``: N uniform agents in [lb, ub] (one draw of N * d, row by row),
    scored and recorded; (agents, values)."""
    d = lb.size
    span = ub - lb
    X = np.empty((N, d))
    F = np.empty(N)
    draw = rng.random(N * d)
    for i in range(N):
        for j in range(d):
            X[i, j] = lb[j] + span[j] * draw[i * d + j]
    score_into(X, geo, hits, k, F)
    record(F, X, N, best, best_x)
    return X, F


@njit(cache=True)
def _draw(rng: Any, u: Array, at: int, size: int) -> None:
    u[at : at + size] = rng.random(size)


@njit(cache=True)
def coot_decide(rng: Any, lb: Array, ub: Array, N: int, T: int, params: Array, geo: Array,
                hits: Array, k: Array, patience: int, tol: float) -> tuple[float, Array, int]:
    """(best value, best point, iterations done) of one decision."""
    d = lb.size
    icoot, randoms = params[0] == 1.0, int(params[3])
    nl = int(params[1])
    if nl == 0:
        nl = math.ceil(params[2] * N)
    gbest_any, mirror_minus = params[4] == 1.0, params[5] == 1.0
    leader_code, counter_code = params[6] == 1.0, params[7] == 1.0
    target, use_acc = int(params[8]), params[9] == 1.0
    cell, power_, leader_gain, omega = params[10], params[11], params[12], params[13]
    nc = N - nl
    span = ub - lb
    mid = 0.5 * (lb + ub)
    cells = cell * span
    best = np.full(1, np.inf)
    best_x = np.zeros(d)
    rest_min = np.empty(d)
    call = np.zeros(10, dtype=np.int64)

    # ---- initialization: N uniform agents, coots first
    X, F = initialize(rng, lb, ub, N, geo, hits, k, best, best_x)
    CP, CF, LP, LF, g, gf, leader_of = split(X, F, N, nl)
    o_v1, _, o_lflag, o_lv1, _, o_extra = offsets(nc, nl, d)
    u = np.empty(o_extra + (nc + nl if icoot else 0))
    acc_c = np.ones(nc)
    acc_l = np.ones(nl)
    g0 = np.empty(d)
    temp = np.empty((nl, d))
    TF = np.empty(nl)
    inv = 1.0 / (T + 1) if counter_code else 1.0 / T
    before = best[0]
    stalled = 0
    t = 0
    while t < T:
        t += 1
        step = t + 1 if counter_code else t
        A = 1.0 - step * inv
        B = 2.0 - step * inv
        _draw(rng, u, 0, 5 * nc)
        _draw(rng, u, o_v1, 2 * nc * d)
        _draw(rng, u, o_lflag, 4 * nl)
        _draw(rng, u, o_lv1, 2 * nl * d)
        if icoot:  # c_accU, l_accU (one draw when of equal shape: the same numbers)
            _draw(rng, u, o_extra, nc + nl)
        if use_acc:
            accelerate(CP, cells, power_, omega, rest_min, call, u, acc_c, acc_l)
        move_coots(CP, LP, leader_of, u, randoms, A, acc_c, use_acc, icoot, target, g, lb, ub,
                   span, mid)
        score_into(CP, geo, hits, k, CF)
        record(CF, CP, nc, best, best_x)

        gf = swap(CP, CF, LP, LF, leader_of, gbest_any, g, gf)
        propose_leaders(LP, g, g0, temp, u, nc, randoms, B * leader_gain, acc_l, use_acc,
                        mirror_minus, lb, ub)
        score_into(temp, geo, hits, k, TF)
        record(TF, temp, nl, best, best_x)
        gf = accept_leaders(LP, LF, temp, TF, g0, g, gf, leader_code)
        stalled = stalled_after(before, best[0], stalled, tol)
        before = best[0]
        if patience > 0 and stalled >= patience and before < 1e6:
            break
    return best[0], best_x, t
