"""BA's compiled kernel: :mod:`swarmpath.optimizers.ba` run for run, every parameter.

Per iteration, as the reference: one draw of 3 x agents uniforms (frequency, pulse test,
loudness test), then the local walk's agents x dim numbers (uniforms for the paper's walk,
normals for the demo's: that one draws both kinds, so its stream is buffered as
``RunStreams``'), the candidates clipped and evaluated, the acceptance and the paper's loudness
and pulse-rate updates. The mean loudness is added as numpy adds it (pairwise).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from numba import njit

from swarmpath.optimizers.ba import BA
from swarmpath.optimizers.compiled.best import record_first_min
from swarmpath.optimizers.compiled.functions import pairwise_sum
from swarmpath.optimizers.compiled.objectives import evaluate, work_for
from swarmpath.optimizers.compiled.registry import Kernel, register_kernel
from swarmpath.optimizers.compiled.streams import NORMAL, RANDOM, open_stream, take
from swarmpath.registry import ParamValue


def pack(p: Mapping[str, ParamValue]) -> np.ndarray:
    return np.array([
        float(p["f_min"]), float(p["f_max"]), float(p["loudness"]), float(p["pulse_rate"]),
        float(p["alpha"]), float(p["gamma"]), float(p["walk_scale"]),
        p["updates"] == "paper", p["local_walk"] == "demo", p["acceptance"] == "own",
        p["velocity"] == "toward",
    ], dtype=np.float64)


@njit(cache=True)
def run(rng, objective, shifted, shift, lower, upper, agents, iterations, params):
    N, d, T = agents, lower.size, iterations
    f_min, f_max, alpha, gamma, walk_scale = params[0], params[1], params[4], params[5], params[6]
    paper_updates, demo_walk, own = params[7] == 1.0, params[8] == 1.0, params[9] == 1.0
    toward = params[10] == 1.0
    stream = open_stream(rng, max(N * d, 3 * N), demo_walk)  # the demo's walk: normals too
    work = work_for(N, d)
    everyone = np.ones(N, dtype=np.bool_)
    X = np.empty((N, d))
    o = take(stream, RANDOM, N * d)
    buf = stream[1][RANDOM]
    for i in range(N):
        for j in range(d):
            X[i, j] = lower[j] + (upper[j] - lower[j]) * buf[o + i * d + j]
    V = np.zeros((N, d))
    F = np.empty(N)
    best = np.full(1, np.inf)
    best_x = np.zeros(d)
    curve = np.empty(T)
    evaluate(stream, objective, shifted, shift, lower, upper, X, F, everyone, work)
    record_first_min(F, X, N, best, best_x)
    A = np.full(N, params[2])
    r = np.full(N, params[3])
    S = np.empty((N, d))
    Fn = np.empty(N)
    u = np.empty(3 * N)
    G = np.empty(d)
    for t in range(1, T + 1):
        for j in range(d):
            G[j] = best_x[j]
        reference = best[0]
        o = take(stream, RANDOM, 3 * N)  # beta, pulse test, loudness test
        for k in range(3 * N):
            u[k] = buf[o + k]
        mean = 0.0
        if demo_walk:
            o = take(stream, NORMAL, N * d)
            walk = stream[1][NORMAL]
        else:
            o = take(stream, RANDOM, N * d)
            walk = buf
            mean = (0.0 + pairwise_sum(A, 0, N)) / N
        for i in range(N):
            freq = f_min + (f_max - f_min) * u[i]
            local = u[N + i] > r[i]
            for j in range(d):
                s = (G[j] - X[i, j] if toward else X[i, j] - G[j]) * freq
                V[i, j] = V[i, j] + s
                s = X[i, j] + V[i, j]
                if local:  # around the best: demo 0.001 N(0, 1), paper U(-1, 1) <A>
                    w = walk[o + i * d + j]
                    if demo_walk:
                        w = w * walk_scale
                    else:
                        w = (w * 2.0 - 1.0) * mean
                    s = w + G[j]
                S[i, j] = min(max(s, lower[j]), upper[j])
        evaluate(stream, objective, shifted, shift, lower, upper, S, Fn, everyone, work)
        record_first_min(Fn, S, N, best, best_x)
        level = params[3] * (1.0 - math.exp(-gamma * t))
        for i in range(N):
            better = Fn[i] <= F[i] if own else Fn[i] < reference
            if better and u[2 * N + i] < A[i]:
                F[i] = Fn[i]
                for j in range(d):
                    X[i, j] = S[i, j]
                if paper_updates:
                    A[i] = A[i] * alpha
                    r[i] = level
        curve[t - 1] = best[0]
    return best[0], best_x, curve, N * (T + 1)


KERNEL = register_kernel(Kernel(BA.name, run, pack))
