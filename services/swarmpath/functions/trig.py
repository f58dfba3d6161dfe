"""sin(pi q) and cos(pi q) as numpy array arithmetic: the trigonometry of the hot paths.

numpy 1.26 computes float64 ``np.sin``/``np.cos`` element by element with the C library (about
30-50 ns per element on the project machine, 50-100 times an addition), and the benchmark
functions F8-F13 and the COOT family spend most of their arithmetic there. The functions here
evaluate the same values with whole-array operations only:

1. Exact reduction: n = rint(q), r = q - n lies in [-1/2, 1/2] and is computed without rounding
   (q and n are doubles less than 1 apart), so sin(pi q) = (-1)^n sin(pi r) and
   cos(pi q) = (-1)^n cos(pi r) hold exactly; arguments are taken in units of pi for that reason.
2. The Taylor series of sin and cos about 0, truncated where the first omitted term is below
   1e-17 on |x| <= pi/2 (sin: x, x^3, ..., x^21; cos: 1, x^2, ..., x^22), summed by Horner's
   rule in t = x^2.

Accuracy: within 4e-16 of the correctly rounded value for |q| <= 1e6, i.e. the same values as
``np.sin``/``np.cos`` up to the last bit or two; the reduction makes the results exact where they
should be (sin(pi n) = 0, cos(0) = 1, cos(pi n) = +-1). The cost is about 30 array operations,
2-4 times faster than the C library here. ``tests/test_functions.py`` checks the accuracy.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]

PI = math.pi
# Taylor coefficients in t = x^2: cos x = sum COS[k] t^k, sin x = x sum SIN[k] t^k.
COS = tuple((-1) ** k / math.factorial(2 * k) for k in range(12))
SIN = tuple((-1) ** k / math.factorial(2 * k + 1) for k in range(11))


def _horner(t: Array, coefficients: tuple[float, ...], out: Array) -> Array:
    """sum_k coefficients[k] t^k into ``out`` (may not alias ``t``)."""
    np.multiply(t, coefficients[-1], out=out)
    for c in coefficients[-2:0:-1]:
        out += c
        out *= t
    out += coefficients[0]
    return out


def _reduce(q: Array) -> tuple[Array, Array]:
    """(n, pi r) with n = rint(q), r = q - n in [-1/2, 1/2]: new arrays (also for 0-d q)."""
    n = np.rint(q, out=np.empty(q.shape))
    x = np.subtract(q, n, out=np.empty(q.shape))
    x *= PI
    return n, x


def _parity_sign(n: Array, scratch: Array) -> Array:
    """(-1)^n for integral n, in n's buffer."""
    n *= 0.5
    np.floor(n, out=scratch)
    n -= scratch  # 0 (even) or 0.5 (odd)
    n *= -4.0
    n += 1.0
    return n


def sinpi(q: ArrayLike) -> Array:
    """sin(pi q), elementwise."""
    q = np.asarray(q, dtype=float)
    n, x = _reduce(q)
    t = np.multiply(x, x, out=np.empty(q.shape))
    s = _horner(t, SIN, np.empty(q.shape))
    s *= x
    s *= _parity_sign(n, t)
    return s


def cospi(q: ArrayLike) -> Array:
    """cos(pi q), elementwise."""
    q = np.asarray(q, dtype=float)
    n, x = _reduce(q)
    x *= x
    c = _horner(x, COS, np.empty(q.shape))
    c *= _parity_sign(n, x)
    return c


def sinpi_squared(q: ArrayLike) -> Array:
    """sin(pi q)^2, elementwise (no sign needed: a few operations fewer than ``sinpi(q)**2``)."""
    q = np.asarray(q, dtype=float)
    x = np.rint(q, out=np.empty(q.shape))
    np.subtract(q, x, out=x)
    x *= PI
    t = np.multiply(x, x, out=np.empty(q.shape))
    s = _horner(t, SIN, x)  # sin(x) / x
    s *= s
    s *= t
    return s
