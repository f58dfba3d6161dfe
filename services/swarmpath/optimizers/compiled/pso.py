"""PSO's compiled kernel: :mod:`swarmpath.optimizers.pso` run for run, every parameter."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numba import njit

from swarmpath.optimizers.compiled.best import record_first_min
from swarmpath.optimizers.compiled.functions import evaluate
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
    ])


@njit(cache=True)
def run(rng, fid, shifted, shift, lower, upper, agents, iterations, params):
    c1, c2, w_max, w_min = params[0], params[1], params[2], params[3]
    mode, fraction, clip = int(params[5]), params[6], params[7] == 1.0
    N, d, T = agents, lower.size, iterations
    stream = open_stream(rng, max(2 * N * d, N))
    buf = stream[1][RANDOM]
    work = np.empty((4, d))
    everyone = np.ones(N, dtype=np.bool_)
    inside = np.ones(N, dtype=np.bool_)
    vmax = np.empty(d)
    for j in range(d):
        vmax[j] = fraction * (upper[j] - lower[j]) if mode == 1 else params[4]
    X = np.empty((N, d))
    o = take(stream, RANDOM, N * d)
    for i in range(N):
        for j in range(d):
            X[i, j] = lower[j] + (upper[j] - lower[j]) * buf[o + i * d + j]
    V = np.zeros((N, d))
    F = np.empty(N)
    best = np.array([np.inf])
    best_x = np.zeros(d)
    curve = np.empty(T)
    evaluate(stream, fid, shifted, shift, lower, upper, X, F, everyone, work)
    evaluations = N
    record_first_min(F, X, F.size, best, best_x)
    pbest_f = F.copy()
    pbest = X.copy()
    G = np.empty(d)
    for t in range(1, T + 1):
        w = w_max - (t - 1) * (w_max - w_min) / T
        G[:] = best_x
        o = take(stream, RANDOM, 2 * N * d)
        o2 = o + N * d
        for i in range(N):
            out = False
            for j in range(d):
                x = X[i, j]
                a = buf[o + i * d + j] * (pbest[i, j] - x)
                b = buf[o2 + i * d + j] * (G[j] - x)
                if c1 == c2:
                    s = (a + b) * c1
                else:
                    s = a * c1 + b * c2
                v = V[i, j] * w + s
                if mode != 2:
                    if v < -vmax[j]:
                        v = -vmax[j]
                    if v > vmax[j]:
                        v = vmax[j]
                V[i, j] = v
                x = x + v
                if clip:
                    if x < lower[j]:
                        x = lower[j]
                    if x > upper[j]:
                        x = upper[j]
                elif x < lower[j] or x > upper[j]:
                    out = True
                X[i, j] = x
            inside[i] = not out
        evaluate(stream, fid, shifted, shift, lower, upper, X, F, inside, work)
        for i in range(N):
            if inside[i]:
                evaluations += 1
        record_first_min(F, X, F.size, best, best_x)
        for i in range(N):
            if F[i] < pbest_f[i]:
                pbest_f[i] = F[i]
                pbest[i] = X[i]
        curve[t - 1] = best[0]
    return best[0], best_x, curve, evaluations


KERNEL = register_kernel(Kernel("PSO", run, pack))
