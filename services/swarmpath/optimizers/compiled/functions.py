"""F1-F13 (and F6-floor) in compiled code, value for value the numpy reference's numbers.

:func:`evaluate` computes one population's values like ``BenchmarkProblem._evaluate`` (shift,
F8's wrap into its box, the kernel, F7's noise from the run's stream). Each kernel repeats the
operations of :mod:`swarmpath.functions.definitions` in the same order, and each reduction adds
in the order numpy adds on this build (its baseline SIMD is two doubles wide, no FMA):

* ``einsum("...i,...i->...")`` (sums of squares, dot products): two lanes, 8 numbers per step
  added last-pair-first (:func:`dot`); ``einsum("...i->...")``: two lanes, pairs of pairs per
  step (:func:`total`); three operands: one accumulator in order (:func:`dot3`).
* ``np.prod``/``np.cumsum`` along the coordinates: in order.
* sin(pi q), cos(pi q): the reduction and Taylor/Horner steps of
  :mod:`swarmpath.functions.trig`, operation for operation.

``tests/test_compiled.py`` checks every function bit for bit against the reference. F10
(Ackley) needs numpy's own ``exp`` for that: numpy's vectorised exp and the C library's differ
in the last bit for about one argument in a hundred, and near Ackley's optimum a last-bit
difference reorders agents. :func:`evaluate` therefore computes a whole population's exponent
arguments in compiled code and runs numpy's own exp loop on them once per evaluation
(:func:`numpy_exp`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from swarmpath.functions.registry import list_functions
from swarmpath.functions.trig import COS, SIN
from swarmpath.optimizers.compiled.streams import RANDOM, take
from swarmpath.optimizers.compiled.ufuncs import exp_inplace

#: Function ids of the compiled kernels, by registered name.
FUNCTION_IDS: dict[str, int] = {
    "F1": 1, "F2": 2, "F3": 3, "F4": 4, "F5": 5, "F6": 6, "F7": 7, "F8": 8, "F9": 9, "F10": 10,
    "F11": 11, "F12": 12, "F13": 13, "F6-floor": 14,
}
# Every built-in function has a kernel; suites' and plugins' functions have none (run on numpy).
assert set(FUNCTION_IDS) == set(list_functions(builtin=True)), "a built-in has no compiled id"
NOISY = 7
WRAPPED = 8
ACKLEY = 10

_PI = math.pi
_E = float(np.e)
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


# ------------------------------------------------------------------------------- functions
@njit(cache=True)
def _penalty(x, a, k, w):
    d = x.size
    for i in range(d):
        e = abs(x[i]) - a
        e = max(e, 0.0)
        e = e * e
        w[i] = e * e
    return k * total(w, d)


@njit(cache=True)
def ackley_parts(x, w):
    """F10's two exponent arguments at x: (-0.2 sqrt(sum x^2 / d), sum cos(2 pi x) / d)."""
    d = x.size
    u = w[0]
    quad = np.sqrt(dot(x, x, d) / d)
    for i in range(d):
        u[i] = cospi(2.0 * x[i])
    return -0.2 * quad, total(u, d) / d


@njit(cache=True, inline="always")
def value(fid, x, w):
    """f(x) of function ``fid`` (not F10: see :func:`evaluate`) for one point x (d,) (no noise);
    ``w`` is (3, d) scratch."""
    d = x.size
    u = w[0]
    v = w[1]
    if fid == 1:
        return dot(x, x, d)
    if fid == 2:
        p = 1.0
        for i in range(d):
            u[i] = abs(x[i])
        p = u[0]
        for i in range(1, d):
            p = p * u[i]
        return total(u, d) + p
    if fid == 3:
        s = 0.0
        for i in range(d):
            s = s + x[i] if i else x[0]
            u[i] = s
        return dot(u, u, d)
    if fid == 4:
        m = abs(x[0])
        for i in range(1, d):
            a = abs(x[i])
            if a > m:
                m = a
        return m
    if fid == 5:
        for i in range(d - 1):
            h = x[i]
            u[i] = x[i + 1] - h * h
            v[i] = h - 1.0
        return 100.0 * dot(u, u, d - 1) + dot(v, v, d - 1)
    if fid == 6 or fid == 14:
        for i in range(d):
            u[i] = np.floor(x[i] + 0.5) if fid == 14 else x[i] + 0.5
        return dot(u, u, d)
    if fid == 7:
        for i in range(d):
            q = x[i] * x[i]
            u[i] = q * q
            v[i] = i + 1.0
        return dot(u, v, d)
    if fid == 8:
        for i in range(d):
            r = np.sqrt(abs(x[i])) * _INV_PI
            u[i] = sinpi(r)
        return -dot(x, u, d)
    if fid == 9:
        for i in range(d):
            u[i] = cospi(2.0 * x[i])
        return (dot(x, x, d) - 10.0 * total(u, d)) + 10.0 * d
    if fid == 11:
        p = 1.0
        for i in range(d):
            c = cospi(x[i] * (1.0 / (_PI * np.sqrt(i + 1.0))))
            p = p * c if i else c
        return (dot(x, x, d) / 4000.0 - p) + 1.0
    if fid == 12:
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
    if fid == 13:
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
    raise ValueError("unknown function id")


@njit(cache=True)
def numpy_exp(e):
    """e <- np.exp(e), numpy's own loop called directly (:func:`ufuncs.exp_inplace`: tens of
    nanoseconds where object mode took microseconds per call)."""
    exp_inplace(e, np.empty(5, dtype=np.int64))


@njit(cache=True)
def evaluate(stream, fid, shifted, shift, lower, upper, X, F, mask, w):
    """Values of the population X (m, d) into F (m,), as the reference's objective computes them.

    ``shifted``: subtract ``shift`` (d,) first (F8 is then wrapped into its box: ``lower``,
    ``upper`` (d,)).
    ``mask`` (m,) bool: False rows are not computed (F gets +inf), which is what the reference's
    masked evaluation leaves of them; F7's noise is drawn for all m rows either way. ``w`` is
    (4, d) scratch. NaN values become +inf, as ``Optimizer.evaluate`` does.
    """
    m, d = X.shape
    z = w[3]
    ackley = fid == ACKLEY
    e = np.zeros(2 * m if ackley else 0)  # F10: exponent arguments, then np.exp of them
    for i in range(m):
        if not mask[i]:
            F[i] = np.inf
            continue
        x = X[i]
        if shifted:
            for j in range(d):
                z[j] = X[i, j] - shift[j]
            if fid == WRAPPED:
                for j in range(d):
                    z[j] = ((z[j] - lower[j]) % (upper[j] - lower[j])) + lower[j]
            x = z
        if ackley:
            e[i], e[m + i] = ackley_parts(x, w)
        else:
            F[i] = value(fid, x, w)
    if ackley:
        numpy_exp(e)
        for i in range(m):
            if mask[i]:
                F[i] = ((-20.0 * e[i] - e[m + i]) + 20.0) + _E
    if fid == NOISY:
        start = take(stream, RANDOM, m)
        row = stream[1][RANDOM]
        for i in range(m):
            F[i] = F[i] + row[start + i]
    for i in range(m):
        if np.isnan(F[i]):
            F[i] = np.inf
