"""RFO's compiled kernel: :mod:`swarmpath.optimizers.rfo` run for run, every parameter.

Per iteration, as the reference: one draw of all the iteration's uniforms (alpha, the notice
test, the movers' phi0, a, their angles, the nomads' points, kappa, the born foxes' radii and,
for ``reproduction = "habitat"``, the Box-Muller pairs), then the three phases: the global
search of every fox but the best (greedy), the local search of the n_move foxes with the largest
mu (eqs 3-5), the reproduction replacing the worst. sin, cos and log1p go through numpy's own
loops on the arrays the reference builds, a fractional power through numpy's power loop, the
squared norms as ``einsum`` adds them (:func:`functions.dot`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from numba import njit

from swarmpath.optimizers.compiled.best import record_first_min
from swarmpath.optimizers.compiled.functions import dot
from swarmpath.optimizers.compiled.hpo import matlab_round
from swarmpath.optimizers.compiled.objectives import evaluate, work_for
from swarmpath.optimizers.compiled.registry import Kernel, register_kernel
from swarmpath.optimizers.compiled.streams import RANDOM, open_stream, take
from swarmpath.optimizers.compiled.ufuncs import cos_inplace, log1p_inplace, power, sin_inplace
from swarmpath.registry import ParamValue

TWO_PI = 2.0 * math.pi


def pack(p: Mapping[str, ParamValue]) -> np.ndarray:
    return np.array([
        float(p["replace_fraction"]), float(p["a_max"]), float(p["notice"]),
        float(p["kappa_threshold"]), p["alpha_draw"] == "fox", p["kappa_draw"] == "fox",
        p["reproduction"] == "habitat", bool(p["local_greedy"]),
    ], dtype=np.float64)


@njit(cache=True)
def sign(x):
    """np.sign: 1, -1, 0 for +-0, NaN for NaN."""
    if x > 0.0:
        return 1.0
    if x < 0.0:
        return -1.0
    return 0.0 if x == 0.0 else x


@njit(cache=True)
def run(rng, objective, shifted, shift, lower, upper, agents, iterations, params):
    N, d, T = agents, lower.size, iterations
    frac, a_max, notice, threshold = params[0], params[1], params[2], params[3]
    per_fox, kappa_per_fox = params[4] == 1.0, params[5] == 1.0
    habitat, greedy = params[6] == 1.0, params[7] == 1.0
    k = 0 if frac <= 0.0 else max(0, min(N - 2, max(1, matlab_round(frac * N))))
    m = min(N, matlab_round((1.0 - notice) * N))
    n_u = N - 1 if per_fox else 1
    n_ang = max(d - 1, 1)
    n_dir = 2 * k * d if habitat else 0
    size = n_u + N + m + 1 + m * n_ang + k * d + 2 * k + n_dir
    o_mu = n_u  # where each part of an iteration's draw starts
    o_phi0 = o_mu + N
    o_a = o_phi0 + m
    o_ang = o_a + 1
    o_box = o_ang + m * n_ang
    o_kappa = o_box + k * d
    o_frac = o_kappa + k
    o_bm = o_frac + k
    stream = open_stream(rng, max(size, N * d), False)
    buf = stream[1][RANDOM]
    work = work_for(N, d)
    everyone = np.ones(N, dtype=np.bool_)
    X = np.empty((N, d))
    o = take(stream, RANDOM, N * d)
    for i in range(N):
        for j in range(d):
            X[i, j] = lower[j] + (upper[j] - lower[j]) * buf[o + i * d + j]
    F = np.empty(N)
    best = np.full(1, np.inf)
    best_x = np.zeros(d)
    curve = np.empty(T)
    evaluate(stream, objective, shifted, shift, lower, upper, X, F, everyone, work)
    record_first_min(F, X, N, best, best_x)
    theta = buf[take(stream, RANDOM, 1)]  # the "weather", used only when phi0 == 0
    u = np.empty(size)
    C = np.empty((N, d))  # a phase's candidates
    FC = np.empty(N)
    who = np.empty(N, dtype=np.int64)  # the fox of each candidate
    n = max(m * n_ang, k * d, 1)
    angle = np.empty(n)
    cosine = np.empty(n)
    sine = np.empty(n)
    p0 = np.empty(max(m, 1))
    radius = np.empty(max(m, 1))
    call = np.empty(10, dtype=np.int64)
    centre = np.empty(d)
    order = np.empty(N, dtype=np.int64)
    for t in range(1, T + 1):
        o = take(stream, RANDOM, size)
        for q in range(size):
            u[q] = buf[o + q]

        # ---- global search (eqs 1-2): every fox but the best, toward it; greedy
        b = 0
        for i in range(1, N):
            if F[i] < F[b]:
                b = i
        for q in range(N - 1):
            i = q + 1 if q >= b else q
            who[q] = i
            for j in range(d):
                C[q, j] = X[b, j] - X[i, j]
            alpha = u[q if per_fox else 0] * math.sqrt(math.sqrt(dot(C[q], C[q], d)))
            for j in range(d):
                C[q, j] = min(max(sign(C[q, j]) * alpha + X[i, j], lower[j]), upper[j])
        evaluate(stream, objective, shifted, shift, lower, upper, C[:N - 1], FC[:N - 1],
                 everyone[:N - 1], work)
        record_first_min(FC, C, N - 1, best, best_x)
        for q in range(N - 1):
            if FC[q] < F[who[q]]:
                F[who[q]] = FC[q]
                for j in range(d):
                    X[who[q], j] = C[q, j]

        # ---- local search (eqs 3-5): the m foxes with the largest mu, in index order
        if m:
            q = 0
            for i in range(N):  # fox i moves when fewer than m foxes have a larger mu
                larger = 0
                for c in range(N):
                    v, w = u[o_mu + c], u[o_mu + i]
                    larger += v > w or (v == w and c > i)
                if larger < m:
                    who[q] = i
                    q += 1
            a = u[o_a] * a_max
            for q in range(m):
                p0[q] = u[o_phi0 + q] * TWO_PI
                radius[q] = p0[q]
            sin_inplace(radius[:m], call)
            for q in range(m):  # eq 4: a sin(phi0) / phi0, theta when phi0 = 0
                radius[q] = a * radius[q] / p0[q] if p0[q] != 0.0 else theta
            for v in range(m * n_ang):
                angle[v] = u[o_ang + v] * TWO_PI
                cosine[v] = angle[v]
                sine[v] = angle[v]
            cos_inplace(cosine[:m * n_ang], call)
            sin_inplace(sine[:m * n_ang], call)
            for q in range(m):  # eq 5: the cumulative sines plus the next cosine
                step = a * radius[q]
                s = 0.0
                for j in range(d):
                    if d == 1:
                        delta = cosine[q]
                    else:
                        delta = cosine[q * n_ang + j] if j < d - 1 else 0.0
                        if j:
                            s = s + sine[q * n_ang + j - 1] if j > 1 else sine[q * n_ang]
                            delta = delta + s
                    C[q, j] = min(max(delta * step + X[who[q], j], lower[j]), upper[j])
            evaluate(stream, objective, shifted, shift, lower, upper, C[:m], FC[:m],
                     everyone[:m], work)
            record_first_min(FC, C, m, best, best_x)
            for q in range(m):
                if not greedy or FC[q] < F[who[q]]:
                    F[who[q]] = FC[q]
                    for j in range(d):
                        X[who[q], j] = C[q, j]

        # ---- reproduction (eqs 6-9): the worst k foxes replaced by nomads or offspring
        if k:
            for i in range(N):  # a stable argsort of F
                at = 0
                for c in range(N):
                    at += F[c] < F[i] or (F[c] == F[i] and c < i)
                order[at] = i
            for j in range(d):
                centre[j] = 0.5 * (X[order[0], j] + X[order[1], j])
                C[0, j] = X[order[0], j] - X[order[1], j]
            rad = 0.5 * math.sqrt(math.sqrt(dot(C[0], C[0], d)))
            if habitat:  # Box-Muller normals: sqrt(-2 log1p(-u1)) cos(2 pi u2)
                for v in range(k * d):
                    sine[v] = -u[o_bm + v]
                    cosine[v] = TWO_PI * u[o_bm + k * d + v]
                log1p_inplace(sine[:k * d], call)
                cos_inplace(cosine[:k * d], call)
                for v in range(k * d):
                    angle[v] = math.sqrt(-2.0 * sine[v]) * cosine[v]
            for q in range(k):
                kappa = u[o_kappa + (q if kappa_per_fox else 0)]
                if kappa >= threshold:  # a nomad: uniform, pushed out of the habitat
                    for j in range(d):
                        C[q, j] = lower[j] + (upper[j] - lower[j]) * u[o_box + q * d + j]
                        cosine[j] = C[q, j] - centre[j]
                    norm = math.sqrt(dot(cosine, cosine, d))
                    if norm < rad and norm > 0.0:
                        for j in range(d):
                            C[q, j] = centre[j] + cosine[j] * (rad / norm)
                elif habitat:  # uniform in the habitat ball
                    scale = rad * power(u[o_frac + q], 1.0 / d, call)
                    norm = math.sqrt(dot(angle[q * d:], angle[q * d:], d))
                    factor = scale / norm if norm > 0.0 else 0.0
                    for j in range(d):
                        C[q, j] = centre[j] + angle[q * d + j] * factor
                else:  # "scaled_centre", eq 9 as printed: kappa H
                    for j in range(d):
                        C[q, j] = kappa * centre[j]
                for j in range(d):
                    C[q, j] = min(max(C[q, j], lower[j]), upper[j])
            evaluate(stream, objective, shifted, shift, lower, upper, C[:k], FC[:k],
                     everyone[:k], work)
            record_first_min(FC, C, k, best, best_x)
            for q in range(k):
                worst = order[N - k + q]
                F[worst] = FC[q]
                for j in range(d):
                    X[worst, j] = C[q, j]
        curve[t - 1] = best[0]
    return best[0], best_x, curve, N + T * (N - 1 + m + k)


KERNEL = register_kernel(Kernel("RFO", run, pack))
