"""Independent fused loops of BA, MFB and HPSO-MFB (default parameters), for
``scripts/bench/kernels.py``. See ``fused_common.py``."""

from __future__ import annotations

import math

import numpy as np
from fused_common import keep_best, numpy_exp
from numba import njit


@njit
def numpy_mean(a):
    """The mean as numpy adds a contiguous row: from 0, eight running sums up to 128 numbers."""
    n = a.size
    if n < 8:
        s = 0.0
        for i in range(n):
            s += a[i]
        return (0.0 + s) / n
    r = a[:8].copy()
    i = 8
    while i < n - n % 8:
        for c in range(8):
            r[c] += a[i + c]
        i += 8
    s = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
    while i < n:
        s += a[i]
        i += 1
    return (0.0 + s) / n


def make_ba(objective):
    """The bat algorithm as its author's demo (A = r = 0.5, f in [0, 2], toward the best, the
    bat's own acceptance), with the paper's local walk U(-1, 1) <A> around the best."""

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
        V = np.zeros((N, d))
        A = np.full(N, 0.5)
        S = np.empty((N, d))
        FS = np.empty(N)
        g = np.empty(d)
        u = np.empty(3 * N)
        walk = np.empty(N * d)
        for _ in range(T):
            g[:] = best_x
            for q in range(3 * N):
                u[q] = rng.random()
            for q in range(N * d):
                walk[q] = rng.random()
            mean = numpy_mean(A)
            for i in range(N):
                f = 0.0 + (2.0 - 0.0) * u[i]
                for j in range(d):
                    V[i, j] += (g[j] - X[i, j]) * f
                    s = X[i, j] + V[i, j]
                    if u[N + i] > 0.5:
                        s = (walk[i * d + j] * 2.0 - 1.0) * mean + g[j]
                    S[i, j] = min(max(s, lower[j]), upper[j])
                FS[i] = objective(S[i], scratch)
            keep_best(FS, S, N, best, best_x)
            for i in range(N):
                if FS[i] <= F[i] and u[2 * N + i] < A[i]:
                    F[i] = FS[i]
                    X[i] = S[i]
        return best[0], best_x

    return loop


def make_bats(objective, hybrid):
    """MFB (eqs 9-15 and Table 1: f in [0, 10], rho 0.01, sigma 0.3, alpha = gamma = 0.9, the
    acceptance against the best, A and r updated every iteration) or, with ``hybrid``, HPSO-MFB:
    5 particles of (alpha, gamma), bat j in sub-swarm j mod 5, epochs of T/5 iterations after
    which PSO moves the particles and the bats restart warm, every bat led by the best of all."""

    @njit
    def loop(rng, lower, upper, N, T):
        d = lower.size
        G = min(5, N) if hybrid else 1
        K = math.ceil(T / 5) if hybrid else T
        X = np.empty((N, d))
        u = rng.random(N * d)
        for i in range(N):
            for j in range(d):
                X[i, j] = lower[j] + (upper[j] - lower[j]) * u[i * d + j]
        u = rng.random(2 * N)
        A0 = np.empty(N)
        r0 = np.empty(N)
        for i in range(N):
            A0[i] = 1.0 + (2.0 - 1.0) * u[2 * i]
            r0[i] = 0.0 + (1.0 - 0.0) * u[2 * i + 1]
        scratch = np.empty(d)
        F = np.empty(N)
        best = np.array([np.inf])
        best_x = np.zeros(d)
        zb = np.full(G, np.inf)  # each sub-swarm's best, and the best of each epoch
        Z = np.zeros((G, d))
        epoch = np.full(G, np.inf)
        for i in range(N):
            F[i] = objective(X[i], scratch)
        keep_best(F, X, N, best, best_x)
        for g in range(G):
            at = g
            for i in range(g + G, N, G):
                if F[i] < F[at]:
                    at = i
            if F[at] < zb[g]:
                zb[g] = F[at]
                Z[g] = X[at]
            epoch[g] = min(epoch[g], F[at])
        P = np.empty((G, 2))  # (alpha, gamma) per particle
        if hybrid:
            u = rng.random(2 * G)
            for g in range(G):
                P[g, 0] = 0.8 + (0.999 - 0.8) * u[2 * g]
                P[g, 1] = 0.01 + (1.0 - 0.01) * u[2 * g + 1]
        else:
            P[0, 0] = 0.9
            P[0, 1] = 0.9
        PV = np.zeros((G, 2))
        PB = P.copy()
        PF = np.full(G, np.inf)
        A = A0.copy()
        r = np.zeros(N)
        V = np.zeros((N, d))
        S = np.empty((N, d))
        FS = np.empty(N)
        u = np.empty(N * (d + 3))
        f = np.empty(N)
        level = np.empty(N)
        mean = np.empty(G)
        zb0 = np.empty(G)
        for t in range(1, T + 1):
            start = (t - 1) // K * K
            clock = t - start
            length = min(start + K, T) - start
            for q in range(N * (d + 3)):
                u[q] = rng.random()
            for i in range(N):
                f[i] = -0.01 * u[N * (d + 2) + i]
            numpy_exp(f)
            for i in range(N):
                f[i] = 0.0 + (10.0 - 0.0) * ((clock / length) * f[i])
            k = 0
            for g in range(1, G):
                if zb[g] < zb[k]:
                    k = g
            zb0[:] = zb
            if G == 1:
                mean[0] = numpy_mean(A)
            else:
                for g in range(G):
                    s = 0.0
                    c = 0
                    for i in range(g, N, G):
                        s += A[i]
                        c += 1
                    mean[g] = s / c
            for i in range(N):
                scale = (2.0 * 0.3) * mean[i % G]
                for j in range(d):
                    V[i, j] += (Z[k, j] - X[i, j]) * f[i]
                    s = X[i, j] + V[i, j]
                    if u[N * d + i] > r[i]:
                        w = scale * (upper[j] - lower[j])
                        s = u[i * d + j] * w + (Z[k, j] - 0.5 * w)
                    S[i, j] = min(max(s, lower[j]), upper[j])
                FS[i] = objective(S[i], scratch)
            keep_best(FS, S, N, best, best_x)
            for g in range(G):
                at = g
                for i in range(g + G, N, G):
                    if FS[i] < FS[at]:
                        at = i
                if FS[at] < zb[g]:
                    zb[g] = FS[at]
                    Z[g] = S[at]
                epoch[g] = min(epoch[g], FS[at])
            for i in range(N):
                if u[N * (d + 1) + i] < A[i] and FS[i] < zb0[k]:
                    F[i] = FS[i]
                    X[i] = S[i]
                level[i] = -P[i % G, 1] * clock
            numpy_exp(level)
            for i in range(N):
                A[i] *= P[i % G, 0]
                r[i] = r0[i] * (1.0 - level[i])
            if hybrid and t % K == 0 and t < T:  # eqs 16-17 on (alpha, gamma), then warm
                for g in range(G):
                    if epoch[g] < PF[g]:
                        PF[g] = epoch[g]
                        PB[g] = P[g]
                k = 0
                for g in range(1, G):
                    if PF[g] < PF[k]:
                        k = g
                w4 = rng.random(4 * G)
                for g in range(G):
                    for c in range(2):
                        v = (1.0 * PV[g, c] + 2.0 * w4[4 * g + c] * (PB[g, c] - P[g, c])
                             + 2.0 * w4[4 * g + 2 + c] * (PB[k, c] - P[g, c]))
                        lo = 0.8 if c == 0 else 0.01
                        hi = 0.999 if c == 0 else 1.0
                        top = 0.2 * (hi - lo)
                        PV[g, c] = min(max(v, -top), top)
                        P[g, c] = min(max(P[g, c] + PV[g, c], lo), hi)
                    epoch[g] = np.inf
                A[:] = A0
                r[:] = 0.0
                V[:] = 0.0
        return best[0], best_x

    return loop
