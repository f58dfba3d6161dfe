"""The 24 BBOB functions as compiled population objectives (``bbob:f1`` .. ``bbob:f24``).

Each follows :mod:`swarmpath.functions.suites.bbob` operation by operation (numpy's loops,
its matmul, its summation orders: :mod:`suite_ops`), so a compiled run gives the numpy suite's
numbers to the last bit; tests/test_compiled_suites.py compares every function's values on
random points and at the optimum, and the optimizers' results, with the numpy backend.

An instance's constants are packed into the objective's ``data`` array by
:func:`.bbob_data.pack` (the layout is described there).
"""

from __future__ import annotations

import types
from typing import Any

import numpy as np
from numba import njit

from swarmpath.optimizers.compiled.bbob_data import HEADER
from swarmpath.optimizers.compiled.bbob_data import data_for as data_for
from swarmpath.optimizers.compiled.bbob_data import pack as pack
from swarmpath.optimizers.compiled.functions import dot, total
from swarmpath.optimizers.compiled.suite_ops import (
    asymmetric_into,
    cos_into,
    errors_into,
    exp_into,
    oscillate_into,
    penalty_row,
    population_views,
    pow_into,
    pow_scalar_into,
    rotate,
    row_sum,
    sin_into,
)

_H = HEADER
_TWO_PI = 2.0 * np.pi


# --- access to the data array and the population (njit: called from the cfuncs) ---

@njit(cache=True)
def _mat(data, d, k):
    at = _H + d + k * d * d
    return data[at:at + d * d].reshape((d, d))


@njit(cache=True)
def _vec(data, d, k):
    at = _H + d + 2 * d * d + k * d
    return data[at:at + d]


@njit(cache=True)
def _extra(data, d):
    return data[_H + 4 * d + 2 * d * d:]


@njit(cache=True)
def _minus_xopt(X, data, d):
    xopt = data[_H:_H + d]
    Z = np.empty(X.shape)
    for i in range(X.shape[0]):
        for j in range(d):
            Z[i, j] = X[i, j] - xopt[j]
    return Z


@njit(cache=True)
def _oscillate(Z):
    out = np.empty(Z.shape)
    oscillate_into(Z.ravel(), out.ravel(), np.empty(8, dtype=np.int64))
    return out


@njit(cache=True)
def _maximum(a, b):  # np.maximum: NaN wins
    return a if (a > b or a != a) else b


@njit(cache=True)
def _minimum(a, b):
    return a if (a < b or a != a) else b


@njit(cache=True)
def _rastrigin(Z, raw):
    m, d = Z.shape
    arg = np.empty(Z.shape)
    for i in range(m):
        for j in range(d):
            arg[i, j] = _TWO_PI * Z[i, j]
    cs = np.empty(Z.shape)
    cos_into(arg.ravel(), cs.ravel(), np.empty(8, dtype=np.int64))
    for i in range(m):
        raw[i] = 10.0 * (d - row_sum(cs[i], d)) + dot(Z[i], Z[i], d)


@njit(cache=True)
def _rosenbrock(Z, raw):
    m, d = Z.shape
    a = np.empty(d - 1)
    b = np.empty(d - 1)
    for i in range(m):
        for j in range(d - 1):
            a[j] = Z[i, j] * Z[i, j] - Z[i, j + 1]
            b[j] = Z[i, j] - 1.0
        raw[i] = 100.0 * dot(a, a, d - 1) + dot(b, b, d - 1)


@njit(cache=True)
def _ellipsoid(Z, w, raw):
    m, d = Z.shape
    zz = np.empty(d)
    for i in range(m):
        for j in range(d):
            zz[j] = Z[i, j] * Z[i, j]
        raw[i] = dot(zz, w, d)


@njit(cache=True)
def _asymmetric(Y, ramp):
    m, d = Y.shape
    out = np.empty(Y.shape)
    asymmetric_into(Y.ravel(), ramp, m, d, out.ravel(), np.empty(8, dtype=np.int64))
    return out


# --- the 24 raw functions: raw[i] = f(X[i]) - f_opt as the numpy suite's RAW computes it ---

@njit(cache=True)
def _sphere(X, data, raw):
    d = X.shape[1]
    Z = _minus_xopt(X, data, d)
    for i in range(X.shape[0]):
        raw[i] = dot(Z[i], Z[i], d)


@njit(cache=True)
def _ellipsoid_separable(X, data, raw):
    d = X.shape[1]
    _ellipsoid(_oscillate(_minus_xopt(X, data, d)), _vec(data, d, 0), raw)


@njit(cache=True)
def _rastrigin_separable(X, data, raw):
    d = X.shape[1]
    Z = _asymmetric(_oscillate(_minus_xopt(X, data, d)), _vec(data, d, 1))
    c = _vec(data, d, 0)
    for i in range(X.shape[0]):
        for j in range(d):
            Z[i, j] = c[j] * Z[i, j]
    _rastrigin(Z, raw)


@njit(cache=True)
def _bueche_rastrigin(X, data, raw):
    m, d = X.shape
    Y = _oscillate(_minus_xopt(X, data, d))
    factor = _vec(data, d, 0)
    for i in range(m):
        for j in range(d):
            f = factor[j] * 10.0 if (Y[i, j] > 0.0 and j % 2 == 0) else factor[j]
            Y[i, j] = f * Y[i, j]
    _rastrigin(Y, raw)
    for i in range(m):
        raw[i] = raw[i] + 100.0 * penalty_row(X[i], 5.0)


@njit(cache=True)
def _linear_slope(X, data, raw):
    m, d = X.shape
    s, five = _vec(data, d, 0), _vec(data, d, 1)
    t = np.empty(d)
    for i in range(m):
        for j in range(d):
            t[j] = five[j] - s[j] * X[i, j]
        raw[i] = total(t, d)


@njit(cache=True)
def _attractive_sector(X, data, raw):
    m, d = X.shape
    call = np.empty(8, dtype=np.int64)
    Z = rotate(_minus_xopt(X, data, d), _mat(data, d, 0), call)
    xopt = data[_H:_H + d]
    wz = np.empty(d)
    for i in range(m):
        for j in range(d):
            wz[j] = (10000.0 if xopt[j] * Z[i, j] > 0.0 else 1.0) * Z[i, j]
        raw[i] = dot(wz, Z[i], d)
    o = np.empty(m)
    oscillate_into(raw.copy(), o, call)
    pow_scalar_into(o, 0.9, raw, call)


@njit(cache=True)
def _step_ellipsoid(X, data, raw):
    m, d = X.shape
    call = np.empty(8, dtype=np.int64)
    Y = rotate(_minus_xopt(X, data, d), _mat(data, d, 0), call)
    x1 = Y[:, 0].copy()
    for i in range(m):
        for j in range(d):
            y = Y[i, j]
            Y[i, j] = np.floor(y + 0.5) if abs(y) > 0.5 else np.floor(10.0 * y + 0.5) / 10.0
    Z = rotate(Y, _mat(data, d, 1), call)
    _ellipsoid(Z, _vec(data, d, 0), raw)
    for i in range(m):
        raw[i] = 0.1 * _maximum(abs(x1[i]) * 1e-4, raw[i]) + penalty_row(X[i], 5.0)


@njit(cache=True)
def _rosenbrock_original(X, data, raw):
    m, d = X.shape
    factor = data[2]
    Z = _minus_xopt(X, data, d)
    for i in range(m):
        for j in range(d):
            Z[i, j] = factor * Z[i, j] + 1.0
    _rosenbrock(Z, raw)


@njit(cache=True)
def _rotated_plus_half(X, data):
    Z = rotate(np.ascontiguousarray(X), _mat(data, X.shape[1], 0), np.empty(8, dtype=np.int64))
    for i in range(Z.shape[0]):
        for j in range(Z.shape[1]):
            Z[i, j] = Z[i, j] + 0.5
    return Z


@njit(cache=True)
def _rosenbrock_rotated(X, data, raw):
    _rosenbrock(_rotated_plus_half(X, data), raw)


@njit(cache=True)
def _rotated_oscillated(X, data):
    d = X.shape[1]
    return _oscillate(rotate(_minus_xopt(X, data, d), _mat(data, d, 0),
                             np.empty(8, dtype=np.int64)))


@njit(cache=True)
def _ellipsoid_rotated(X, data, raw):
    _ellipsoid(_rotated_oscillated(X, data), _vec(data, X.shape[1], 0), raw)


@njit(cache=True)
def _discus(X, data, raw):
    m, d = X.shape
    Z = _rotated_oscillated(X, data)
    for i in range(m):
        rest = Z[i, 1:]
        raw[i] = 1e6 * (Z[i, 0] * Z[i, 0]) + dot(rest, rest, d - 1)


@njit(cache=True)
def _bent_cigar(X, data, raw):
    m, d = X.shape
    call = np.empty(8, dtype=np.int64)
    r = _mat(data, d, 0)
    Y = _asymmetric(rotate(_minus_xopt(X, data, d), r, call), _vec(data, d, 0))
    Z = rotate(Y, r, call)
    for i in range(m):
        rest = Z[i, 1:]
        raw[i] = Z[i, 0] * Z[i, 0] + 1e6 * dot(rest, rest, d - 1)


@njit(cache=True)
def _sharp_ridge(X, data, raw):
    m, d = X.shape
    Z = rotate(_minus_xopt(X, data, d), _mat(data, d, 0), np.empty(8, dtype=np.int64))
    for i in range(m):
        rest = Z[i, 1:]
        raw[i] = Z[i, 0] * Z[i, 0] + 100.0 * np.sqrt(dot(rest, rest, d - 1))


@njit(cache=True)
def _different_powers(X, data, raw):
    m, d = X.shape
    call = np.empty(8, dtype=np.int64)
    Z = rotate(_minus_xopt(X, data, d), _mat(data, d, 0), call)
    exps = _vec(data, d, 0)
    base = np.empty(m * d)
    e = np.empty(m * d)
    for i in range(m):
        for j in range(d):
            base[i * d + j] = abs(Z[i, j])
            e[i * d + j] = exps[j]
    p = np.empty(m * d)
    pow_into(base, e, p, call)
    for i in range(m):
        raw[i] = np.sqrt(total(p[i * d:(i + 1) * d], d))


@njit(cache=True)
def _rastrigin_rotated(X, data, raw):
    d = X.shape[1]
    Y = _asymmetric(_rotated_oscillated(X, data), _vec(data, d, 0))
    _rastrigin(rotate(Y, _mat(data, d, 1), np.empty(8, dtype=np.int64)), raw)


@njit(cache=True)
def _weierstrass(X, data, raw):
    m, d = X.shape
    call = np.empty(8, dtype=np.int64)
    Z = rotate(_rotated_oscillated(X, data), _mat(data, d, 1), call)
    ex = _extra(data, d)
    wa, wb = ex[:12], ex[12:24]
    arg = np.empty(m * d * 12)
    for i in range(m):
        for j in range(d):
            base = _TWO_PI * (Z[i, j] + 0.5)
            for k in range(12):
                arg[(i * d + j) * 12 + k] = base * wb[k]
    c = np.empty(m * d * 12)
    cos_into(arg, c, call)
    total = np.empty(m)
    for i in range(m):
        t = c[i * d * 12] * wa[0]
        for q in range(1, d * 12):
            t = t + c[i * d * 12 + q] * wa[q % 12]
        total[i] = t / d - data[2]
    cube = np.empty(m)
    pow_scalar_into(total, 3.0, cube, call)
    for i in range(m):
        raw[i] = 10.0 * cube[i] + 10.0 / d * penalty_row(X[i], 5.0)


@njit(cache=True)
def _schaffers(X, data, raw):
    m, d = X.shape
    call = np.empty(8, dtype=np.int64)
    Y = _asymmetric(rotate(_minus_xopt(X, data, d), _mat(data, d, 0), call), _vec(data, d, 0))
    Z = rotate(Y, _mat(data, d, 1), call)
    scale = _vec(data, d, 1)
    n = m * (d - 1)
    s = np.empty(n)
    for i in range(m):
        for j in range(d):
            Z[i, j] = Z[i, j] * scale[j]
        for j in range(d - 1):
            s[i * (d - 1) + j] = Z[i, j] * Z[i, j] + Z[i, j + 1] * Z[i, j + 1]
    quarter = np.empty(n)
    pow_scalar_into(s, 0.25, quarter, call)
    tenth = np.empty(n)
    pow_scalar_into(s, 0.1, tenth, call)
    for k in range(n):
        tenth[k] = 50.0 * tenth[k]
    sines = np.empty(n)
    sin_into(tenth, sines, call)
    for k in range(n):
        quarter[k] = quarter[k] * (1.0 + sines[k] * sines[k])
    for i in range(m):
        core = total(quarter[i * (d - 1):(i + 1) * (d - 1)], d - 1) / (d - 1.0)
        raw[i] = core * core + 10.0 * penalty_row(X[i], 5.0)


@njit(cache=True)
def _griewank_rosenbrock(X, data, raw):
    m, d = X.shape
    Z = _rotated_plus_half(X, data)
    n = m * (d - 1)
    s = np.empty(n)
    for i in range(m):
        for j in range(d - 1):
            a = Z[i, j] * Z[i, j] - Z[i, j + 1]
            b = 1.0 - Z[i, j]
            s[i * (d - 1) + j] = 100.0 * a * a + b * b
    c = np.empty(n)
    cos_into(s, c, np.empty(8, dtype=np.int64))
    for i in range(m):
        at = i * (d - 1)
        t = s[at] / 4000.0 - c[at]
        for j in range(1, d - 1):
            t = t + (s[at + j] / 4000.0 - c[at + j])
        raw[i] = 10.0 + 10.0 * t / (d - 1.0)


@njit(cache=True)
def _schwefel(X, data, raw):
    m, d = X.shape
    two_signs, twice, cond = _vec(data, d, 0), _vec(data, d, 1), _vec(data, d, 2)
    Z = np.empty(X.shape)
    y = np.empty(d)
    for i in range(m):
        for j in range(d):
            y[j] = two_signs[j] * X[i, j]
        Z[i, 0] = y[0]
        for j in range(1, d):
            Z[i, j] = y[j] + 0.25 * (y[j - 1] - twice[j - 1])
        for j in range(d):
            Z[i, j] = 100.0 * ((Z[i, j] - twice[j]) * cond[j] + twice[j])
    root = np.empty(m * d)
    for i in range(m):
        for j in range(d):
            root[i * d + j] = np.sqrt(abs(Z[i, j]))
    sines = np.empty(m * d)
    sin_into(root, sines, np.empty(8, dtype=np.int64))
    e = np.empty(d)
    t = np.empty(d)
    for i in range(m):
        for j in range(d):
            e[j] = max(abs(Z[i, j]) - 500.0, 0.0)
            t[j] = Z[i, j] * sines[i * d + j]
        raw[i] = 0.01 * ((dot(e, e, d) + 418.9828872724339) - total(t, d) / d)


@njit(cache=True)
def _gallagher(X, data, raw):
    m, d = X.shape
    call = np.empty(8, dtype=np.int64)
    p = int(data[2])
    ex = _extra(data, d)
    local = ex[:p * d].reshape((p, d))
    scales = ex[p * d:2 * p * d].reshape((p, d))
    heights = ex[2 * p * d:2 * p * d + p]
    T = rotate(np.ascontiguousarray(X), _mat(data, d, 0), call)
    w = np.empty(m * p)
    dd = np.empty(d)
    factor = -0.5 / d
    for i in range(m):
        for k in range(p):
            for j in range(d):
                v = T[i, j] - local[k, j]
                dd[j] = v * v
            w[i * p + k] = factor * dot(dd, scales[k], d)
    e = np.empty(m * p)
    exp_into(w, e, call)
    best = np.empty(m)
    for i in range(m):
        b = heights[0] * e[i * p]
        for k in range(1, p):
            b = _maximum(b, heights[k] * e[i * p + k])
        best[i] = 10.0 - _maximum(b, 0.0)
    f = np.empty(m)
    oscillate_into(best, f, call)
    for i in range(m):
        raw[i] = f[i] * f[i] + penalty_row(X[i], 5.0)


@njit(cache=True)
def _katsuura(X, data, raw):
    m, d = X.shape
    Z = rotate(_minus_xopt(X, data, d), _mat(data, d, 0), np.empty(8, dtype=np.int64))
    powers = _extra(data, d)[:32]
    product = np.empty(m)
    t = np.empty(32)
    for i in range(m):
        prod = 1.0
        for j in range(d):
            for k in range(32):
                scaled = powers[k] * Z[i, j]
                t[k] = abs(scaled - np.floor(scaled + 0.5)) / powers[k]
            term = 1.0 + (j + 1.0) * total(t, 32)
            prod = term if j == 0 else prod * term
        product[i] = prod
    powered = np.empty(m)
    pow_scalar_into(product, data[3], powered, np.empty(8, dtype=np.int64))
    for i in range(m):
        raw[i] = data[2] * (-1.0 + powered[i]) + penalty_row(X[i], 5.0)


@njit(cache=True)
def _lunacek(X, data, raw):
    m, d = X.shape
    call = np.empty(8, dtype=np.int64)
    s, mu1 = data[2], data[3]
    signs = _vec(data, d, 0)
    XH = np.empty(X.shape)
    for i in range(m):
        for j in range(d):
            XH[i, j] = 2.0 * X[i, j] * signs[j] - 2.5
    Z = rotate(rotate(XH, _mat(data, d, 0), call), _mat(data, d, 1), call)
    arg = np.empty(m * d)
    for i in range(m):
        for j in range(d):
            arg[i * d + j] = _TWO_PI * Z[i, j]
    c = np.empty(m * d)
    cos_into(arg, c, call)
    a = np.empty(d)
    b = np.empty(d)
    for i in range(m):
        for j in range(d):
            xh = 2.0 * X[i, j] * signs[j]
            a[j] = xh - 2.5
            b[j] = xh - mu1
        waves = total(c[i * d:(i + 1) * d], d)
        raw[i] = (_minimum(dot(a, a, d), 1.0 * d + s * dot(b, b, d))
                  + 10.0 * (d - waves) + 1e4 * penalty_row(X[i], 5.0))


_RAW = {
    1: _sphere, 2: _ellipsoid_separable, 3: _rastrigin_separable, 4: _bueche_rastrigin,
    5: _linear_slope, 6: _attractive_sector, 7: _step_ellipsoid, 8: _rosenbrock_original,
    9: _rosenbrock_rotated, 10: _ellipsoid_rotated, 11: _discus, 12: _bent_cigar,
    13: _sharp_ridge, 14: _different_powers, 15: _rastrigin_rotated, 16: _weierstrass,
    17: _schaffers, 18: _schaffers, 19: _griewank_rosenbrock, 20: _schwefel,
    21: _gallagher, 22: _gallagher, 23: _katsuura, 24: _lunacek,
}


#: the raw function of a copy of :func:`_population_code`: each copy has its own (_population)
RAW: Any = None


def _population_code(m, d, xp, fp, mp, wp, dp):
    """The population objective (objectives.SIGNATURE's parameters) of the raw function
    ``RAW``, a global that :func:`_population` gives each copy of this code."""
    X, F, mask, data = population_views(m, d, xp, fp, mp, dp)
    raw = np.empty(m)
    RAW(X, data, raw)
    errors_into(F, mask, raw, data)


def _population(raw_fn: Any) -> Any:
    """:func:`_population_code` for one raw function, with ``RAW`` = ``raw_fn`` a global of its
    own, not a closure: numba's cache key hashes a closure's cells pickled, and a compiled
    function pickles with a random id, so a closure's objective was compiled again in every
    process (0.2-0.9 s of CPU each, a new cache entry each time) instead of loaded."""
    scope = {**globals(), "RAW": raw_fn}
    name = f"bbob{raw_fn.__name__}"
    population = types.FunctionType(_population_code.__code__, scope, name)
    population.__qualname__ = name  # numba's cache file: one per raw function
    population.__doc__ = _population_code.__doc__
    return population


#: ``bbob:f<k>`` -> its population function (compiled by objectives on first use)
POPULATIONS = {f"bbob:f{k}": _population(fn) for k, fn in _RAW.items()}
