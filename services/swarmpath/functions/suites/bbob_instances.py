"""COCO's instance generator of the noiseless BBOB functions: instance -> x_opt, f_opt, rotations.

COCO (Hansen et al., "COCO: a platform for comparing continuous optimizers in a black-box
setting", Optim. Methods Softw. 36(1), 2021) draws every instance from a seed with the legacy
generator of BBOB 2009 (Hansen et al., INRIA RR-6829): a Park-Miller minimal-standard linear
congruential generator behind a 32-entry shuffle table, Box-Muller normals, rotations by
Gram-Schmidt of a normal matrix, ``x_opt`` on a 1e-4 grid in [-4, 4] and ``f_opt`` a rounded ratio
of two normals clipped to [-1000, 1000]. The seed of function f, instance i is
``f + 10000 i`` (f4 borrows f3's seed for x_opt, f18 f17's for everything).

The numbers here are that generator's, computed the same way (the draws in the same order), so
``bbob:f<k>`` instance i is COCO's instance i (``tests/test_suites_golden.py`` checks values
against ``cocoex``). Results are cached per (seed, dim): an instance is built once per process.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from swarmpath.functions.suites.sums import sequential_sum

Array = NDArray[np.float64]

_MODULUS = 2147483647
_MULTIPLIER = 16807
_QUOTIENT = 127773  # _MODULUS // _MULTIPLIER
_REMAINDER = 2836  # _MODULUS % _MULTIPLIER
_TABLE = 32
_TABLE_DIVISOR = 67108865  # maps a draw to one of the 32 table entries


def _step(state: int) -> int:
    """One Park-Miller step by Schrage's method (no overflow in 32 bits)."""
    high = state // _QUOTIENT
    state = _MULTIPLIER * (state - high * _QUOTIENT) - _REMAINDER * high
    return state + _MODULUS if state < 0 else state


@lru_cache(maxsize=4096)
def _uniform(n: int, seed: int) -> tuple[float, ...]:
    state = max(abs(int(seed)), 1)
    table = [0] * _TABLE
    for k in range(39, -1, -1):  # warm up; the last 32 states fill the table
        state = _step(state)
        if k < _TABLE:
            table[k] = state
    current = table[0]
    out = []
    for _ in range(n):
        state = _step(state)
        slot = current // _TABLE_DIVISOR
        current = table[slot]
        table[slot] = state
        value = current / 2.147483647e9
        out.append(value if value != 0.0 else 1e-99)
    return tuple(out)


def uniform(n: int, seed: int) -> Array:
    """n uniform numbers in (0, 1] from ``seed`` (BBOB 2009's ``unif``)."""
    return np.array(_uniform(int(n), int(seed)), dtype=float)


def gauss(n: int, seed: int) -> Array:
    """n standard normals from ``seed`` by Box-Muller on 2n uniforms (BBOB 2009's ``gauss``)."""
    u = uniform(2 * n, seed)
    g = np.sqrt(-2.0 * np.log(u[:n])) * np.cos(2.0 * math.pi * u[n:])
    g[g == 0.0] = 1e-99
    return g


@lru_cache(maxsize=1024)
def _rotation(dim: int, seed: int) -> Array:
    # column j of the normal matrix holds draws j*dim .. j*dim + dim - 1
    b = gauss(dim * dim, seed).reshape(dim, dim).T.copy()
    for i in range(dim):  # Gram-Schmidt over the columns, in order; sums added in order
        for j in range(i):
            b[:, i] -= sequential_sum(b[:, i] * b[:, j]) * b[:, j]
        b[:, i] /= math.sqrt(sequential_sum(b[:, i] * b[:, i]))
    b.setflags(write=False)
    return b


def rotation(dim: int, seed: int) -> Array:
    """The orthogonal (dim, dim) matrix of ``seed`` (read-only; BBOB 2009's
    ``compute_rotation``)."""
    return _rotation(int(dim), int(seed))


def x_opt(dim: int, seed: int) -> Array:
    """The optimum of ``seed``: uniform on a 1e-4 grid in [-4, 4), never exactly 0."""
    x = 8.0 * np.floor(1e4 * uniform(dim, seed)) / 1e4 - 4.0
    x[x == 0.0] = -1e-5
    return x


def f_opt(function: int, instance: int) -> float:
    """The objective offset of BBOB function ``function``, instance ``instance``."""
    seed = {4: 3, 18: 17}.get(function, function) + 10000 * instance
    ratio = float(gauss(1, seed)[0]) / float(gauss(1, seed + 1)[0])
    return min(1000.0, max(-1000.0, math.floor(100.0 * 100.0 * ratio + 0.5) / 100.0))


def seed_of(function: int, instance: int) -> int:
    """The seed of x_opt and the rotations (f4 uses f3's, f18 f17's)."""
    return {4: 3, 18: 17}.get(function, function) + 10000 * instance
