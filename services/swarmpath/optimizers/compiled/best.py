"""The best-ever record the compiled kernels share (``Optimizer.evaluate``'s, run by run)."""

from __future__ import annotations

from numba import njit


@njit(cache=True)
def record_first_min(F, X, m, best, best_x):
    """The first minimum of F[:m] (ties: first index), recorded if below ``best[0]``."""
    k = 0
    for i in range(1, m):
        if F[i] < F[k]:
            k = i
    if F[k] < best[0]:
        best[0] = F[k]
        best_x[:] = X[k]
