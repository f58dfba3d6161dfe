"""The CEC codes' basic functions compiled, on a population: each gives the numpy suite's
numbers (:mod:`swarmpath.functions.suites.cec_basic`) to the last bit.

Each function takes the population's points Z (m, n), C-contiguous, already shifted, scaled and
rotated as the numpy suite's ``sr`` does (except :func:`bi_rastrigin`, which does its own),
and writes one value per row into ``out`` (m,). The operations are numpy's (:mod:`.suite_ops`):

* every term is computed, rounded, then the terms are added first to last, which is what
  ``sequential`` (a cumsum) and ``np.prod``/``np.cumprod`` do;
* sin, cos, exp and power go through numpy's own loops, on arrays holding every argument of
  the population (numpy's loops compute each element alone: the grouping does not matter, the
  loop does), with a scalar exponent at stride 0 as numpy passes it;
* ``** 2`` is ``x * x`` and ``** 0.5`` is ``sqrt`` (numpy's shortcuts for those exponents);
  ``np.fmod`` is exact (a remainder needs no rounding): numba's gives numpy's number.

Constants that numpy computes from the dimension with ``pow`` (the ellipsoid's weights, the
bi-Rastrigin's s and mu1, Katsuura's exponent) come in ``aux``, packed by :mod:`.cec_data`
with the numpy suite's expressions.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from swarmpath.functions.suites.cec_basic import PI, E
from swarmpath.optimizers.compiled.suite_ops import (
    cos_into,
    exp_into,
    pow_into,
    pow_scalar_into,
    rotate,
    sin_into,
)

TWO_PI = 2.0 * PI  # the numpy suite's ``2.0 * PI * z``: the product of the two first


@njit(cache=True)
def _scratch():
    return np.empty(8, dtype=np.int64)


@njit(cache=True)
def _row_sum(a, at, n):
    """``sequential`` of a[at:at + n]: first to last (0.0 when empty, like numpy's)."""
    if n == 0:
        return 0.0
    t = a[at]
    for j in range(1, n):
        t = t + a[at + j]
    return t


@njit(cache=True)
def bent_cigar(Z, out):
    m, n = Z.shape
    for i in range(m):
        t = Z[i, 0] * Z[i, 0]
        for j in range(1, n):
            t = t + 1e6 * Z[i, j] * Z[i, j]
        out[i] = t


@njit(cache=True)
def discus(Z, out):
    m, n = Z.shape
    for i in range(m):
        t = 1e6 * Z[i, 0] * Z[i, 0]
        for j in range(1, n):
            t = t + Z[i, j] * Z[i, j]
        out[i] = t


@njit(cache=True)
def ellips(Z, weights, out):
    m, n = Z.shape
    for i in range(m):
        t = weights[0] * Z[i, 0] * Z[i, 0]
        for j in range(1, n):
            t = t + weights[j] * Z[i, j] * Z[i, j]
        out[i] = t


@njit(cache=True)
def sum_diff_pow(Z, out):
    m, n = Z.shape
    base = np.empty(m * n)
    e = np.empty(m * n)
    for i in range(m):
        for j in range(n):
            base[i * n + j] = abs(Z[i, j])
            e[i * n + j] = j + 1.0
    p = np.empty(m * n)
    pow_into(base, e, p, _scratch())
    for i in range(m):
        out[i] = _row_sum(p, i * n, n)


@njit(cache=True)
def zakharov(Z, out):
    m, n = Z.shape
    s1 = np.empty(m)
    s2 = np.empty(m)
    for i in range(m):
        t1 = Z[i, 0] * Z[i, 0]
        t2 = (0.5 * 1.0) * Z[i, 0]
        for j in range(1, n):
            t1 = t1 + Z[i, j] * Z[i, j]
            t2 = t2 + (0.5 * (j + 1.0)) * Z[i, j]
        s1[i] = t1
        s2[i] = t2
    fourth = np.empty(m)
    pow_scalar_into(s2, 4.0, fourth, _scratch())
    for i in range(m):
        out[i] = s1[i] + s2[i] * s2[i] + fourth[i]


@njit(cache=True)
def rosenbrock(Z, out):
    m, n = Z.shape
    for i in range(m):
        t = 0.0
        for j in range(n - 1):
            z = Z[i, j] + 1.0
            nxt = Z[i, j + 1] + 1.0
            a = z * z - nxt
            b = z - 1.0
            term = 100.0 * a * a + b * b
            t = term if j == 0 else t + term
        out[i] = t


@njit(cache=True)
def rastrigin(Z, out):
    m, n = Z.shape
    arg = np.empty(m * n)
    for i in range(m):
        for j in range(n):
            arg[i * n + j] = TWO_PI * Z[i, j]
    c = np.empty(m * n)
    cos_into(arg, c, _scratch())
    for i in range(m):
        t = 0.0
        for j in range(n):
            term = Z[i, j] * Z[i, j] - 10.0 * c[i * n + j] + 10.0
            t = term if j == 0 else t + term
        out[i] = t


@njit(cache=True)
def schaffer_f7(Y, out):
    """On the code's unrotated ``y`` (the numpy suite's docstring says why)."""
    m, n = Y.shape
    k = n - 1
    s = np.empty(m * k)
    for i in range(m):
        for j in range(k):
            s[i * k + j] = np.sqrt(Y[i, j] * Y[i, j] + Y[i, j + 1] * Y[i, j + 1])
    call = _scratch()
    p = np.empty(m * k)
    pow_scalar_into(s, 0.2, p, call)
    for q in range(m * k):
        p[q] = 50.0 * p[q]
    t = np.empty(m * k)
    sin_into(p, t, call)
    for i in range(m):
        f = 0.0
        for j in range(k):
            root = np.sqrt(s[i * k + j])
            term = root + root * t[i * k + j] * t[i * k + j]
            f = term if j == 0 else f + term
        out[i] = f * f / (n - 1) / (n - 1)


@njit(cache=True)
def ackley(Z, out):
    m, n = Z.shape
    arg = np.empty(m * n)
    for i in range(m):
        for j in range(n):
            arg[i * n + j] = TWO_PI * Z[i, j]
    call = _scratch()
    c = np.empty(m * n)
    cos_into(arg, c, call)
    e = np.empty(2 * m)
    for i in range(m):
        t = Z[i, 0] * Z[i, 0]
        for j in range(1, n):
            t = t + Z[i, j] * Z[i, j]
        e[i] = -0.2 * np.sqrt(t / n)
        e[m + i] = _row_sum(c, i * n, n) / n
    ex = np.empty(2 * m)
    exp_into(e, ex, call)
    for i in range(m):
        out[i] = E - 20.0 * ex[i] - ex[m + i] + 20.0


@njit(cache=True)
def weierstrass(Z, aux, out):
    """``aux``: a (21), (2 pi) b (21), the value at z = 0.5 per coordinate."""
    m, n = Z.shape
    K = 21
    arg = np.empty(m * n * K)
    for i in range(m):
        for j in range(n):
            half = Z[i, j] + 0.5
            for k in range(K):
                arg[(i * n + j) * K + k] = aux[K + k] * half
    c = np.empty(m * n * K)
    cos_into(arg, c, _scratch())
    for i in range(m):
        total = 0.0
        for j in range(n):
            at = (i * n + j) * K
            per = aux[0] * c[at]
            for k in range(1, K):
                per = per + aux[k] * c[at + k]
            total = per if j == 0 else total + per
        out[i] = total - n * aux[2 * K]


@njit(cache=True)
def griewank(Z, out):
    m, n = Z.shape
    arg = np.empty(m * n)
    for i in range(m):
        for j in range(n):
            arg[i * n + j] = Z[i, j] / np.sqrt(1.0 + j)
    c = np.empty(m * n)
    cos_into(arg, c, _scratch())
    for i in range(m):
        s = Z[i, 0] * Z[i, 0]
        p = c[i * n]
        for j in range(1, n):
            s = s + Z[i, j] * Z[i, j]
            p = p * c[i * n + j]
        out[i] = 1.0 + s / 4000.0 - p


@njit(cache=True)
def schwefel(Z, out):
    """The three branches of the code (z > 500, z < -500, between), each element's sine from
    one call of numpy's loop on the arguments of its own branch."""
    m, n = Z.shape
    factor = np.empty(m * n)
    arg = np.empty(m * n)
    rest = np.empty(m * n)
    outside = np.empty(m * n, dtype=np.bool_)  # beyond +-500: the term has a second part
    for i in range(m):
        for j in range(n):
            q = i * n + j
            z = Z[i, j] + 4.209687462275036e002
            if z > 500.0:
                rh = 500.0 - np.fmod(z, 500.0)
                factor[q] = -rh
                arg[q] = np.sqrt(rh)
                r = (z - 500.0) / 100.0
                rest[q] = r * r / n
                outside[q] = True
            elif z < -500.0:
                az = np.fmod(abs(z), 500.0)
                factor[q] = -(-500.0 + az)
                arg[q] = np.sqrt(500.0 - az)
                r = (z + 500.0) / 100.0
                rest[q] = r * r / n
                outside[q] = True
            else:
                factor[q] = -z
                arg[q] = np.sqrt(abs(z))
                outside[q] = False
    s = np.empty(m * n)
    sin_into(arg, s, _scratch())
    for i in range(m):
        t = 0.0
        for j in range(n):
            q = i * n + j
            term = factor[q] * s[q]
            if outside[q]:
                term = term + rest[q]
            t = term if j == 0 else t + term
        out[i] = t + 4.189828872724338e002 * n


@njit(cache=True)
def katsuura(Z, aux, out):
    """``aux``: the exponent 10 / n^1.2, the scale 10 / n^2, the 32 powers of two."""
    m, n = Z.shape
    factors = np.empty(m * n)
    for i in range(m):
        for j in range(n):
            z = Z[i, j]
            inner = 0.0
            for k in range(32):
                p = aux[2 + k]
                scaled = p * z
                term = abs(scaled - np.floor(scaled + 0.5)) / p
                inner = term if k == 0 else inner + term
            factors[i * n + j] = 1.0 + (j + 1.0) * inner
    powered = np.empty(m * n)
    pow_scalar_into(factors, aux[0], powered, _scratch())
    scale = aux[1]
    for i in range(m):
        product = powered[i * n]
        for j in range(1, n):
            product = product * powered[i * n + j]
        out[i] = product * scale - scale


@njit(cache=True)
def grie_rosen(Z, out):
    m, n = Z.shape
    t = np.empty(m * n)
    for i in range(m):
        for j in range(n):
            z = Z[i, j] + 1.0
            nxt = Z[i, (j + 1) % n] + 1.0
            a = z * z - nxt
            b = z - 1.0
            t[i * n + j] = 100.0 * a * a + b * b
    c = np.empty(m * n)
    cos_into(t, c, _scratch())
    for i in range(m):
        s = 0.0
        for j in range(n):
            q = i * n + j
            term = (t[q] * t[q]) / 4000.0 - c[q] + 1.0
            s = term if j == 0 else s + term
        out[i] = s


@njit(cache=True)
def escaffer6(Z, out):
    m, n = Z.shape
    r = np.empty(m * n)
    root = np.empty(m * n)
    for i in range(m):
        for j in range(n):
            nxt = Z[i, (j + 1) % n]
            v = Z[i, j] * Z[i, j] + nxt * nxt
            r[i * n + j] = v
            root[i * n + j] = np.sqrt(v)
    s = np.empty(m * n)
    sin_into(root, s, _scratch())
    for i in range(m):
        total = 0.0
        for j in range(n):
            q = i * n + j
            t1 = s[q] * s[q]
            t2 = 1.0 + 0.001 * r[q]
            term = 0.5 + (t1 - 0.5) / (t2 * t2)
            total = term if j == 0 else total + term
        out[i] = total


@njit(cache=True)
def _moments(Z, i):
    """(sum of (z - 1)^2, sum of (z - 1)) of row i, first to last."""
    n = Z.shape[1]
    z = Z[i, 0] - 1.0
    r2 = z * z
    s = z
    for j in range(1, n):
        z = Z[i, j] - 1.0
        r2 = r2 + z * z
        s = s + z
    return r2, s


@njit(cache=True)
def happycat(Z, out):
    m, n = Z.shape
    a = np.empty(m)
    rest = np.empty(m)
    for i in range(m):
        r2, s = _moments(Z, i)
        a[i] = abs(r2 - n)
        rest[i] = (0.5 * r2 + s) / n
    p = np.empty(m)
    pow_scalar_into(a, 2.0 * (1.0 / 8.0), p, _scratch())
    for i in range(m):
        out[i] = p[i] + rest[i] + 0.5


@njit(cache=True)
def hgbat(Z, out):
    m, n = Z.shape
    for i in range(m):
        r2, s = _moments(Z, i)
        out[i] = np.sqrt(abs(r2 * r2 - s * s)) + (0.5 * r2 + s) / n + 0.5


@njit(cache=True)
def _minimum(a, b):  # np.minimum: NaN wins
    return a if (a < b or a != a) else b


@njit(cache=True)
def bi_rastrigin(X, o, M, rotated, shifted, aux, out):
    """Lunacek's bi-Rastrigin on the points X (m, n) as the code computes it: its own shift
    (``shifted``) and scale, signs from o[:n], the cosine term rotated by M when ``rotated``;
    ``aux``: s and mu1 for this n."""
    m, n = X.shape
    s, mu1 = aux[0], aux[1]
    T = np.empty((m, n))
    for i in range(m):
        for j in range(n):
            y = X[i, j] - o[j] if shifted else X[i, j]
            y = y * (10.0 / 100.0)
            t = 2.0 * y
            T[i, j] = t * -1.0 if o[j] < 0.0 else t
    W = rotate(T, M, _scratch()) if rotated else T
    arg = np.empty(m * n)
    for i in range(m):
        for j in range(n):
            arg[i * n + j] = TWO_PI * W[i, j]
    c = np.empty(m * n)
    cos_into(arg, c, _scratch())
    for i in range(m):
        tmp1 = 0.0
        tmp2 = 0.0
        for j in range(n):
            t = T[i, j] + 2.5
            a = t - 2.5
            b = t - mu1
            tmp1 = a * a if j == 0 else tmp1 + a * a
            tmp2 = b * b if j == 0 else tmp2 + b * b
        tmp2 = tmp2 * s + 1.0 * n
        waves = _row_sum(c, i * n, n)
        out[i] = _minimum(tmp1, tmp2) + 10.0 * (n - waves)


@njit(cache=True)
def levy(Z, shift, out):
    """``shift``: the code's w = 1 + (z - shift) / 4 (CEC 2017: 1, CEC 2022: 0)."""
    m, n = Z.shape
    k = n - 1
    arg = np.empty(2 * m + m * k)
    for i in range(m):
        w0 = 1.0 + (Z[i, 0] - shift) / 4.0
        last = 1.0 + (Z[i, n - 1] - shift) / 4.0
        arg[i] = PI * w0
        arg[m + i] = TWO_PI * last
        for j in range(k):
            w = 1.0 + (Z[i, j] - shift) / 4.0
            arg[2 * m + i * k + j] = PI * w + 1.0
    s = np.empty(arg.size)
    sin_into(arg, s, _scratch())
    for i in range(m):
        last = 1.0 + (Z[i, n - 1] - shift) / 4.0
        term1 = s[i] * s[i]
        term3 = (last - 1.0) * (last - 1.0) * (1.0 + s[m + i] * s[m + i])
        inner = 0.0
        for j in range(k):
            w = 1.0 + (Z[i, j] - shift) / 4.0
            sj = s[2 * m + i * k + j]
            term = (w - 1.0) * (w - 1.0) * (1.0 + 10.0 * (sj * sj))
            inner = term if j == 0 else inner + term
        out[i] = term1 + inner + term3
