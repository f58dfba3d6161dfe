"""Independent fused loops of HPO, IHPO and RFO (default parameters), for
``scripts/bench/kernels.py``. See ``fused_common.py``."""

from __future__ import annotations

import math

import numpy as np
from fused_common import (
    keep_best,
    numpy_cos,
    numpy_log1p,
    numpy_power,
    numpy_sin,
    square_sum,
)
from numba import njit

TWO_PI = 2.0 * math.pi


@njit
def half_away(x):
    """MATLAB's round."""
    r = math.floor(abs(x))
    if abs(x) - r >= 0.5:
        r += 1
    return int(math.copysign(r, x))


def make_hpo(objective, improved):
    """HPO as its authors coded it (the agents moved one by one, a hunter's mean and ranking
    from the population as it is, the prey toward the best so far); ``improved``: IHPO's
    alpha = (2 rand - 1) sin(C - t/T) per agent on the printed eqs 14a-14b."""

    @njit
    def loop(rng, lower, upper, N, T):
        d = lower.size
        X = np.empty((N, d))
        u = rng.random(N * d)
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
        CZ = np.empty((N, d))
        S = np.empty(N * d)
        mu = np.empty(d)
        gap = np.empty(d)
        dist = np.empty(N)
        rows = 3 if improved else 2
        U = np.empty(2 * N * d)
        V = np.empty(rows * N)
        for t in range(1, T + 1):
            C = 1.0 - t * (0.98 / T)
            kbest = max(1, half_away(N * C))
            for q in range(2 * N * d):
                U[q] = rng.random()
            for q in range(rows * N):
                V[q] = rng.random()
            for i in range(N):
                for j in range(d):
                    q = U[i * d + j]
                    CZ[i, j] = (q - V[i] * C) + V[i] * C if q < C else V[i] * C
                    S[i * d + j] = (U[N * d + i * d + j] - 0.5) * TWO_PI
            numpy_cos(S)
            cp = math.sin(C - t / T)
            for i in range(N):
                a = (2.0 * V[2 * N + i] - 1.0) * cp if improved else 1.0
                for j in range(d):
                    S[i * d + j] = S[i * d + j] * CZ[i, j]
                    if improved:
                        S[i * d + j] = S[i * d + j] * a
            for i in range(N):
                a = (2.0 * V[2 * N + i] - 1.0) * cp if improved else 1.0
                if V[N + i] < 0.1:  # a hunter
                    for j in range(d):
                        mu[j] = 0.0
                        for c in range(N):
                            mu[j] = mu[j] + X[c, j]
                        mu[j] = mu[j] / N
                    for c in range(N):
                        for j in range(d):
                            gap[j] = X[c, j] - mu[j]
                        dist[c] = square_sum(gap, d)
                    chosen = 0
                    for c in range(N):
                        rank = 0
                        for e in range(N):
                            rank += dist[e] < dist[c] or (dist[e] == dist[c] and e < c)
                        if rank == kbest - 1:
                            chosen = c
                    for j in range(d):
                        if improved:
                            target = a * (C * X[chosen, j]) + (1.0 - C) * mu[j]
                        else:
                            target = C * X[chosen, j] + (1.0 - C) * mu[j]
                        gap[j] = (CZ[i, j] / C) * target
                    for j in range(d):
                        X[i, j] = min(max(gap[j], lower[j]), upper[j])
                else:
                    for j in range(d):
                        y = (best_x[j] - X[i, j]) * S[i * d + j] + best_x[j]
                        X[i, j] = min(max(y, lower[j]), upper[j])
                f = objective(X[i], scratch)
                if f < best[0]:
                    best[0] = f
                    for j in range(d):
                        best_x[j] = X[i, j]
        return best[0], best_x

    return loop


def make_rfo(objective):
    """RFO as documented in rfo.py: the global search toward the best fox (greedy), n_move
    foxes with the largest mu searching locally, the worst 5% replaced by nomads or by foxes
    born in the habitat ball of the two best."""

    @njit
    def loop(rng, lower, upper, N, T):
        d = lower.size
        k = max(0, min(N - 2, max(1, half_away(0.05 * N))))
        m = min(N, half_away(0.25 * N))
        X = np.empty((N, d))
        u = rng.random(N * d)
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
        theta = rng.random()
        na = d - 1
        size = 1 + N + m + 1 + m * na + k * d + 2 * k + 2 * k * d
        u = np.empty(size)
        Y = np.empty((N, d))
        FY = np.empty(N)
        movers = np.empty(m, dtype=np.int64)
        p0 = np.empty(m)
        sp = np.empty(m)
        cs = np.empty(m * na)
        sn = np.empty(m * na)
        bm = np.empty(2 * k * d)
        rank = np.empty(N, dtype=np.int64)
        mid = np.empty(d)
        for _ in range(T):
            for q in range(size):
                u[q] = rng.random()
            b = 0
            for i in range(1, N):
                if F[i] < F[b]:
                    b = i
            for q in range(N - 1):  # global: toward the best by u sqrt(distance)
                i = q if q < b else q + 1
                for j in range(d):
                    scratch[j] = X[b, j] - X[i, j]
                step = u[0] * math.sqrt(math.sqrt(square_sum(scratch, d)))
                for j in range(d):
                    g = scratch[j]
                    s = 1.0 if g > 0.0 else (-1.0 if g < 0.0 else 0.0)
                    Y[q, j] = min(max(s * step + X[i, j], lower[j]), upper[j])
                FY[q] = objective(Y[q], scratch)
            keep_best(FY, Y, N - 1, best, best_x)
            for q in range(N - 1):
                i = q if q < b else q + 1
                if FY[q] < F[i]:
                    F[i] = FY[q]
                    X[i] = Y[q]
            c = 0  # local: the foxes of the m largest mu
            for i in range(N):
                above = 0
                for e in range(N):
                    above += u[1 + e] > u[1 + i]
                if above < m:
                    movers[c] = i
                    c += 1
            a = u[1 + N + m] * 0.2
            for q in range(m):
                p0[q] = u[1 + N + q] * TWO_PI
                sp[q] = p0[q]
            numpy_sin(sp)
            for q in range(m * na):
                cs[q] = u[2 + N + m + q] * TWO_PI
                sn[q] = cs[q]
            numpy_cos(cs)
            numpy_sin(sn)
            for q in range(m):
                r = a * sp[q] / p0[q] if p0[q] != 0.0 else theta
                total = 0.0
                for j in range(d):
                    if j == 0:
                        delta = cs[q * na]
                    else:
                        total = total + sn[q * na + j - 1] if j > 1 else sn[q * na]
                        delta = (cs[q * na + j] if j < na else 0.0) + total
                    Y[q, j] = min(max(delta * (a * r) + X[movers[q], j], lower[j]), upper[j])
                FY[q] = objective(Y[q], scratch)
            keep_best(FY, Y, m, best, best_x)
            for q in range(m):
                F[movers[q]] = FY[q]
                X[movers[q]] = Y[q]
            for i in range(N):  # reproduction: the worst k replaced
                rank[i] = 0
                for e in range(N):
                    rank[i] += F[e] < F[i] or (F[e] == F[i] and e < i)
            first = second = 0
            for i in range(N):
                if rank[i] == 0:
                    first = i
                if rank[i] == 1:
                    second = i
            for j in range(d):
                mid[j] = 0.5 * (X[first, j] + X[second, j])
                scratch[j] = X[first, j] - X[second, j]
            rad = 0.5 * math.sqrt(math.sqrt(square_sum(scratch, d)))
            o = 1 + N + m + 1 + m * na
            for q in range(k * d):
                bm[q] = -u[o + k * d + 2 * k + q]
                bm[k * d + q] = TWO_PI * u[o + 2 * k * d + 2 * k + q]
            numpy_log1p(bm[:k * d])
            numpy_cos(bm[k * d:])
            nomad = u[o + k * d] >= 0.45
            for q in range(k):
                if nomad:
                    for j in range(d):
                        Y[q, j] = lower[j] + (upper[j] - lower[j]) * u[o + q * d + j]
                        scratch[j] = Y[q, j] - mid[j]
                    norm = math.sqrt(square_sum(scratch, d))
                    if 0.0 < norm < rad:
                        for j in range(d):
                            Y[q, j] = mid[j] + scratch[j] * (rad / norm)
                else:
                    for j in range(d):
                        scratch[j] = math.sqrt(-2.0 * bm[q * d + j]) * bm[k * d + q * d + j]
                    norm = math.sqrt(square_sum(scratch, d))
                    scale = rad * numpy_power(u[o + k * d + k + q], 1.0 / d)
                    factor = scale / norm if norm > 0.0 else 0.0
                    for j in range(d):
                        Y[q, j] = mid[j] + scratch[j] * factor
                for j in range(d):
                    Y[q, j] = min(max(Y[q, j], lower[j]), upper[j])
                FY[q] = objective(Y[q], scratch)
            keep_best(FY, Y, k, best, best_x)
            for i in range(N):
                if rank[i] >= N - k:
                    q = rank[i] - (N - k)
                    F[i] = FY[q]
                    X[i] = Y[q]
        return best[0], best_x

    return loop
