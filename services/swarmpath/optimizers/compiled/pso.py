"""PSO's compiled kernel: :mod:`swarmpath.optimizers.pso` run for run, every parameter.

With ``bounds = "fly"`` a particle outside the box is not evaluated, so a run's evaluations
vary and a study's budget can end it inside an iteration: the kernel counts the budget itself
(``Kernel.capped``; a particle past it is neither computed nor counted, and keeps its pbest).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numba import njit

from swarmpath.optimizers.compiled.best import record_masked, within_budget
from swarmpath.optimizers.compiled.objectives import evaluate, work_for
from swarmpath.optimizers.compiled.registry import Kernel, register_kernel
from swarmpath.optimizers.compiled.streams import RANDOM, open_stream, take
from swarmpath.registry import ParamValue

_VMAX_MODES = ("absolute", "range", "none")
_BOUNDS = ("fly", "clip")


def pack(p: Mapping[str, ParamValue]) -> np.ndarray:
    return np.array([
        float(p["c1"]), float(p["c2"]), float(p["w_max"]), float(p["w_min"]), float(p["vmax"]),
        float(_VMAX_MODES.index(str(p["vmax_mode"]))), float(p["vmax_fraction"]),
        float(_BOUNDS.index(str(p["bounds"]))),
        -1.0,  # the evaluation budget (Kernel.capped): the dispatcher fills it
    ])


@njit(cache=True)
def run(rng, objective, shifted, shift, lower, upper, agents, iterations, params):
    c1, c2, w_max, w_min = params[0], params[1], params[2], params[3]
    mode, fraction, clip, budget = int(params[5]), params[6], params[7] == 1.0, params[8]
    same, clamp = c1 == c2, mode != 2
    N, d, T = agents, lower.size, iterations
    stream = open_stream(rng, max(2 * N * d, N), False)
    buf = stream[1][RANDOM]
    work = work_for(N, d)
    inside = np.ones(N, dtype=np.bool_)
    counted = np.empty(N, dtype=np.bool_)  # the particles inside that fit the budget
    vmax = np.empty(d)
    vmin = np.empty(d)
    for j in range(d):
        vmax[j] = fraction * (upper[j] - lower[j]) if mode == 1 else params[4]
        vmin[j] = -vmax[j]
    X = np.empty((N, d))
    o = take(stream, RANDOM, N * d)
    for i in range(N):
        for j in range(d):
            X[i, j] = lower[j] + (upper[j] - lower[j]) * buf[o + i * d + j]
    V = np.zeros((N, d))
    F = np.empty(N)
    best = np.full(1, np.inf)
    best_x = np.zeros(d)
    curve = np.empty(T)
    within_budget(inside, counted, 0, budget)
    evaluate(stream, objective, shifted, shift, lower, upper, X, F, counted, work)
    evaluations = record_masked(F, X, counted, best, best_x)
    PF = np.empty(N)
    P = np.empty((N, d))
    for i in range(N):
        PF[i] = F[i]
        for j in range(d):
            P[i, j] = X[i, j]
    G = np.empty(d)
    for t in range(1, T + 1):
        w = w_max - (t - 1) * (w_max - w_min) / T
        for j in range(d):
            G[j] = best_x[j]
        o = take(stream, RANDOM, 2 * N * d)  # r1, then r2
        o2 = o + N * d
        for i in range(N):
            ok = True
            for j in range(d):
                x = X[i, j]
                a = buf[o + i * d + j] * (P[i, j] - x)
                b = buf[o2 + i * d + j] * (G[j] - x)
                s = (a + b) * c1 if same else a * c1 + b * c2
                v = V[i, j] * w + s
                if clamp:  # np.maximum, then np.minimum (NaN stays NaN)
                    v = vmin[j] if v < vmin[j] else v
                    v = vmax[j] if v > vmax[j] else v
                V[i, j] = v
                x = x + v
                if clip:
                    x = lower[j] if x < lower[j] else x
                    x = upper[j] if x > upper[j] else x
                elif x < lower[j] or x > upper[j]:
                    ok = False
                X[i, j] = x
            inside[i] = ok
        within_budget(inside, counted, evaluations, budget)
        evaluate(stream, objective, shifted, shift, lower, upper, X, F, counted, work)
        evaluations += record_masked(F, X, counted, best, best_x)
        for i in range(N):
            if F[i] < PF[i]:
                PF[i] = F[i]
                for j in range(d):
                    P[i, j] = X[i, j]
        curve[t - 1] = best[0]
    return best[0], best_x, curve, evaluations


KERNEL = register_kernel(Kernel("PSO", run, pack, capped=True))
