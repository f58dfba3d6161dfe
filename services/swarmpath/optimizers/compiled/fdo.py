"""FDO (:mod:`swarmpath.optimizers.fdo`) as one compiled loop per run.

The same equations in the same order as the numpy reference, on one run's (agents, dim) arrays,
drawing the run's buffered streams exactly as :class:`~swarmpath.optimizers.streams.RunStreams`
does (FDO draws uniforms and normals, so the refill points matter). Per iteration: the Levy pair
(u, v: 2 x agents x dim normals), the Levy row (2 x dim), with ``bound = "author"`` one more
Levy draw of agents x dim per bounded trial, and F7's noise (agents uniforms per evaluation,
untried points included). Untried trial points are not evaluated here (the reference evaluates
and masks them); they are neither counted nor eligible as best in either.

|v|^(2/3) is cbrt(v^2) through numpy's own float64 cbrt loop
(:mod:`~swarmpath.optimizers.compiled.ufuncs`): numpy picks its cbrt at run time by CPU (on an
AVX-512 machine a SIMD version that differs from the C library's in the last bit for about half
of the arguments), and one last bit in a Levy step is enough to turn a greedy comparison later
in the run. Calling that very loop keeps the kernel bitwise equal to the reference.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numba import njit

from swarmpath.optimizers.compiled.functions import evaluate
from swarmpath.optimizers.compiled.registry import Kernel, register_kernel
from swarmpath.optimizers.compiled.streams import NORMAL, RANDOM, open_stream, take
from swarmpath.optimizers.compiled.ufuncs import CBRT, unary, with_objective
from swarmpath.optimizers.fdo import _LEVY_SCALE as LEVY_SCALE
from swarmpath.optimizers.fdo import FDO
from swarmpath.registry import ParamValue


@njit(cache=True, error_model="numpy")
def levy(stream, m, d, cbrt, data, call, L, S):
    """L[:m] = Levy steps of m x d from one two-part normal draw (u, v): (u / cbrt(v^2)) *
    scale, the reference's ``_levy``; with S of size > 0 also S = copysign(L, v) (its
    ``_levy_pair``). L and S are contiguous."""
    n = m * d
    start = take(stream, NORMAL, 2 * n)
    z = stream[1][NORMAL]
    flat = L.reshape(n)
    for k in range(n):
        v = z[start + n + k]
        flat[k] = v * v
    unary(cbrt, data, flat, call)
    for k in range(n):
        flat[k] = z[start + k] / flat[k]
        flat[k] *= LEVY_SCALE
    if S.size:
        sflat = S.reshape(n)
        for k in range(n):
            sflat[k] = np.copysign(flat[k], z[start + n + k])


@njit(cache=True)
def bound(stream, C, lower, upper, author, cbrt, data, call, scratch, none):
    """The reference's ``_bound`` in place: the author's rule (a fresh Levy draw) if asked,
    then clip."""
    N, d = C.shape
    if author:
        levy(stream, N, d, cbrt, data, call, scratch, none)
    for i in range(N):
        for j in range(d):
            c = C[i, j]
            if author:
                if c > upper[j]:
                    c = upper[j] * scratch[i, j]
                elif c < lower[j]:
                    c = lower[j] * scratch[i, j]
            if c < lower[j]:
                c = lower[j]
            if c > upper[j]:
                c = upper[j]
            C[i, j] = c


@njit(cache=True)
def record(X, F, mask, best, best_x):
    """The best point ever evaluated (strict <, first index); returns the points counted."""
    k = -1
    n = 0
    for i in range(F.size):
        if mask[i]:
            n += 1
            if F[i] < best[0]:
                best[0] = F[i]
                k = i
    if k >= 0:
        best_x[:] = X[k]
    return n


@njit(cache=True, error_model="numpy")
def weights(F, b, wf, threshold, fw, walk, plain):
    """fw (eq 2 with the reference's edge cases) and its two special branches, per bee."""
    fb = F[b]
    for i in range(F.size):
        w = fb / F[i]
        if wf != 0.0:
            w -= wf
        if threshold and fb < 0.05 * F[i]:
            w = 0.2
        if not np.isfinite(w) or fb == 0.0:
            w = 0.0
        infinite = F[i] == 0.0 and fb != 0.0
        if infinite:
            w = 1.0
        fw[i] = w
        walk[i] = w == 1.0 or infinite  # pace = x r
        plain[i] = w == 0.0 and not walk[i]  # pace = (x* - x) r


def pack(p: Mapping[str, ParamValue]) -> np.ndarray:
    return np.array([
        float(p["weight_factor"]),
        float(FDO.choices["weight_rule"].index(str(p["weight_rule"]))),
        float(FDO.choices["trials"].index(str(p["trials"]))),
        float(FDO.choices["bound"].index(str(p["bound"]))),
    ])


def run(rng, fid, shifted, shift, lower, upper, agents, iterations, params):
    """One FDO run (the package's kernel signature). A Python shim: numpy's cbrt loop is an
    argument of the compiled loop (a global function pointer would keep numba from caching
    it)."""
    return _run(rng, fid, shifted, shift, lower, upper, agents, iterations, params, *CBRT)


def loop(evaluate, rng, fid, shifted, shift, lower, upper, agents, iterations, params):
    """``run`` with the objective ``evaluate`` (``functions.evaluate``'s signature), for
    ``scripts/bench/kernels.py``'s fused loop (compiled per objective, not cached)."""
    return with_objective(_run, evaluate)(rng, fid, shifted, shift, lower, upper, agents,
                                          iterations, params, *CBRT)


@njit(cache=True)
def _run(rng, fid, shifted, shift, lower, upper, agents, iterations, params, cbrt, data):
    N, d, T = agents, lower.size, iterations
    wf = params[0]
    threshold = params[1] == 0.0
    nested = params[2] == 0.0
    author = params[3] == 1.0
    stream = open_stream(rng, max(2 * N * d, N))
    call = np.empty(5, dtype=np.int64)
    w4 = np.empty((4, d))
    best = np.full(1, np.inf)
    best_x = np.zeros(d)
    curve = np.empty(T)
    none = np.empty((0, 0))
    everyone = np.ones(N, dtype=np.bool_)
    X = np.empty((N, d))
    start = take(stream, RANDOM, N * d)
    u = stream[1][RANDOM]
    for i in range(N):
        for j in range(d):
            X[i, j] = lower[j] + (upper[j] - lower[j]) * u[start + i * d + j]
    F = np.empty(N)
    evaluate(stream, fid, shifted, shift, lower, upper, X, F, everyone, w4)
    evals = record(X, F, everyone, best, best_x)
    pace = np.zeros((N, d))
    has_pace = np.zeros(N, dtype=np.bool_)
    L = np.empty((N, d))
    S3 = np.empty((N, d))
    row = np.empty((1, d))
    scratch = np.empty((N, d))
    pace1 = np.empty((N, d))
    cand1 = np.empty((N, d))
    cand2 = np.empty((N, d))
    cand3 = np.empty((N, d))
    F1 = np.empty(N)
    F2 = np.empty(N)
    F3 = np.empty(N)
    fw = np.empty(N)
    walk = np.empty(N, dtype=np.bool_)
    plain = np.empty(N, dtype=np.bool_)
    tried2 = np.empty(N, dtype=np.bool_)
    tried3 = np.empty(N, dtype=np.bool_)
    acc = np.zeros(N, dtype=np.int64)  # 0: stays, else the accepted trial
    xb = np.empty(d)
    for t in range(T):
        b = 0
        for i in range(1, N):
            if F[i] < F[b]:
                b = i
        xb[:] = X[b]
        weights(F, b, wf, threshold, fw, walk, plain)
        levy(stream, N, d, cbrt, data, call, L, S3)
        levy(stream, 1, d, cbrt, data, call, row, none)
        # trial 1: x + pace; (x* - x) fw is kept in cand2 for trial 2
        for i in range(N):
            for j in range(d):
                x = X[i, j]
                dist = xb[j] - x
                f = dist * fw[i]
                cand2[i, j] = f
                if walk[i]:
                    p = x * L[i, j]
                elif plain[i]:
                    p = dist * L[i, j]
                else:
                    p = np.copysign(f, L[i, j])
                pace1[i, j] = p
                cand1[i, j] = x + p
        bound(stream, cand1, lower, upper, author, cbrt, data, call, scratch, none)
        evaluate(stream, fid, shifted, shift, lower, upper, cand1, F1, everyone, w4)
        evals += record(cand1, F1, everyone, best, best_x)
        # trial 2: x + (x* - x) fw + the stored pace; trial 3: x + x r
        for i in range(N):
            acc[i] = 1 if F1[i] < F[i] else 0
            tried2[i] = acc[i] == 0 and has_pace[i]
            special = walk[i] or plain[i]
            for j in range(d):
                x = X[i, j]
                cand2[i, j] = (cand2[i, j] + x) + pace[i, j]
                s = row[0, j] if special else S3[i, j]
                cand3[i, j] = s * x + x
        if nested:  # trial 3 only after a failed trial 2
            bound(stream, cand2, lower, upper, author, cbrt, data, call, scratch, none)
            evaluate(stream, fid, shifted, shift, lower, upper, cand2, F2, tried2, w4)
            evals += record(cand2, F2, tried2, best, best_x)
            for i in range(N):
                if F2[i] < F[i]:
                    acc[i] = 2
                tried3[i] = tried2[i] and acc[i] != 2
            bound(stream, cand3, lower, upper, author, cbrt, data, call, scratch, none)
            evaluate(stream, fid, shifted, shift, lower, upper, cand3, F3, tried3, w4)
            evals += record(cand3, F3, tried3, best, best_x)
            for i in range(N):
                if F3[i] < F[i]:
                    acc[i] = 3
        else:  # "split": trial 2 for bees that moved before, trial 3 for the others
            for i in range(N):
                tried3[i] = acc[i] == 0 and not has_pace[i]
                if tried3[i]:
                    cand2[i] = cand3[i]
                    tried2[i] = True  # evaluated together, told apart below
            bound(stream, cand2, lower, upper, author, cbrt, data, call, scratch, none)
            evaluate(stream, fid, shifted, shift, lower, upper, cand2, F2, tried2, w4)
            evals += record(cand2, F2, tried2, best, best_x)
            for i in range(N):
                if F2[i] < F[i]:
                    acc[i] = 3 if tried3[i] else 2
        # greedy update; a bee that moves keeps this iteration's trial-1 pace
        for i in range(N):
            a = acc[i]
            if a == 0:
                continue
            if a == 1:
                X[i] = cand1[i]
                F[i] = F1[i]
            elif a == 2 or not nested:
                X[i] = cand2[i]
                F[i] = F2[i]
            else:
                X[i] = cand3[i]
                F[i] = F3[i]
            pace[i] = pace1[i]
            has_pace[i] = True
        curve[t] = best[0]
    return best[0], best_x, curve, evals


KERNEL = register_kernel(Kernel("FDO", run, pack))
