"""SSA (:mod:`swarmpath.optimizers.ssa`) as one compiled loop per run, bit for bit the reference.

The same equations in the same order as the numpy reference, on one run's (agents, dim) arrays:

* every number comes from the run's stream in the reference's order: the initial population,
  then per iteration c2 and c3 as one two-part draw of ``leaders x dim`` uniforms each (F7's
  noise, ``agents`` uniforms per evaluation, in between);
* c1 (eq 3.2) is :meth:`SSA.c1` itself, tabulated per number of iterations: Python's ``x ** 2``
  is the C library's pow, which differs from x * x (what compiled code makes of it) in the last
  bit for about one t / T in a thousand;
* the followers are :meth:`SSA.chain` applied as the reference applies it, by ``np.matmul``
  (OpenBLAS). Where OpenBLAS adds each row in index order, that is the literal sweep
  y_i = (y_{i-1} + x_i) / 2 (the weights are powers of two: every product is exact), which the
  kernel then computes in its loop over the salps; elsewhere (here: the last columns when dim
  is 1-4 past a multiple of 8) it calls numpy's own matmul loop
  (:func:`~swarmpath.optimizers.compiled.ufuncs.matmul_into`), about 0.8 us per iteration, 12%
  of a 30 x 30 run. Which of the two a shape gets is found by :func:`sweep_is_matmul`, on this
  machine, once per shape.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import lru_cache

import numpy as np
from numba import njit

from swarmpath.optimizers.compiled.objectives import evaluate, work_for
from swarmpath.optimizers.compiled.registry import Kernel, register_kernel
from swarmpath.optimizers.compiled.streams import RANDOM, open_stream, take
from swarmpath.optimizers.compiled.ufuncs import matmul_into
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


def run(rng, objective, shifted, shift, lower, upper, agents, iterations, params):
    """One SSA run (the package's kernel signature). A Python shim: c1's table and the
    followers' matrix are arguments of the compiled loop."""
    leaders = agents // 2 if params[0] == 0.0 else 1
    c1, chain = _tables(agents, leaders, iterations)
    sweep = sweep_is_matmul(agents - leaders, lower.size)
    return _run(rng, objective, shifted, shift, lower, upper, agents, leaders, c1, chain, sweep)


@lru_cache(maxsize=256)
def sweep_is_matmul(followers: int, dim: int) -> bool:
    """Whether ``np.matmul(SSA.chain(followers), Y)`` for Y (followers + 1, dim) rows of a
    population gives the literal sweep's numbers on this machine, i.e. whether BLAS adds each
    row in index order at this shape. Tried on three random populations whose rows span six
    decades (another order of additions rounds differently almost everywhere)."""
    chain = SSA.chain(followers)
    rng = np.random.default_rng(followers * 1000 + dim)
    for _ in range(3):
        X = rng.standard_normal((2, followers + 3, dim))
        X *= 10.0 ** rng.uniform(-3.0, 3.0, (2, followers + 3, 1))
        Y = X[:, 2:]  # as the reference slices its population
        swept = np.empty((2, followers, dim))
        for r in range(2):
            y = Y[r, 0]
            for i in range(followers):
                y = (y + Y[r, i + 1]) * 0.5
                swept[r, i] = y
        if not np.array_equal(np.matmul(chain, Y), swept):
            return False
    return True


@njit(cache=True)
def record(X, F, best, best_x):
    """The best point ever evaluated (strict <, first index), as ``Optimizer.evaluate``."""
    k = -1
    for i in range(F.size):
        if F[i] < best[0]:
            best[0] = F[i]
            k = i
    if k >= 0:
        for j in range(best_x.size):
            best_x[j] = X[k, j]


@njit(cache=True)
def _run(rng, objective, shifted, shift, lower, upper, N, n_leaders, c1, chain, sweep):
    d, T = lower.size, c1.size
    stream = open_stream(rng, max(2 * n_leaders * d, N * d, N), False)
    u = stream[1][RANDOM]
    X = np.empty((N, d))
    start = take(stream, RANDOM, N * d)
    for i in range(N):
        for j in range(d):
            X[i, j] = lower[j] + (upper[j] - lower[j]) * u[start + i * d + j]
    F = np.empty(N)
    everyone = np.ones(N, dtype=np.bool_)
    work = work_for(N, d)
    out = np.empty((N - n_leaders, d))
    call = np.empty(16, dtype=np.int64)
    best = np.full(1, np.inf)
    best_x = np.zeros(d)
    curve = np.empty(T)
    size = n_leaders * d
    for t in range(T + 1):
        if t:  # eqs 3.1-3.4: the leaders from c2, c3, then the followers; all clipped after
            start = take(stream, RANDOM, 2 * size)
            for i in range(n_leaders):
                for j in range(d):
                    lead = u[start + i * d + j] * (upper[j] - lower[j])
                    lead += lower[j]
                    lead *= c1[t - 1]
                    if u[start + size + i * d + j] >= 0.5:
                        lead = -lead
                    X[i, j] = lead + best_x[j]
            if not sweep:  # the chain starts at the last leader, moved and not clipped
                matmul_into(chain, X[n_leaders - 1:], out, call)
            for i in range(N):
                for j in range(d):
                    x = X[i, j]
                    if i >= n_leaders:
                        x = (X[i - 1, j] + x) * 0.5 if sweep else out[i - n_leaders, j]
                        X[i, j] = x  # unclipped: the next follower averages with it
                    if i > 0:
                        X[i - 1, j] = min(max(X[i - 1, j], lower[j]), upper[j])
            for j in range(d):
                X[N - 1, j] = min(max(X[N - 1, j], lower[j]), upper[j])
        evaluate(stream, objective, shifted, shift, lower, upper, X, F, everyone, work)
        record(X, F, best, best_x)
        if t:
            curve[t - 1] = best[0]
    return best[0], best_x, curve, N * (T + 1)


KERNEL = register_kernel(Kernel("SSA", run, pack))
