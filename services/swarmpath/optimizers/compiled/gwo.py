"""GWO's compiled kernel: :mod:`swarmpath.optimizers.gwo` run for run, both leader rules."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numba import njit

from swarmpath.optimizers.compiled.best import record_first_min
from swarmpath.optimizers.compiled.functions import evaluate
from swarmpath.optimizers.compiled.registry import Kernel, register_kernel
from swarmpath.optimizers.compiled.streams import RANDOM, open_stream, take
from swarmpath.registry import ParamValue

_LEADERS = ("authors", "elitist")


def pack(p: Mapping[str, ParamValue]) -> np.ndarray:
    return np.array([float(p["a_max"]), float(_LEADERS.index(str(p["leaders"])))])


@njit(cache=True)
def _authors(F, X, scores, leaders):
    """GWO.m's sweep: agent by agent, strict inequalities, no demotion."""
    for i in range(F.size):
        f = F[i]
        if f < scores[0]:
            scores[0] = f
            leaders[0] = X[i]
        if f > scores[0] and f < scores[1]:
            scores[1] = f
            leaders[1] = X[i]
        if f > scores[0] and f > scores[1] and f < scores[2]:
            scores[2] = f
            leaders[2] = X[i]


@njit(cache=True)
def _elitist(F, X, scores, leaders):
    """The three first of a stable sort of (leaders, population) by value."""
    n = F.size + 3
    pool = np.empty(n)
    pool[:3] = scores
    pool[3:] = F
    taken = np.zeros(n, dtype=np.bool_)
    new_scores = np.empty(3)
    new_leaders = np.empty_like(leaders)
    for k in range(3):
        m = -1
        for i in range(n):
            if not taken[i] and (m < 0 or pool[i] < pool[m]):
                m = i
        taken[m] = True
        new_scores[k] = pool[m]
        new_leaders[k] = leaders[m] if m < 3 else X[m - 3]
    scores[:] = new_scores
    leaders[:] = new_leaders


@njit(cache=True)
def run(rng, fid, shifted, shift, lower, upper, agents, iterations, params):
    a_max, elitist = params[0], params[1] == 1.0
    N, d, T = agents, lower.size, iterations
    stream = open_stream(rng, max(6 * N * d, N))
    buf = stream[1][RANDOM]
    work = np.empty((4, d))
    everyone = np.ones(N, dtype=np.bool_)
    X = np.empty((N, d))
    o = take(stream, RANDOM, N * d)
    for i in range(N):
        for j in range(d):
            x = lower[j] + (upper[j] - lower[j]) * buf[o + i * d + j]
            X[i, j] = min(max(x, lower[j]), upper[j])
    F = np.empty(N)
    best = np.array([np.inf])
    best_x = np.zeros(d)
    curve = np.empty(T)
    scores = np.full(3, np.inf)
    leaders = np.zeros((3, d))
    evaluate(stream, fid, shifted, shift, lower, upper, X, F, everyone, work)
    evaluations = N
    record_first_min(F, X, F.size, best, best_x)
    if elitist:
        _elitist(F, X, scores, leaders)
    else:
        _authors(F, X, scores, leaders)
    size = N * d
    for t in range(1, T + 1):
        a = a_max * (1.0 - (t - 1) / T)
        two_a = 2.0 * a
        o = take(stream, RANDOM, 6 * size)  # (2, 3, N, d): r1 of each leader, then r2
        for j in range(d):
            lead = (leaders[0, j] + leaders[1, j]) + leaders[2, j]
            for i in range(N):
                x = X[i, j]
                s0 = 0.0
                s1 = 0.0
                s2 = 0.0
                for k in range(3):
                    r1 = buf[o + k * size + i * d + j]
                    r2 = buf[o + (3 + k) * size + i * d + j]
                    A = r1 * two_a - a
                    D = abs(r2 * 2.0 * leaders[k, j] - x)
                    if k == 0:
                        s0 = A * D
                    elif k == 1:
                        s1 = A * D
                    else:
                        s2 = A * D
                x = (lead - ((s0 + s1) + s2)) / 3.0
                X[i, j] = min(max(x, lower[j]), upper[j])
        evaluate(stream, fid, shifted, shift, lower, upper, X, F, everyone, work)
        evaluations += N
        record_first_min(F, X, F.size, best, best_x)
        if elitist:
            _elitist(F, X, scores, leaders)
        else:
            _authors(F, X, scores, leaders)
        curve[t - 1] = best[0]
    return best[0], best_x, curve, evaluations


KERNEL = register_kernel(Kernel("GWO", run, pack))
