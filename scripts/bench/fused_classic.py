"""Independent fused loops of PSO, GWO, SSA and FDO (default parameters), for
``scripts/bench/kernels.py``: see ``fused_common.py`` for what "independent" and "fused" mean.
Each ``make_*`` returns the loop compiled with ``objective``:
``loop(rng, lower, upper, agents, iterations) -> (best value, best point)``.
"""

from __future__ import annotations

import math

import numpy as np
from fused_common import keep_best, numpy_cbrt
from numba import njit

from swarmpath.optimizers.ops import mantegna_sigma


def make_pso(objective):
    """PSO: w 0.9 -> 0.2, c1 = c2 = 2, |v| <= 0.1 (ub - lb), particles fly free (outside the
    box: not evaluated)."""

    @njit
    def loop(rng, lower, upper, N, T):
        d = lower.size
        X = np.empty((N, d))
        u = rng.random(N * d)
        for i in range(N):
            for j in range(d):
                X[i, j] = lower[j] + (upper[j] - lower[j]) * u[i * d + j]
        V = np.zeros((N, d))
        vmax = 0.1 * (upper - lower)
        scratch = np.empty(d)
        F = np.empty(N)
        for i in range(N):
            F[i] = objective(X[i], scratch)
        best = np.array([np.inf])
        best_x = np.zeros(d)
        keep_best(F, X, N, best, best_x)
        P = X.copy()
        PF = F.copy()
        G = np.empty(d)
        u = np.empty(2 * N * d)
        for t in range(1, T + 1):
            w = 0.9 - (t - 1) * (0.9 - 0.2) / T
            G[:] = best_x
            for k in range(2 * N * d):
                u[k] = rng.random()
            for i in range(N):
                inside = True
                for j in range(d):
                    x = X[i, j]
                    v = V[i, j] * w + (u[i * d + j] * (P[i, j] - x)
                                       + u[N * d + i * d + j] * (G[j] - x)) * 2.0
                    v = min(max(v, -vmax[j]), vmax[j])
                    V[i, j] = v
                    x += v
                    X[i, j] = x
                    if x < lower[j] or x > upper[j]:
                        inside = False
                F[i] = objective(X[i], scratch) if inside else np.inf
            keep_best(F, X, N, best, best_x)
            for i in range(N):
                if F[i] < PF[i]:
                    PF[i] = F[i]
                    P[i] = X[i]
        return best[0], best_x

    return loop


def make_gwo(objective):
    """GWO as its authors coded it: alpha, beta, delta records swept agent by agent."""

    @njit
    def loop(rng, lower, upper, N, T):
        d = lower.size
        X = np.empty((N, d))
        u = rng.random(N * d)
        for i in range(N):
            for j in range(d):
                X[i, j] = min(max(lower[j] + (upper[j] - lower[j]) * u[i * d + j], lower[j]),
                              upper[j])
        scratch = np.empty(d)
        F = np.empty(N)
        score = np.full(3, np.inf)
        L = np.zeros((3, d))
        best = np.array([np.inf])
        best_x = np.zeros(d)
        u = np.empty(6 * N * d)
        size = N * d
        for t in range(T + 1):
            if t:
                a = 2.0 * (1.0 - (t - 1) / T)
                for k in range(6 * size):
                    u[k] = rng.random()
                for i in range(N):
                    for j in range(d):
                        x = X[i, j]
                        m0 = (u[i * d + j] * (2.0 * a) - a) * abs(
                            u[3 * size + i * d + j] * 2.0 * L[0, j] - x)
                        m1 = (u[size + i * d + j] * (2.0 * a) - a) * abs(
                            u[4 * size + i * d + j] * 2.0 * L[1, j] - x)
                        m2 = (u[2 * size + i * d + j] * (2.0 * a) - a) * abs(
                            u[5 * size + i * d + j] * 2.0 * L[2, j] - x)
                        y = (((L[0, j] + L[1, j]) + L[2, j]) - ((m0 + m1) + m2)) / 3.0
                        X[i, j] = min(max(y, lower[j]), upper[j])
            for i in range(N):
                F[i] = objective(X[i], scratch)
            keep_best(F, X, N, best, best_x)
            for i in range(N):
                f = F[i]
                if f < score[0]:
                    score[0] = f
                    L[0] = X[i]
                if score[0] < f < score[1]:
                    score[1] = f
                    L[1] = X[i]
                if score[0] < f and score[1] < f < score[2]:
                    score[2] = f
                    L[2] = X[i]
        return best[0], best_x

    return loop


def make_ssa(objective):
    """SSA as its authors coded it: the first half of the chain leads, the followers average
    with the already moved salp before them."""

    @njit
    def loop(rng, lower, upper, N, T):
        d = lower.size
        leaders = N // 2
        X = np.empty((N, d))
        u = rng.random(N * d)
        for i in range(N):
            for j in range(d):
                X[i, j] = lower[j] + (upper[j] - lower[j]) * u[i * d + j]
        scratch = np.empty(d)
        F = np.empty(N)
        best = np.array([np.inf])
        best_x = np.zeros(d)
        u = np.empty(2 * leaders * d)
        size = leaders * d
        for t in range(T + 1):
            if t:
                c1 = 2.0 * math.exp(-math.pow(4.0 * t / T, 2.0))  # Python's ** is pow
                for k in range(2 * size):
                    u[k] = rng.random()
                for i in range(N):
                    for j in range(d):
                        if i < leaders:
                            y = (u[i * d + j] * (upper[j] - lower[j]) + lower[j]) * c1
                            if u[size + i * d + j] >= 0.5:
                                y = -y
                            X[i, j] = y + best_x[j]
                        else:
                            X[i, j] = (X[i - 1, j] + X[i, j]) * 0.5
                for i in range(N):
                    for j in range(d):
                        X[i, j] = min(max(X[i, j], lower[j]), upper[j])
            for i in range(N):
                F[i] = objective(X[i], scratch)
            keep_best(F, X, N, best, best_x)
        return best[0], best_x

    return loop


def make_fdo(objective):
    """FDO as the author's later code (threshold weights, nested trials, clipped bounds);
    |v|^(2/3) as the reference computes it, numpy's cbrt of v^2."""
    scale = 0.01 * mantegna_sigma(1.5)

    @njit(error_model="numpy")
    def levy(rng, n, L, S):
        """n Levy steps into L (and copysign(L, v) into S when S has room): u / cbrt(v^2)."""
        for k in range(n):
            L[k] = rng.standard_normal()
        for k in range(n):
            v = rng.standard_normal()
            S[k] = v
        for k in range(n):
            S[n + k] = S[k] * S[k]
        numpy_cbrt(S[n:2 * n])
        for k in range(n):
            L[k] = L[k] / S[n + k] * scale
            S[k] = np.copysign(L[k], S[k])

    @njit(error_model="numpy")
    def loop(rng, lower, upper, N, T):
        d = lower.size
        n = N * d
        X = np.empty((N, d))
        u = rng.random(8192)  # swarmpath draws uniforms by blocks of 8192: one block here
        for i in range(N):
            for j in range(d):
                X[i, j] = lower[j] + (upper[j] - lower[j]) * u[i * d + j]
        scratch = np.empty(d)
        F = np.empty(N)
        for i in range(N):
            F[i] = objective(X[i], scratch)
        best = np.array([np.inf])
        best_x = np.zeros(d)
        keep_best(F, X, N, best, best_x)
        pace = np.zeros((N, d))
        moved = np.zeros(N, dtype=np.bool_)
        L = np.empty(n)
        S = np.empty(2 * n)
        row = np.empty(d)
        rs = np.empty(2 * d)
        step = np.empty((N, d))
        C = np.empty((3, N, d))
        FC = np.empty((3, N))
        fw = np.empty(N)
        kind = np.empty(N, dtype=np.int64)  # 0 general, 1 walk (x r), 2 plain ((x* - x) r)
        xb = np.empty(d)
        for _ in range(T):
            b = 0
            for i in range(1, N):
                if F[i] < F[b]:
                    b = i
            fb = F[b]
            for j in range(d):
                xb[j] = X[b, j]
            for i in range(N):
                w = fb / F[i]
                if fb < 0.05 * F[i]:
                    w = 0.2
                if not np.isfinite(w) or fb == 0.0:
                    w = 0.0
                infinite = F[i] == 0.0 and fb != 0.0
                if infinite:
                    w = 1.0
                fw[i] = w
                kind[i] = 1 if (w == 1.0 or infinite) else (2 if w == 0.0 else 0)
            levy(rng, n, L, S)
            levy(rng, d, row, rs)
            for i in range(N):
                for j in range(d):
                    x = X[i, j]
                    gap = xb[j] - x
                    if kind[i] == 1:
                        p = x * L[i * d + j]
                    elif kind[i] == 2:
                        p = gap * L[i * d + j]
                    else:
                        p = np.copysign(gap * fw[i], L[i * d + j])
                    step[i, j] = p
                    C[0, i, j] = min(max(x + p, lower[j]), upper[j])
                    C[1, i, j] = min(max(((gap * fw[i]) + x) + pace[i, j], lower[j]), upper[j])
                    r = row[j] if kind[i] else S[i * d + j]
                    C[2, i, j] = min(max(r * x + x, lower[j]), upper[j])
            took = np.zeros(N, dtype=np.int64)
            for trial in range(3):
                for i in range(N):
                    tried = trial == 0 or (moved[i] and took[i] == 0)
                    FC[trial, i] = objective(C[trial, i], scratch) if tried else np.inf
                keep_best(FC[trial], C[trial], N, best, best_x)
                for i in range(N):
                    if took[i] == 0 and FC[trial, i] < F[i]:
                        took[i] = trial + 1
            for i in range(N):
                if took[i]:
                    k = took[i] - 1
                    F[i] = FC[k, i]
                    for j in range(d):
                        X[i, j] = C[k, i, j]
                        pace[i, j] = step[i, j]
                    moved[i] = True
        return best[0], best_x

    return loop
