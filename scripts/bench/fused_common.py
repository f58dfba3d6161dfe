"""What every independent fused loop of ``scripts/bench/kernels.py`` shares: F1 and F9 written
out by hand, and the record of the best point.

The loops (``fused_*.py``) are written apart from swarmpath's kernels (they import nothing of
``swarmpath.optimizers.compiled`` but ``ufuncs.numpy_loop``, the address of numpy's own loop
where the reference's numbers come from numpy's cbrt, exp or power): each is one ``@njit``
function per run that draws the run's PCG64 generator directly, in swarmpath's order, with the
objective's code inlined (a closure over one of the two objectives below, so the function is
fixed when the loop compiles). They
must reach the backend's best values bit for bit (``kernels.py`` checks every run), so the
objectives add in the order numpy's ``einsum`` adds on this machine (two lanes, blocks of
eight, the last pair of a block first) and take cos(2 pi x) by the reduction and Taylor series
of ``swarmpath.functions.trig`` (coefficients from ``math.factorial``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from swarmpath.optimizers.compiled.ufuncs import numpy_loop

# numpy's own loops (what the reference's np.cbrt, np.exp, ... and ``array ** p`` run: on
# AVX-512 not always the C library's)
CBRT_LOOP, CBRT_DATA = numpy_loop(np.cbrt, "dd")
EXP_LOOP, EXP_DATA = numpy_loop(np.exp, "dd")
COS_LOOP, COS_DATA = numpy_loop(np.cos, "dd")
SIN_LOOP, SIN_DATA = numpy_loop(np.sin, "dd")
LOG1P_LOOP, LOG1P_DATA = numpy_loop(np.log1p, "dd")
POWER_LOOP, POWER_DATA = numpy_loop(np.power, "ddd")
COS_TAYLOR = np.array([(-1) ** k / math.factorial(2 * k) for k in range(12)][::-1])
PI = math.pi


@njit(inline="always")
def square_sum(x, n):
    """sum x_i^2, i < n, in einsum's order."""
    left = 0.0
    right = 0.0
    i = 0
    while i + 8 <= n:
        p = x[i + 6] * x[i + 6] + left
        q = x[i + 7] * x[i + 7] + right
        p = x[i + 4] * x[i + 4] + p
        q = x[i + 5] * x[i + 5] + q
        p = x[i + 2] * x[i + 2] + p
        q = x[i + 3] * x[i + 3] + q
        left = x[i] * x[i] + p
        right = x[i + 1] * x[i + 1] + q
        i += 8
    while i < n:
        left = x[i] * x[i] + left
        right = (x[i + 1] * x[i + 1] if i + 1 < n else 0.0) + right
        i += 2
    return 0.0 + (left + right)


@njit(inline="always")
def plain_sum(x, n):
    """sum x_i, i < n, in one-operand einsum's order."""
    left = 0.0
    right = 0.0
    i = 0
    while i + 8 <= n:
        left = ((x[i] + x[i + 2]) + (x[i + 4] + x[i + 6])) + left
        right = ((x[i + 1] + x[i + 3]) + (x[i + 5] + x[i + 7])) + right
        i += 8
    while i < n:
        left = x[i] + left
        right = (x[i + 1] if i + 1 < n else 0.0) + right
        i += 2
    return (left + right) + 0.0


@njit(inline="always")
def cos_two_pi(x):
    """cos(2 pi x): n = rint(2x), cos(pi (2x - n)) (-1)^n by Horner's rule in t = r^2."""
    q = 2.0 * x
    n = np.rint(q)
    r = (q - n) * PI
    t = r * r
    c = t * COS_TAYLOR[0]
    for k in range(1, COS_TAYLOR.size - 1):
        c = c + COS_TAYLOR[k]
        c = c * t
    c = c + COS_TAYLOR[COS_TAYLOR.size - 1]
    h = n * 0.5
    h = h - np.floor(h)
    return c * (h * -4.0 + 1.0)


@njit(inline="always")
def sphere(x, scratch):
    return square_sum(x, x.size)


@njit(inline="always")
def rastrigin(x, scratch):
    d = x.size
    for j in range(d):
        scratch[j] = cos_two_pi(x[j])
    return (square_sum(x, d) - 10.0 * plain_sum(scratch, d)) + 10.0 * d


#: The objectives a fused loop is compiled with, by swarmpath's function name.
OBJECTIVES = {"F1": sphere, "F9": rastrigin}


@njit(inline="always")
def keep_best(F, X, m, best, best_x):
    """best[0], best_x <- the first minimum of F[:m] when it is below best[0] (strict)."""
    k = 0
    for i in range(1, m):
        if F[i] < F[k]:
            k = i
    if F[k] < best[0]:
        best[0] = F[k]
        for j in range(X.shape[1]):
            best_x[j] = X[k, j]


@njit(inline="always")
def _args(x):
    """numpy's loop arguments for x = f(x) (x contiguous): args, dimensions, steps."""
    call = np.empty(5, dtype=np.int64)
    call[0] = x.ctypes.data
    call[1] = x.ctypes.data
    call[2] = x.size
    call[3] = 8
    call[4] = 8
    return call


@njit
def numpy_cbrt(x):
    """x <- np.cbrt(x) in place, by numpy's loop; and so the others."""
    call = _args(x)
    CBRT_LOOP(call.ctypes.data, call[2:].ctypes.data, call[3:].ctypes.data, CBRT_DATA)


@njit
def numpy_exp(x):
    call = _args(x)
    EXP_LOOP(call.ctypes.data, call[2:].ctypes.data, call[3:].ctypes.data, EXP_DATA)


@njit
def numpy_cos(x):
    call = _args(x)
    COS_LOOP(call.ctypes.data, call[2:].ctypes.data, call[3:].ctypes.data, COS_DATA)


@njit
def numpy_sin(x):
    call = _args(x)
    SIN_LOOP(call.ctypes.data, call[2:].ctypes.data, call[3:].ctypes.data, SIN_DATA)


@njit
def numpy_log1p(x):
    call = _args(x)
    LOG1P_LOOP(call.ctypes.data, call[2:].ctypes.data, call[3:].ctypes.data, LOG1P_DATA)


@njit
def numpy_power(x, e):
    """x ** e as numpy computes an array to a scalar power (the exponent's stride 0)."""
    values = np.array([x, e, 0.0])
    call = np.empty(6, dtype=np.int64)
    base = values.ctypes.data
    call[0] = base
    call[1] = base + 8
    call[2] = base + 16
    call[3] = 1
    call[4] = 8
    call[5] = 0
    steps = np.array([8, 0, 8], dtype=np.int64)
    POWER_LOOP(call.ctypes.data, call[3:].ctypes.data, steps.ctypes.data, POWER_DATA)
    return values[2]
