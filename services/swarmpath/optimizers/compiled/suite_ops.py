"""numpy's operations as the suites' numpy code performs them, for compiled suite objectives.

A compiled suite objective must give the numpy suite's numbers to the last bit (the backends'
contract), so each operation here is numpy's own, not a re-derivation:

* elementwise transcendentals (log, exp, sin, cos, power) call numpy's loops
  (:mod:`ufuncs`: the CPU-dispatched SIMD loops, not the C library), out of place and with the
  strides numpy passes (a power's scalar exponent has stride 0);
* rotations call numpy's matmul loop on the same operands (``X @ M.T`` of a population);
* sums follow the order of the numpy call the suite code makes: ``np.einsum`` over the last
  axis adds in two lanes of its baseline (SSE) loop, four vectors a step
  (:func:`functions.dot`, :func:`functions.total`; tests/test_compiled_suites.py checks them
  against ``einsum`` for every length 1-100), ``.sum`` adds pairwise
  (:func:`functions.pairwise_sum`), ``np.prod`` and ``np.cumsum`` left to right.

The functions take contiguous float64 arrays; ``call`` is int64 scratch of 8 entries.
"""

from __future__ import annotations

import numpy as np
from numba import carray, njit

from swarmpath.optimizers.compiled.functions import dot, pairwise_sum
from swarmpath.optimizers.compiled.ufuncs import (
    _call_cos,
    _call_exp,
    _call_power,
    _call_sin,
    _linked_loop,
    matmul_into,
)

_call_log = _linked_loop("swarmpath_numpy_log_dd", np.log, "dd")


@njit(cache=True)
def population_views(m, d, xp, fp, mp, dp):
    """A suite objective's arguments (objectives.SIGNATURE) as arrays: the points X (m, d),
    the values F (m,), the mask (m,) and the data array, whose entry 0 is its length."""
    n = int(carray(dp, 1)[0])
    return carray(xp, (m, d)), carray(fp, m), carray(mp, m), carray(dp, n)


@njit(cache=True)
def errors_into(F, mask, raw, data):
    """The error (f + f_opt) - f_opt, as the numpy suites compute it (data[1] is f_opt);
    +inf off the mask."""
    fopt = data[1]
    for i in range(F.size):
        F[i] = (raw[i] + fopt) - fopt if mask[i] else np.inf


@njit(cache=True)
def _unary(x, out, call):
    """numpy's loop arguments for out = f(x) (both contiguous, same size)."""
    call[0] = x.ctypes.data
    call[1] = out.ctypes.data
    call[2] = x.size
    call[3] = 8
    call[4] = 8
    return call.ctypes.data, call[2:].ctypes.data, call[3:].ctypes.data


@njit(cache=True)
def log_into(x, out, call):
    _call_log(*_unary(x, out, call))


@njit(cache=True)
def exp_into(x, out, call):
    _call_exp(*_unary(x, out, call))


@njit(cache=True)
def sin_into(x, out, call):
    _call_sin(*_unary(x, out, call))


@njit(cache=True)
def cos_into(x, out, call):
    _call_cos(*_unary(x, out, call))


@njit(cache=True)
def _binary(x, e, out, e_step, call):
    call[0] = x.ctypes.data
    call[1] = e.ctypes.data
    call[2] = out.ctypes.data
    call[3] = x.size
    call[4] = 8
    call[5] = e_step
    call[6] = 8
    _call_power(call.ctypes.data, call[3:].ctypes.data, call[4:].ctypes.data)


@njit(cache=True)
def pow_into(x, e, out, call):
    """out = x ** e elementwise (e an array of x's size)."""
    _binary(x, e, out, 8, call)


@njit(cache=True)
def pow_scalar_into(x, e, out, call):
    """out = x ** e for a scalar e, as numpy runs ``array ** float`` (exponent stride 0)."""
    exponent = np.empty(1)
    exponent[0] = e
    _binary(x, exponent, out, 0, call)


@njit(cache=True)
def rotate(Z, M, call):
    """Z @ M.T for a population Z (m, d) and a rotation M (d, d): the suites' ``rotate``."""
    out = np.empty((Z.shape[0], M.shape[0]))
    matmul_into(Z, M.T, out, np.empty(16, dtype=np.int64))
    return out


@njit(cache=True)
def row_sum(a, n):
    """``a.sum(axis=-1)`` of one row (numpy's pairwise sum)."""
    return pairwise_sum(a, 0, n)


@njit(cache=True)
def oscillate_into(x, out, call):
    """T_osz elementwise as ``bbob_parts.oscillate`` computes it (x, out flat, not aliased)."""
    n = x.size
    t = np.empty(n)
    s1 = np.empty(n)
    s2 = np.empty(n)
    for i in range(n):
        a = abs(x[i])
        s1[i] = a if a > 0.0 else 1.0
    log_into(s1, t, call)
    for i in range(n):
        ti = t[i] / 0.1
        t[i] = ti
        if x[i] > 0.0:
            s1[i] = ti
            s2[i] = 0.79 * ti
        else:
            s1[i] = 0.55 * ti
            s2[i] = 0.31 * ti
    sin_into(s1, out, call)
    sin_into(s2, s1, call)
    for i in range(n):
        s2[i] = t[i] + 0.49 * (out[i] + s1[i])
    exp_into(s2, s1, call)
    pow_scalar_into(s1, 0.1, s2, call)
    for i in range(n):
        if x[i] > 0.0:
            out[i] = s2[i]
        elif x[i] < 0.0:
            out[i] = -s2[i]
        else:
            out[i] = 0.0


@njit(cache=True)
def asymmetric_into(x, ramp, m, d, out, call):
    """T_asy (``bbob_parts.asymmetric``) of a population x (m * d flat); ``ramp`` is
    beta * i / (d - 1) as numpy computes it."""
    n = m * d
    safe = np.empty(n)
    e = np.empty(n)
    for k in range(n):
        safe[k] = x[k] if x[k] > 0.0 else 1.0
        e[k] = 1.0 + ramp[k % d] * np.sqrt(safe[k])
    pow_into(safe, e, out, call)
    for k in range(n):
        if not x[k] > 0.0:
            out[k] = x[k]


@njit(cache=True)
def penalty_row(x, bound):
    """f_pen of one point: the sum of max(0, |x_i| - bound)^2 (einsum's order)."""
    d = x.size
    e = np.empty(d)
    for j in range(d):
        e[j] = max(abs(x[j]) - bound, 0.0)
    return dot(e, e, d)
