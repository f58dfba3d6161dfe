"""SSA (:mod:`swarmpath.optimizers.ssa`) as one compiled loop per run, bit for bit the reference.

The same equations in the same order as the numpy reference, on one run's (agents, dim) arrays:

* every number comes from the run's stream in the reference's order: the initial population,
  then per iteration c2 and c3 as one two-part draw of ``leaders x dim`` uniforms each (F7's
  noise, ``agents`` uniforms per evaluation, in between);
* c1 (eq 3.2) is :meth:`SSA.c1` itself, tabulated per number of iterations: Python's ``x ** 2``
  is the C library's pow, which differs from x * x (what compiled code makes of it) in the last
  bit for about one t / T in a thousand;
* the followers are :meth:`SSA.chain` applied with numpy's own matmul loop
  (:mod:`~swarmpath.optimizers.compiled.ufuncs`). The literal sweep y_i = (y_{i-1} + x_i) / 2
  gives the same numbers only where OpenBLAS adds each row in index order (30 x 30 here, but
  not the last columns when dim is 1-4 past a multiple of 8): calling numpy's loop costs about
  a microsecond per iteration and makes no such exception.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import lru_cache

import numpy as np
from numba import njit

from swarmpath.optimizers.compiled.functions import evaluate
from swarmpath.optimizers.compiled.registry import Kernel, register_kernel
from swarmpath.optimizers.compiled.streams import RANDOM, open_stream, take
from swarmpath.optimizers.compiled.ufuncs import MATMUL, matmul, with_objective
from swarmpath.optimizers.ssa import SSA
from swarmpath.registry import ParamValue

_LEADERS = SSA.choices["leaders"]


def pack(p: Mapping[str, ParamValue]) -> np.ndarray:
    return np.array([float(_LEADERS.index(str(p["leaders"])))])


@lru_cache(maxsize=32)
def _tables(agents: int, leaders: int, iterations: int) -> tuple[np.ndarray, np.ndarray]:
    """(c1 for t = 1..T, the followers' matrix), from the reference's own functions."""
    c1 = np.array([SSA.c1(t, iterations) for t in range(1, iterations + 1)])
    chain = SSA.chain(agents - leaders)
    c1.flags.writeable = False
    chain.flags.writeable = False
    return c1, chain


def run(rng, fid, shifted, shift, lower, upper, agents, iterations, params):
    """One SSA run (the package's kernel signature). A Python shim: the tables and numpy's
    matmul loop are arguments of the compiled loop (a global function pointer would keep numba
    from caching it)."""
    leaders, c1, chain = _setting(agents, iterations, params)
    return _run(rng, fid, shifted, shift, lower, upper, agents, leaders, c1, chain, *MATMUL)


def loop(evaluate, rng, fid, shifted, shift, lower, upper, agents, iterations, params):
    """``run`` with the objective ``evaluate`` (``functions.evaluate``'s signature), for
    ``scripts/bench/kernels.py``'s fused loop (compiled per objective, not cached)."""
    leaders, c1, chain = _setting(agents, iterations, params)
    return with_objective(_run, evaluate)(rng, fid, shifted, shift, lower, upper, agents,
                                          leaders, c1, chain, *MATMUL)


def _setting(agents, iterations, params):
    leaders = agents // 2 if params[0] == 0.0 else 1
    return (leaders, *_tables(agents, leaders, iterations))


@njit(cache=True)
def move(stream, X, lower, upper, food, c1, n_leaders, chain, mm, data, out, call):
    """One SSA move of the population X (agents, dim) in place, clipped (not evaluated).

    ``food`` is the best point ever evaluated, ``c1`` eq 3.2 at this iteration, ``out``
    (agents - leaders, dim) scratch.
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
    # followers: the chain starts at the last leader, moved and not clipped
    matmul(mm, data, chain, X[n_leaders - 1 :], out, call)
    X[n_leaders:] = out
    for i in range(N):
        for j in range(d):
            x = X[i, j]
            if x < lower[j]:
                x = lower[j]
            if x > upper[j]:
                x = upper[j]
            X[i, j] = x


@njit(cache=True)
def record(X, F, best, best_x):
    """The best point ever evaluated (strict <, first index), as ``Optimizer.evaluate``."""
    k = -1
    for i in range(F.size):
        if F[i] < best[0]:
            best[0] = F[i]
            k = i
    if k >= 0:
        best_x[:] = X[k]


@njit(cache=True)
def _run(rng, fid, shifted, shift, lower, upper, N, n_leaders, c1, chain, mm, data):
    d, T = lower.size, c1.size
    stream = open_stream(rng, max(2 * n_leaders * d, N * d, N))
    X = np.empty((N, d))
    start = take(stream, RANDOM, N * d)
    u = stream[1][RANDOM]
    for i in range(N):
        for j in range(d):
            X[i, j] = lower[j] + (upper[j] - lower[j]) * u[start + i * d + j]
    F = np.empty(N)
    everyone = np.ones(N, dtype=np.bool_)
    work = np.empty((4, d))
    out = np.empty((N - n_leaders, d))
    call = np.empty(16, dtype=np.int64)
    best = np.full(1, np.inf)
    best_x = np.zeros(d)
    curve = np.empty(T)
    evaluate(stream, fid, shifted, shift, lower, upper, X, F, everyone, work)
    record(X, F, best, best_x)
    for t in range(T):
        move(stream, X, lower, upper, best_x, c1[t], n_leaders, chain, mm, data, out, call)
        evaluate(stream, fid, shifted, shift, lower, upper, X, F, everyone, work)
        record(X, F, best, best_x)
        curve[t] = best[0]
    return best[0], best_x, curve, N * (T + 1)


KERNEL = register_kernel(Kernel("SSA", run, pack))
