"""FDO (:mod:`swarmpath.optimizers.fdo`) as one compiled loop per run.

The same equations in the same order as the numpy reference, on one run's (agents, dim) arrays,
drawing the run's buffered streams exactly as :class:`~swarmpath.optimizers.streams.RunStreams`
does (FDO draws uniforms and normals, so the refill points matter). Per iteration: the Levy pair
(u, v: 2 x agents x dim normals), the Levy row (2 x dim), with ``bound = "author"`` one more
Levy draw of agents x dim per bounded trial, and F7's noise (agents uniforms per evaluation,
untried points included). Untried trial points are not evaluated here (the reference evaluates
and masks them); they are neither counted nor eligible as best in either.

|v|^(2/3) is cbrt(v^2) through numpy's own float64 cbrt loop
(:func:`~swarmpath.optimizers.compiled.ufuncs.cbrt_inplace`): numpy picks its cbrt at run time
by CPU (on an AVX-512 machine a SIMD version that differs from the C library's in the last bit
for about half of the arguments), and one last bit in a Levy step is enough to turn a greedy
comparison later in the run. Calling that very loop keeps the kernel bitwise equal to the
reference.

An iteration is one pass over the bees computing the three trial points of each (trial 1's
pace, trial 2 from the stored pace, trial 3 from the second Levy step), then per trial the
bound rule, the evaluation of the bees that try it and the greedy test.

FDO's evaluations per run vary (trials 2 and 3 only where tried), so a study's budget can end a
run inside an iteration: the kernel counts it itself (``Kernel.capped``), as the reference's
``max_evaluations`` does: a tried point past the budget is neither computed nor counted, gets
+inf and so fails its greedy test, and the iterations go on drawing their numbers.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numba import njit

from swarmpath.optimizers.compiled.best import record_masked, within_budget
from swarmpath.optimizers.compiled.norefcount import NO_REFCOUNT
from swarmpath.optimizers.compiled.objectives import evaluate, work_for
from swarmpath.optimizers.compiled.registry import Kernel, register_kernel
from swarmpath.optimizers.compiled.streams import NORMAL, open_stream, take
from swarmpath.optimizers.compiled.ufuncs import cbrt_inplace
from swarmpath.optimizers.fdo import _LEVY_SCALE as LEVY_SCALE
from swarmpath.optimizers.fdo import FDO
from swarmpath.registry import ParamValue


def pack(p: Mapping[str, ParamValue]) -> np.ndarray:
    return np.array([
        float(p["weight_factor"]),
        float(FDO.choices["weight_rule"].index(str(p["weight_rule"]))),
        float(FDO.choices["trials"].index(str(p["trials"]))),
        float(FDO.choices["bound"].index(str(p["bound"]))),
        -1.0,  # the evaluation budget (Kernel.capped): the dispatcher fills it
    ])


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def levy(stream, n, L, S, call):
    """L[:n] = n Levy steps from one two-part normal draw (u, v): (u / cbrt(v^2)) * scale, the
    reference's ``_levy``; S[:n] = copysign(L, v) (its ``_levy_pair``) when S has room."""
    start = take(stream, NORMAL, 2 * n)
    z = stream[1][NORMAL]
    w = L[:n]
    for k in range(n):
        v = z[start + n + k]
        w[k] = v * v
    cbrt_inplace(w, call)
    for k in range(n):
        w[k] = z[start + k] / w[k]
        w[k] *= LEVY_SCALE
    if S.size >= n:
        for k in range(n):
            S[k] = np.copysign(w[k], z[start + n + k])


@njit(cache=True, **NO_REFCOUNT)
def bound(stream, C, lower, upper, steps, call):
    """The author's bound rule in place (``_bound``, ``bound = "author"``): a component above
    the box becomes ub L, below lb L (a fresh Levy step L), then everything is clipped."""
    N, d = C.shape
    levy(stream, N * d, steps, steps[:0], call)
    for i in range(N):
        for j in range(d):
            c = C[i, j]
            if c > upper[j]:
                c = upper[j] * steps[i * d + j]
            elif c < lower[j]:
                c = lower[j] * steps[i * d + j]
            C[i, j] = min(max(c, lower[j]), upper[j])


@njit(cache=True, error_model="numpy")
def run(rng, objective, shifted, shift, lower, upper, agents, iterations, params):
    N, d, T = agents, lower.size, iterations
    n = N * d
    wf = params[0]
    threshold, nested, author = params[1] == 0.0, params[2] == 0.0, params[3] == 1.0
    budget = params[4]
    stream = open_stream(rng, max(2 * n, N), True)  # uniforms and normals: buffered
    call = np.empty(5, dtype=np.int64)
    work = work_for(N, d)
    best = np.full(1, np.inf)
    best_x = np.zeros(d)
    curve = np.empty(T)
    X = np.empty((N, d))
    start = take(stream, 0, n)
    u = stream[1][0]
    for i in range(N):
        for j in range(d):
            X[i, j] = lower[j] + (upper[j] - lower[j]) * u[start + i * d + j]
    F = np.empty(N)
    tried = np.ones((3, N), dtype=np.bool_)
    counted = np.empty(N, dtype=np.bool_)  # the tried rows that fit the budget
    within_budget(tried[0], counted, 0, budget)
    evaluate(stream, objective, shifted, shift, lower, upper, X, F, counted, work)
    evals = record_masked(F, X, counted, best, best_x)
    pace = np.zeros((N, d))
    has_pace = np.zeros(N, dtype=np.bool_)
    L = np.empty(n)
    S3 = np.empty(n)
    row = np.empty(d)
    steps = np.empty(n)
    pace1 = np.empty((N, d))
    C = np.empty((3, N, d))
    FC = np.empty((3, N))
    kind = np.empty(N, dtype=np.int64)  # 0: general, 1: walk (pace x r), 2: plain ((x* - x) r)
    fw = np.empty(N)
    took = np.empty(N, dtype=np.int64)  # the accepted trial, 0: none
    xb = np.empty(d)
    for t in range(T):
        b = 0
        for i in range(1, N):
            if F[i] < F[b]:
                b = i
        fb = F[b]
        for j in range(d):
            xb[j] = X[b, j]
        for i in range(N):  # eq 2 with the reference's edge cases
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
            kind[i] = 1 if w == 1.0 or infinite else (2 if w == 0.0 else 0)
        levy(stream, n, L, S3, call)
        levy(stream, d, row, row[:0], call)
        for i in range(N):
            for j in range(d):
                x = X[i, j]
                dist = xb[j] - x
                f = dist * fw[i]
                if kind[i] == 1:
                    p = x * L[i * d + j]
                elif kind[i] == 2:
                    p = dist * L[i * d + j]
                else:
                    p = np.copysign(f, L[i * d + j])
                pace1[i, j] = p
                s = S3[i * d + j] if kind[i] == 0 else row[j]
                c1 = x + p
                c2 = (f + x) + pace[i, j]
                c3 = s * x + x
                if not author:
                    c1 = min(max(c1, lower[j]), upper[j])
                    c2 = min(max(c2, lower[j]), upper[j])
                    c3 = min(max(c3, lower[j]), upper[j])
                C[0, i, j] = c1
                C[1, i, j] = c2
                C[2, i, j] = c3
        for i in range(N):
            took[i] = 0
        # trials in the reference's order: 1 (everyone), then "nested": 2 for the bees that moved
        # before, 3 for those of them that failed 2; "split": 2 or 3 in one evaluation
        for trial in range(3 if nested else 2):
            if trial:
                for i in range(N):
                    if nested:
                        tried[trial, i] = took[i] == 0 and (has_pace[i] if trial == 1
                                                            else tried[1, i])
                    else:
                        tried[1, i] = took[i] == 0
                        if tried[1, i] and not has_pace[i]:  # trial 3 instead of 2
                            for j in range(d):
                                C[1, i, j] = C[2, i, j]
            if author:
                bound(stream, C[trial], lower, upper, steps, call)
            within_budget(tried[trial], counted, evals, budget)
            evaluate(stream, objective, shifted, shift, lower, upper, C[trial], FC[trial],
                     counted, work)
            evals += record_masked(FC[trial], C[trial], counted, best, best_x)
            for i in range(N):
                if took[i] == 0 and FC[trial, i] < F[i]:
                    took[i] = trial + 1 if nested or has_pace[i] or not trial else 3
        for i in range(N):  # greedy; a bee that moves keeps this iteration's trial-1 pace
            if took[i]:
                k = took[i] - 1 if nested or took[i] < 3 else 1
                F[i] = FC[k, i]
                for j in range(d):
                    X[i, j] = C[k, i, j]
                    pace[i, j] = pace1[i, j]
                has_pace[i] = True
        curve[t] = best[0]
    return best[0], best_x, curve, evals


KERNEL = register_kernel(Kernel("FDO", run, pack, capped=True))
