"""SSA (:mod:`swarmpath.optimizers.ssa`) as one compiled loop per run.

The same equations in the same order as the numpy reference, on one run's (agents, dim) arrays:

* every number comes from the run's stream in the reference's order: the initial population,
  then per iteration c2 and c3 as one two-part draw of ``leaders x dim`` uniforms each (F7's
  noise, ``agents`` uniforms per evaluation, in between);
* c1 (eq 3.2) is :meth:`SSA.c1` itself, tabulated once per number of iterations: Python's
  ``x ** 2`` is the C library's pow, which differs from x * x (what compiled code makes of it)
  in the last bit for about one t / T in a thousand;
* the followers are the literal sweep y_i = (y_{i-1} + x_i) / 2 of ``SSA.m``. The reference
  applies it as a matrix of powers of two (``np.matmul``); a power of two scales exactly, so that
  product equals the sweep whenever the BLAS accumulates each row in index order, which OpenBLAS
  does at the Table 2 setting (30 agents, 30 dims) on this machine. Where it does not (measured:
  30 agents at 2 and 100 dims), the two differ in the last bits of some followers, and a run
  agrees with the reference to rounding, not bitwise.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import lru_cache

import numpy as np
from numba import njit, objmode

from swarmpath.optimizers.compiled.functions import evaluate
from swarmpath.optimizers.compiled.registry import Kernel, register_kernel
from swarmpath.optimizers.compiled.streams import RANDOM, open_stream, take
from swarmpath.optimizers.ssa import SSA
from swarmpath.registry import ParamValue

Array = np.ndarray


@lru_cache(maxsize=32)
def c1_table(iterations: int) -> Array:
    """c1(t, T) for t = 1..T, from the reference's own function."""
    table = np.array([SSA.c1(t, iterations) for t in range(1, iterations + 1)])
    table.flags.writeable = False
    return table


@njit(cache=True)
def _c1(iterations):  # type: ignore[no-untyped-def]
    with objmode(table="float64[::1]"):
        table = c1_table(iterations).copy()
    return table


@njit(cache=True)
def move(stream, X, lower, upper, food, c1, n_leaders):  # type: ignore[no-untyped-def]
    """One SSA move of the population X (agents, dim) in place, clipped (not evaluated).

    ``food`` is the best point ever evaluated, ``c1`` eq 3.2 at this iteration.
    """
    N, d = X.shape
    size = n_leaders * d
    start = take(stream, RANDOM, 2 * size)  # c2, then c3
    u = stream[1][RANDOM]
    for i in range(n_leaders):
        for j in range(d):
            lead = u[start + i * d + j] * (upper[j] - lower[j])
            lead += lower[j]
            lead *= c1
            if u[start + size + i * d + j] >= 0.5:
                lead = -lead
            X[i, j] = lead + food[j]
    for j in range(d):
        y = X[n_leaders - 1, j]  # the last leader, moved and not clipped
        for i in range(n_leaders, N):
            y = (y + X[i, j]) * 0.5
            X[i, j] = y
    for i in range(N):
        for j in range(d):
            x = X[i, j]
            if x < lower[j]:
                x = lower[j]
            if x > upper[j]:
                x = upper[j]
            X[i, j] = x


@njit(cache=True)
def record(X, F, best, best_pos):  # type: ignore[no-untyped-def]
    """The best point ever evaluated (strict <, first index), as ``Optimizer.evaluate``."""
    k = -1
    for i in range(F.size):
        if F[i] < best[0]:
            best[0] = F[i]
            k = i
    if k >= 0:
        best_pos[:] = X[k]


_LEADERS = SSA.choices["leaders"]


def pack(p: Mapping[str, ParamValue]) -> np.ndarray:
    return np.array([float(_LEADERS.index(str(p["leaders"])))])


@njit(cache=True)
def run(rng, fid, shifted, shift, lower, upper, agents, iterations, params):  # type: ignore[no-untyped-def]
    """One SSA run (the package's kernel signature): (best value, best point, curve,
    evaluations)."""
    N, d, T = agents, lower.size, iterations
    n_leaders = N // 2 if params[0] == 0.0 else 1
    stream = open_stream(rng, max(2 * n_leaders * d, N * d, N))
    c1 = _c1(T)
    X = np.empty((N, d))
    start = take(stream, RANDOM, N * d)
    u = stream[1][RANDOM]
    for i in range(N):
        for j in range(d):
            X[i, j] = lower[j] + (upper[j] - lower[j]) * u[start + i * d + j]
    F = np.empty(N)
    everyone = np.ones(N, dtype=np.bool_)
    work = np.empty((4, d))
    best = np.full(1, np.inf)
    best_x = np.zeros(d)
    curve = np.empty(T)
    evaluate(stream, fid, shifted, shift, lower, upper, X, F, everyone, work)
    record(X, F, best, best_x)
    for t in range(T):
        move(stream, X, lower, upper, best_x, c1[t], n_leaders)
        evaluate(stream, fid, shifted, shift, lower, upper, X, F, everyone, work)
        record(X, F, best, best_x)
        curve[t] = best[0]
    return best[0], best_x, curve, N * (T + 1)


KERNEL = register_kernel(Kernel("SSA", run, pack))
