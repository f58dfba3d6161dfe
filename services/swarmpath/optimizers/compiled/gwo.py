"""GWO's compiled kernel: :mod:`swarmpath.optimizers.gwo` run for run, both leader rules."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numba import njit

from swarmpath.optimizers.compiled.best import record_first_min
from swarmpath.optimizers.compiled.objectives import evaluate, work_for
from swarmpath.optimizers.compiled.registry import Kernel, register_kernel
from swarmpath.optimizers.compiled.streams import RANDOM, open_stream, take
from swarmpath.registry import ParamValue

_LEADERS = ("authors", "elitist")


def pack(p: Mapping[str, ParamValue]) -> np.ndarray:
    return np.array([float(p["a_max"]), float(_LEADERS.index(str(p["leaders"])))])


@njit(cache=True)
def _keep(leaders, k, X, i):
    for j in range(X.shape[1]):
        leaders[k, j] = X[i, j]


@njit(cache=True)
def _authors(F, X, scores, leaders):
    """GWO.m's sweep: agent by agent, strict inequalities, no demotion."""
    for i in range(F.size):
        f = F[i]
        if f < scores[0]:
            scores[0] = f
            _keep(leaders, 0, X, i)
        if f > scores[0] and f < scores[1]:
            scores[1] = f
            _keep(leaders, 1, X, i)
        if f > scores[0] and f > scores[1] and f < scores[2]:
            scores[2] = f
            _keep(leaders, 2, X, i)


@njit(cache=True)
def _elitist(F, X, scores, leaders):
    """The three first of a stable sort of (leaders, population) by value: a leader keeps its
    place before an agent of the same value, and the old leaders move down in order."""
    n = F.size
    picked = np.empty(3, dtype=np.int64)  # k < 3: old leader k, else agent k - 3
    values = np.empty(3)
    for k in range(3):
        m = -1
        v = np.inf
        for c in range(n + 3):
            taken = False
            for q in range(k):
                taken = taken or picked[q] == c
            f = scores[c] if c < 3 else F[c - 3]
            if not taken and (m < 0 or f < v):
                m = c
                v = f
        picked[k] = m
        values[k] = v
    old = leaders.copy()
    for k in range(3):
        scores[k] = values[k]
        if picked[k] < 3:
            for j in range(X.shape[1]):
                leaders[k, j] = old[picked[k], j]
        else:
            _keep(leaders, k, X, picked[k] - 3)


@njit(cache=True)
def run(rng, objective, shifted, shift, lower, upper, agents, iterations, params):
    a_max, elitist = params[0], params[1] == 1.0
    N, d, T = agents, lower.size, iterations
    stream = open_stream(rng, max(6 * N * d, N), False)
    buf = stream[1][RANDOM]
    work = work_for(N, d)
    everyone = np.ones(N, dtype=np.bool_)
    X = np.empty((N, d))
    o = take(stream, RANDOM, N * d)
    for i in range(N):
        for j in range(d):
            x = lower[j] + (upper[j] - lower[j]) * buf[o + i * d + j]
            X[i, j] = min(max(x, lower[j]), upper[j])
    F = np.empty(N)
    best = np.full(1, np.inf)
    best_x = np.zeros(d)
    curve = np.empty(T)
    scores = np.full(3, np.inf)
    leaders = np.zeros((3, d))
    lead = np.empty(d)
    size = N * d
    for t in range(T + 1):
        if t:  # eqs 3.3-3.7: r (2, 3, N, d), r1 of each leader, then r2; row by row
            a = a_max * (1.0 - (t - 1) / T)
            two_a = 2.0 * a
            o = take(stream, RANDOM, 6 * size)
            for j in range(d):
                lead[j] = (leaders[0, j] + leaders[1, j]) + leaders[2, j]
            for i in range(N):
                p = o + i * d
                for j in range(d):
                    x = X[i, j]
                    s0 = (buf[p + j] * two_a - a) * abs(buf[p + 3 * size + j] * 2.0 * leaders[0, j]
                                                        - x)
                    s1 = (buf[p + size + j] * two_a - a) * abs(
                        buf[p + 4 * size + j] * 2.0 * leaders[1, j] - x)
                    s2 = (buf[p + 2 * size + j] * two_a - a) * abs(
                        buf[p + 5 * size + j] * 2.0 * leaders[2, j] - x)
                    x = (lead[j] - ((s0 + s1) + s2)) / 3.0
                    X[i, j] = min(max(x, lower[j]), upper[j])
        evaluate(stream, objective, shifted, shift, lower, upper, X, F, everyone, work)
        record_first_min(F, X, N, best, best_x)
        if elitist:
            _elitist(F, X, scores, leaders)
        else:
            _authors(F, X, scores, leaders)
        if t:
            curve[t - 1] = best[0]
    return best[0], best_x, curve, N * (T + 1)


KERNEL = register_kernel(Kernel("GWO", run, pack))
