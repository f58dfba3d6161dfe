"""F1-F13, the classical benchmark set of Yao, Liu & Lin (IEEE TEC 3(2), 1999).

Each function is written as the authors of the Grey Wolf Optimizer computed it in their published
code (Mirjalili, Mirjalili & Lewis, Adv. Eng. Softw. 69, 2014, `Get_Functions_details.m`), which is
also where the seeds' Table 1 comes from. The seeds copy several formulas with typos; the
decisions are listed in docs/functions.md.

Every kernel takes an array of shape (..., d) and returns shape (...). They are written for speed
on the optimizers' (runs, agents, d) batches: sums over the coordinates with ``np.einsum`` (numpy's
reductions along a short last axis are 2-3 times slower), no temporaries that can be avoided, and
sin/cos through :mod:`swarmpath.functions.trig` (whole-array arithmetic, the same values up to the
last bit or two; the C library is 50-100 times an addition per element).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from swarmpath.functions.trig import cospi, sinpi, sinpi_squared

Array = NDArray[np.float64]


def _sum(x: Array) -> Array:
    """sum over the last axis."""
    return np.einsum("...i->...", x)


def _sum_squares(x: Array) -> Array:
    """sum of squares over the last axis."""
    return np.einsum("...i,...i->...", x, x)


@lru_cache(maxsize=64)
def _weights(name: str, d: int) -> Array:
    """Per-coordinate constants of F7 and F11 for dimension d (read-only)."""
    i = np.arange(1, d + 1, dtype=float)
    w = i if name == "index" else 1.0 / (math.pi * np.sqrt(i))
    w.flags.writeable = False
    return w


def sphere(x: Array) -> Array:  # F1
    return _sum_squares(x)


def schwefel_2_22(x: Array) -> Array:  # F2
    ax = np.abs(x)
    return _sum(ax) + np.prod(ax, axis=-1)


def schwefel_1_2(x: Array) -> Array:  # F3
    partial = np.cumsum(x, axis=-1)
    return _sum_squares(partial)


def schwefel_2_21(x: Array) -> Array:  # F4
    return np.max(np.abs(x), axis=-1)


def rosenbrock(x: Array) -> Array:  # F5
    head = x[..., :-1]
    gap = head * head
    np.subtract(x[..., 1:], gap, out=gap)  # x_{i+1} - x_i^2
    one = head - 1.0
    return 100.0 * _sum_squares(gap) + _sum_squares(one)


def step(x: Array) -> Array:  # F6 as the GWO code computes it: no floor
    shifted = x + 0.5
    return _sum_squares(shifted)


def step_floor(x: Array) -> Array:  # F6 as Yao et al. define it
    floored = np.floor(x + 0.5)
    return _sum_squares(floored)


def quartic(x: Array) -> Array:  # F7 without its U[0,1) noise term
    x2 = x * x  # squaring twice: numpy's general power is far slower here
    x2 *= x2
    return np.einsum("...i,i->...", x2, _weights("index", x.shape[-1]))


def schwefel_2_26(x: Array) -> Array:  # F8
    root = np.abs(x)
    np.sqrt(root, out=root)
    root *= 1.0 / math.pi
    return -np.einsum("...i,...i->...", x, sinpi(root))


def rastrigin(x: Array) -> Array:  # F9
    return _sum_squares(x) - 10.0 * _sum(cospi(2.0 * x)) + 10.0 * x.shape[-1]


def ackley(x: Array) -> Array:  # F10
    d = x.shape[-1]
    quad = np.sqrt(_sum_squares(x) / d)
    cyc = _sum(cospi(2.0 * x)) / d
    return -20.0 * np.exp(-0.2 * quad) - np.exp(cyc) + 20.0 + np.e


def griewank(x: Array) -> Array:  # F11
    waves = cospi(x * _weights("griewank", x.shape[-1]))  # cos(x_i / sqrt(i))
    return _sum_squares(x) / 4000.0 - np.prod(waves, axis=-1) + 1.0


def _penalty(x: Array, a: float, k: float, m: int) -> Array:
    """u(x, a, k, m) of Yao et al., summed over the coordinates.

    u = k (x - a)^m for x > a, k (-x - a)^m for x < -a, 0 in between: that is k max(|x| - a, 0)^m
    (|x| - a is exactly x - a or -x - a), with m = 4 by repeated squaring (numpy's general power
    is far slower).
    """
    excess = np.abs(x)
    excess -= a
    np.maximum(excess, 0.0, out=excess)
    if m == 4:
        excess *= excess
        excess *= excess
    else:
        excess **= m
    return k * _sum(excess)


def penalized_1(x: Array) -> Array:  # F12
    # y_i = 1 + (x_i + 1) / 4; written with z = y - 1 = (x + 1) / 4, sin(pi y) = -sin(pi z)
    d = x.shape[-1]
    z = x + 1.0
    z *= 0.25
    waves = sinpi_squared(z)  # sin^2(pi y_i) for every i
    first = 10.0 * waves[..., 0]
    waves *= 10.0
    waves += 1.0  # 1 + 10 sin^2(pi y_i)
    head = z[..., :-1]
    inner = np.einsum("...i,...i,...i->...", head, head, waves[..., 1:])
    last = z[..., -1] ** 2
    return (math.pi / d) * (first + inner + last) + _penalty(x, 10.0, 100.0, 4)


def penalized_2(x: Array) -> Array:  # F13
    waves = sinpi_squared(3.0 * x)  # sin^2(3 pi x_i) for every i
    first = waves[..., 0].copy()
    waves += 1.0
    head = x[..., :-1] - 1.0
    inner = np.einsum("...i,...i,...i->...", head, head, waves[..., 1:])
    xn = x[..., -1]
    last = (xn - 1.0) ** 2 * (1.0 + sinpi_squared(2.0 * xn))
    return 0.1 * (first + inner + last) + _penalty(x, 5.0, 100.0, 4)
