"""F1-F13, the classical benchmark set of Yao, Liu & Lin (IEEE TEC 3(2), 1999).

Each function is written as the authors of the Grey Wolf Optimizer computed it in their published
code (Mirjalili, Mirjalili & Lewis, Adv. Eng. Softw. 69, 2014, `Get_Functions_details.m`), which is
also where the seeds' Table 1 comes from. The seeds copy several formulas with typos; the
decisions are listed in docs/functions.md.

Every kernel takes an array of shape (..., d) and returns shape (...).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def sphere(x: Array) -> Array:  # F1
    return np.sum(x * x, axis=-1)


def schwefel_2_22(x: Array) -> Array:  # F2
    ax = np.abs(x)
    return np.sum(ax, axis=-1) + np.prod(ax, axis=-1)


def schwefel_1_2(x: Array) -> Array:  # F3
    partial = np.cumsum(x, axis=-1)
    return np.sum(partial * partial, axis=-1)


def schwefel_2_21(x: Array) -> Array:  # F4
    return np.max(np.abs(x), axis=-1)


def rosenbrock(x: Array) -> Array:  # F5
    head, tail = x[..., :-1], x[..., 1:]
    return np.sum(100.0 * (tail - head * head) ** 2 + (head - 1.0) ** 2, axis=-1)


def step(x: Array) -> Array:  # F6 as the GWO code computes it: no floor
    shifted = x + 0.5
    return np.sum(shifted * shifted, axis=-1)


def step_floor(x: Array) -> Array:  # F6 as Yao et al. define it
    floored = np.floor(x + 0.5)
    return np.sum(floored * floored, axis=-1)


def quartic(x: Array) -> Array:  # F7 without its U[0,1) noise term
    i = np.arange(1, x.shape[-1] + 1, dtype=float)
    x2 = x * x  # squaring twice: numpy's general power is far slower here
    return np.sum(i * (x2 * x2), axis=-1)


def schwefel_2_26(x: Array) -> Array:  # F8
    return np.sum(-x * np.sin(np.sqrt(np.abs(x))), axis=-1)


def rastrigin(x: Array) -> Array:  # F9
    return np.sum(x * x - 10.0 * np.cos(2.0 * np.pi * x), axis=-1) + 10.0 * x.shape[-1]


def ackley(x: Array) -> Array:  # F10
    d = x.shape[-1]
    quad = np.sqrt(np.sum(x * x, axis=-1) / d)
    cyc = np.sum(np.cos(2.0 * np.pi * x), axis=-1) / d
    return -20.0 * np.exp(-0.2 * quad) - np.exp(cyc) + 20.0 + np.e


def griewank(x: Array) -> Array:  # F11
    i = np.arange(1, x.shape[-1] + 1, dtype=float)
    return np.sum(x * x, axis=-1) / 4000.0 - np.prod(np.cos(x / np.sqrt(i)), axis=-1) + 1.0


def _penalty(x: Array, a: float, k: float, m: int) -> Array:
    """u(x, a, k, m) of Yao et al., summed over the coordinates.

    Written as k * max(x - a, 0)^m + k * max(-x - a, 0)^m (at most one term is non-zero), with
    m = 4 by repeated squaring: numpy's general power is far slower here.
    """
    over = np.maximum(x - a, 0.0)
    under = np.maximum(-x - a, 0.0)
    if m == 4:
        over *= over
        over *= over
        under *= under
        under *= under
    else:
        over **= m
        under **= m
    return k * np.sum(over + under, axis=-1)


def penalized_1(x: Array) -> Array:  # F12
    d = x.shape[-1]
    y = 1.0 + (x + 1.0) / 4.0
    first = 10.0 * np.sin(np.pi * y[..., 0]) ** 2
    wave = 1.0 + 10.0 * np.sin(np.pi * y[..., 1:]) ** 2
    inner = np.sum((y[..., :-1] - 1.0) ** 2 * wave, axis=-1)
    last = (y[..., -1] - 1.0) ** 2
    return (np.pi / d) * (first + inner + last) + _penalty(x, 10.0, 100.0, 4)


def penalized_2(x: Array) -> Array:  # F13
    first = np.sin(3.0 * np.pi * x[..., 0]) ** 2
    inner = np.sum(
        (x[..., :-1] - 1.0) ** 2 * (1.0 + np.sin(3.0 * np.pi * x[..., 1:]) ** 2), axis=-1
    )
    xn = x[..., -1]
    last = (xn - 1.0) ** 2 * (1.0 + np.sin(2.0 * np.pi * xn) ** 2)
    return 0.1 * (first + inner + last) + _penalty(x, 5.0, 100.0, 4)
