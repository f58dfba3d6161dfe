"""The best-ever record the compiled kernels share (``Optimizer.evaluate``'s, run by run)."""

from __future__ import annotations

from numba import njit

from swarmpath.optimizers.compiled.norefcount import NO_REFCOUNT


@njit(cache=True, **NO_REFCOUNT)
def record_first_min(F, X, m, best, best_x):
    """The first minimum of F[:m] (ties: first index), recorded if below ``best[0]``."""
    k = 0
    for i in range(1, m):
        if F[i] < F[k]:
            k = i
    if F[k] < best[0]:
        best[0] = F[k]
        for j in range(best_x.size):
            best_x[j] = X[k, j]


@njit(cache=True, **NO_REFCOUNT)
def record_masked(F, X, mask, best, best_x):
    """:func:`record_first_min` over the rows of ``mask`` (a masked evaluation: the others are
    neither counted nor eligible); returns how many rows were evaluated."""
    k = -1
    n = 0
    for i in range(F.size):
        if mask[i]:
            n += 1
            if F[i] < best[0] and (k < 0 or F[i] < F[k]):
                k = i
    if k >= 0:
        best[0] = F[k]
        for j in range(best_x.size):
            best_x[j] = X[k, j]
    return n


@njit(cache=True, **NO_REFCOUNT)
def within_budget(mask, out, used, budget):
    """out = ``mask`` narrowed to the rows that still fit ``budget`` evaluations after ``used``
    were counted, in row order (budget < 0: no budget): ``Optimizer.max_evaluations``'s rule,
    for a kernel that counts the budget itself (``Kernel.capped``)."""
    left = budget - used
    for i in range(mask.size):
        out[i] = mask[i] and (budget < 0 or left > 0)
        if out[i]:
            left -= 1
