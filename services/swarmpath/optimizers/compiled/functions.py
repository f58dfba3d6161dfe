"""F1-F13 (and F6-floor) at one point in compiled code, value for value the numpy reference's.

Each function repeats the operations of :mod:`swarmpath.functions.definitions` in the same order,
and each reduction adds in the order numpy adds on this build (its baseline SIMD is two doubles
wide, no FMA):

* ``einsum("...i,...i->...")`` (sums of squares, dot products): two lanes, 8 numbers per step
  added last-pair-first (:func:`dot`); ``einsum("...i->...")``: two lanes, pairs of pairs per
  step (:func:`total`); three operands: one accumulator in order (:func:`dot3`).
* ``np.prod``/``np.cumsum`` along the coordinates: in order.
* sin(pi q), cos(pi q): the reduction and Taylor/Horner steps of
  :mod:`swarmpath.functions.trig`, operation for operation.

A point function takes the point x (d,) and scratch w (3, d); F10 (Ackley) has no point function:
its two exponent arguments (:func:`ackley_parts`) go through numpy's own exp loop for a whole
population at once (:mod:`.objectives`). The population objectives the kernels call are built
on these in :mod:`.objectives`; ``tests/test_compiled.py`` checks every function bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from swarmpath.functions.trig import COS, SIN

_PI = math.pi
_INV_PI = 1.0 / math.pi
# Horner coefficients, highest degree first (the reference runs coefficients[-1] ... [0])
_COS = np.array(COS[::-1])
_SIN = np.array(SIN[::-1])


# ----------------------------------------------------------------------------- reductions
@njit(cache=True, inline="always")
def dot(x, y, n):
    """sum x_i y_i over i < n, as numpy's einsum adds it (two lanes, blocks of eight)."""
    a0 = 0.0
    a1 = 0.0
    i = 0
    while n - i >= 8:
        b0 = x[i + 6] * y[i + 6] + a0
        b1 = x[i + 7] * y[i + 7] + a1
        b0 = x[i + 4] * y[i + 4] + b0
        b1 = x[i + 5] * y[i + 5] + b1
        b0 = x[i + 2] * y[i + 2] + b0
        b1 = x[i + 3] * y[i + 3] + b1
        a0 = x[i] * y[i] + b0
        a1 = x[i + 1] * y[i + 1] + b1
        i += 8
    while i < n:
        a0 = x[i] * y[i] + a0
        if i + 1 < n:
            a1 = x[i + 1] * y[i + 1] + a1
        else:
            a1 = 0.0 * 0.0 + a1
        i += 2
    return 0.0 + (a0 + a1)


@njit(cache=True, inline="always")
def total(x, n):
    """sum x_i over i < n, as numpy's one-operand einsum adds it."""
    a0 = 0.0
    a1 = 0.0
    i = 0
    while n - i >= 8:
        s0 = (x[i] + x[i + 2]) + (x[i + 4] + x[i + 6])
        s1 = (x[i + 1] + x[i + 3]) + (x[i + 5] + x[i + 7])
        a0 = s0 + a0
        a1 = s1 + a1
        i += 8
    while i < n:
        a0 = x[i] + a0
        if i + 1 < n:
            a1 = x[i + 1] + a1
        else:
            a1 = 0.0 + a1
        i += 2
    return (a0 + a1) + 0.0


@njit(cache=True, inline="always")
def dot3(x, y, z, n):
    """sum x_i y_i z_i over i < n, in order (numpy's three-operand einsum)."""
    acc = 0.0
    for i in range(n):
        acc += x[i] * y[i] * z[i]
    return acc + 0.0


# ---------------------------------------------------------------------------- trigonometry
@njit(cache=True, inline="always")
def _parity(n):
    h = n * 0.5
    h = h - np.floor(h)
    h = h * -4.0
    return h + 1.0


@njit(cache=True, inline="always")
def _horner(t, coefficients):
    out = t * coefficients[0]
    for k in range(1, coefficients.size - 1):
        out = out + coefficients[k]
        out = out * t
    return out + coefficients[coefficients.size - 1]


@njit(cache=True, inline="always")
def sinpi(q):
    n = np.rint(q)
    x = (q - n) * _PI
    s = _horner(x * x, _SIN)
    s = s * x
    return s * _parity(n)


@njit(cache=True, inline="always")
def cospi(q):
    n = np.rint(q)
    x = (q - n) * _PI
    c = _horner(x * x, _COS)
    return c * _parity(n)


@njit(cache=True, inline="always")
def sinpi_squared(q):
    x = (q - np.rint(q)) * _PI
    t = x * x
    s = _horner(t, _SIN)
    s = s * s
    return s * t


@njit(cache=True)
def _block_sum(a, start, n):
    """numpy's pairwise sum of a[start:start + n] for n <= 128: eight accumulators."""
    if n < 8:
        s = 0.0
        for i in range(n):
            s += a[start + i]
        return s
    r0, r1, r2, r3 = a[start], a[start + 1], a[start + 2], a[start + 3]
    r4, r5, r6, r7 = a[start + 4], a[start + 5], a[start + 6], a[start + 7]
    i = 8
    while i < n - n % 8:
        r0 += a[start + i]
        r1 += a[start + i + 1]
        r2 += a[start + i + 2]
        r3 += a[start + i + 3]
        r4 += a[start + i + 4]
        r5 += a[start + i + 5]
        r6 += a[start + i + 6]
        r7 += a[start + i + 7]
        i += 8
    s = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        s += a[start + i]
        i += 1
    return s


@njit(cache=True)
def pairwise_sum(a, start, n):
    """sum of a[start:start + n] as numpy adds a contiguous reduction (pairwise: eight
    accumulators up to 128 numbers, above that the sum of two halves, the first a multiple of
    8), without the initial 0. numpy's recursion runs on explicit stacks: a recursive function
    cached by numba fails to load in the next process (an unresolved symbol of itself)."""
    if n <= 128:
        return _block_sum(a, start, n)
    starts = np.empty(192, dtype=np.int64)  # pending parts (start, size, 1: add the two
    sizes = np.empty(192, dtype=np.int64)  # sums on top), 3 per level of halving
    combine = np.empty(192, dtype=np.bool_)
    sums = np.empty(64)
    top, at = 0, 0
    starts[0], sizes[0], combine[0] = start, n, False
    while top >= 0:
        s, m, join = starts[top], sizes[top], combine[top]
        top -= 1
        if join:
            at -= 1
            sums[at - 1] = sums[at - 1] + sums[at]
        elif m <= 128:
            sums[at] = _block_sum(a, s, m)
            at += 1
        else:
            half = m // 2
            half -= half % 8
            starts[top + 1], sizes[top + 1], combine[top + 1] = s, m, True
            starts[top + 2], sizes[top + 2], combine[top + 2] = s + half, m - half, False
            starts[top + 3], sizes[top + 3], combine[top + 3] = s, half, False
            top += 3
    return sums[0]


# ------------------------------------------------------------------------------- functions
@njit(cache=True, inline="always")
def _penalty(x, a, k, w):
    d = x.size
    for i in range(d):
        e = abs(x[i]) - a
        e = max(e, 0.0)
        e = e * e
        w[i] = e * e
    return k * total(w, d)


@njit(cache=True, inline="always")
def ackley_parts(x, w):
    """F10's two exponent arguments at x: (-0.2 sqrt(sum x^2 / d), sum cos(2 pi x) / d)."""
    d = x.size
    u = w[0]
    quad = np.sqrt(dot(x, x, d) / d)
    for i in range(d):
        u[i] = cospi(2.0 * x[i])
    return -0.2 * quad, total(u, d) / d


@njit(cache=True, inline="always")
def sphere(x, w):  # F1
    return dot(x, x, x.size)


@njit(cache=True, inline="always")
def schwefel_2_22(x, w):  # F2
    d = x.size
    u = w[0]
    for i in range(d):
        u[i] = abs(x[i])
    p = u[0]
    for i in range(1, d):
        p = p * u[i]
    return total(u, d) + p


@njit(cache=True, inline="always")
def schwefel_1_2(x, w):  # F3
    d = x.size
    u = w[0]
    s = 0.0
    for i in range(d):
        s = s + x[i] if i else x[0]
        u[i] = s
    return dot(u, u, d)


@njit(cache=True, inline="always")
def schwefel_2_21(x, w):  # F4
    m = abs(x[0])
    for i in range(1, x.size):
        a = abs(x[i])
        if a > m:
            m = a
    return m


@njit(cache=True, inline="always")
def rosenbrock(x, w):  # F5
    d = x.size
    u = w[0]
    v = w[1]
    for i in range(d - 1):
        h = x[i]
        u[i] = x[i + 1] - h * h
        v[i] = h - 1.0
    return 100.0 * dot(u, u, d - 1) + dot(v, v, d - 1)


@njit(cache=True, inline="always")
def step(x, w):  # F6 (the GWO code's: no floor)
    d = x.size
    u = w[0]
    for i in range(d):
        u[i] = x[i] + 0.5
    return dot(u, u, d)


@njit(cache=True, inline="always")
def step_floor(x, w):  # F6-floor
    d = x.size
    u = w[0]
    for i in range(d):
        u[i] = np.floor(x[i] + 0.5)
    return dot(u, u, d)


@njit(cache=True, inline="always")
def quartic(x, w):  # F7 without its noise
    d = x.size
    u = w[0]
    v = w[1]
    for i in range(d):
        q = x[i] * x[i]
        u[i] = q * q
        v[i] = i + 1.0
    return dot(u, v, d)


@njit(cache=True, inline="always")
def schwefel_2_26(x, w):  # F8
    d = x.size
    u = w[0]
    for i in range(d):
        r = np.sqrt(abs(x[i])) * _INV_PI
        u[i] = sinpi(r)
    return -dot(x, u, d)


@njit(cache=True, inline="always")
def rastrigin(x, w):  # F9
    d = x.size
    u = w[0]
    for i in range(d):
        u[i] = cospi(2.0 * x[i])
    return (dot(x, x, d) - 10.0 * total(u, d)) + 10.0 * d


@njit(cache=True, inline="always")
def griewank(x, w):  # F11
    d = x.size
    p = 1.0
    for i in range(d):
        c = cospi(x[i] * (1.0 / (_PI * np.sqrt(i + 1.0))))
        p = p * c if i else c
    return (dot(x, x, d) / 4000.0 - p) + 1.0


@njit(cache=True, inline="always")
def penalized_1(x, w):  # F12
    d = x.size
    u = w[0]
    v = w[1]
    for i in range(d):
        z = (x[i] + 1.0) * 0.25
        u[i] = z
        v[i] = sinpi_squared(z)
    first = 10.0 * v[0]
    for i in range(d):
        v[i] = v[i] * 10.0 + 1.0
    inner = dot3(u, u, v[1:], d - 1)
    last = u[d - 1] * u[d - 1]
    return (_PI / d) * ((first + inner) + last) + _penalty(x, 10.0, 100.0, w[2])


@njit(cache=True, inline="always")
def penalized_2(x, w):  # F13
    d = x.size
    u = w[0]
    v = w[1]
    for i in range(d):
        v[i] = sinpi_squared(3.0 * x[i])
        u[i] = x[i] - 1.0
    first = v[0]
    for i in range(d):
        v[i] = v[i] + 1.0
    inner = dot3(u, u, v[1:], d - 1)
    xn = x[d - 1]
    g = xn - 1.0
    last = (g * g) * (1.0 + sinpi_squared(2.0 * xn))
    return 0.1 * ((first + inner) + last) + _penalty(x, 5.0, 100.0, w[2])
