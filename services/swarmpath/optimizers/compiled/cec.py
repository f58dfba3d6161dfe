"""The CEC 2017 and CEC 2022 functions as compiled population objectives (``cec2017:F1`` ..
``cec2017:F30``, ``cec2022:F1`` .. ``cec2022:F12``).

One compiled function serves them all: the definition (plain, hybrid or composition, its basic
functions, scales, shuffle, weights) is data, packed from the numpy suite's own tables by
:mod:`.cec_data`, so the compiled code is the numpy suite's operations
(:mod:`swarmpath.functions.suites.cec`) once, not once per function: ``sr`` (shift, scale,
rotation by numpy's matmul), the hybrids' shuffle and groups, cf_cal's weights. Its numbers are
the numpy suite's to the last bit (tests/test_compiled_suites.py).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from swarmpath.functions.suites.cec_basic import INF
from swarmpath.optimizers.compiled import cec_basic as cb
from swarmpath.optimizers.compiled.cec_data import APPLICATION, CODES, HEADER, RECORD
from swarmpath.optimizers.compiled.cec_data import data_for as data_for
from swarmpath.optimizers.compiled.suite_ops import (
    errors_into,
    exp_into,
    population_views,
    rotate,
)

_BENT_CIGAR, _SUM_DIFF_POW, _ZAKHAROV = CODES["bent_cigar"], CODES["sum_diff_pow"], CODES[
    "zakharov"]
_ROSENBROCK, _RASTRIGIN, _SCHAFFER = CODES["rosenbrock"], CODES["rastrigin"], CODES[
    "schaffer_f7"]
_BI_RASTRIGIN, _LEVY, _SCHWEFEL = CODES["bi_rastrigin"], CODES["levy"], CODES["schwefel"]
_ELLIPS, _DISCUS, _ACKLEY = CODES["ellips"], CODES["discus"], CODES["ackley"]
_WEIERSTRASS, _GRIEWANK, _KATSUURA = CODES["weierstrass"], CODES["griewank"], CODES[
    "katsuura"]
_GRIE_ROSEN, _ESCAFFER6, _HAPPYCAT = CODES["grie_rosen"], CODES["escaffer6"], CODES[
    "happycat"]
_HGBAT = CODES["hgbat"]


@njit(cache=True)
def _block(data, at, n):
    """data[at:at + n] (empty for an absent block, at = -1)."""
    start = max(int(at), 0)
    return data[start:start + (n if at >= 0 else 0)]


@njit(cache=True)
def _matrix(data, at, d):
    """The (d, d) block at ``at`` (a 1 x 1 placeholder for an absent one)."""
    if at < 0:
        return np.zeros((1, 1))
    start = int(at)
    return data[start:start + d * d].reshape((d, d))


@njit(cache=True)
def _aux(data, app):
    """The constants of an application (up to the rest of the array; empty if none)."""
    at = data[app + 3]
    return data[int(at):] if at >= 0 else data[0:0]


@njit(cache=True)
def _basic(code, Z, aux, levy_shift, out):
    """Basic function ``code`` of the points Z (m, n) into out (m,) (all but Schaffer F7 and
    the bi-Rastrigin, which read other inputs)."""
    if code == _BENT_CIGAR:
        cb.bent_cigar(Z, out)
    elif code == _SUM_DIFF_POW:
        cb.sum_diff_pow(Z, out)
    elif code == _ZAKHAROV:
        cb.zakharov(Z, out)
    elif code == _ROSENBROCK:
        cb.rosenbrock(Z, out)
    elif code == _RASTRIGIN:
        cb.rastrigin(Z, out)
    elif code == _LEVY:
        cb.levy(Z, levy_shift, out)
    elif code == _SCHWEFEL:
        cb.schwefel(Z, out)
    elif code == _ELLIPS:
        cb.ellips(Z, aux, out)
    elif code == _DISCUS:
        cb.discus(Z, out)
    elif code == _ACKLEY:
        cb.ackley(Z, out)
    elif code == _WEIERSTRASS:
        cb.weierstrass(Z, aux, out)
    elif code == _GRIEWANK:
        cb.griewank(Z, out)
    elif code == _KATSUURA:
        cb.katsuura(Z, aux, out)
    elif code == _GRIE_ROSEN:
        cb.grie_rosen(Z, out)
    elif code == _ESCAFFER6:
        cb.escaffer6(Z, out)
    elif code == _HAPPYCAT:
        cb.happycat(Z, out)
    elif code == _HGBAT:
        cb.hgbat(Z, out)
    else:
        raise ValueError("unknown CEC basic function code")


@njit(cache=True)
def _shifted(X, o, rate):
    """(X - o) * rate, rounded after each step as numpy's two operations."""
    m, d = X.shape
    Y = np.empty((m, d))
    for i in range(m):
        for j in range(d):
            Y[i, j] = (X[i, j] - o[j]) * rate
    return Y


@njit(cache=True)
def _columns(P, start, size, rate):
    """P[:, start:start + size] * rate as a new contiguous array (the numpy suite's ``sr`` of a
    hybrid's group: a copy, scaled)."""
    m = P.shape[0]
    out = np.empty((m, size))
    for i in range(m):
        for j in range(size):
            out[i, j] = P[i, start + j] * rate
    return out


@njit(cache=True)
def _plain(X, data, record, levy_shift, out):
    """A basic function of x, shifted by o, scaled and rotated as ``sr`` does (``cec.simple``)."""
    d = X.shape[1]
    app = int(record[3])
    code, rate = int(data[app]), data[app + 2]
    o = _block(data, record[1], d)
    M = _matrix(data, record[2], d)
    rotated = record[2] >= 0
    if code == _BI_RASTRIGIN:
        cb.bi_rastrigin(X, o, M, rotated, True, _aux(data, app), out)
        return
    Y = _shifted(X, o, rate)
    if code == _SCHAFFER:  # the code's y: shifted and scaled, not rotated
        cb.schaffer_f7(Y, out)
        return
    Z = rotate(Y, M, np.empty(8, dtype=np.int64)) if rotated else Y
    _basic(code, Z, _aux(data, app), levy_shift, out)


@njit(cache=True)
def _hybrid(X, data, record, levy_shift, out):
    """``cec.hybrid``: z = M (x - o), shuffled, cut into groups, one basic function a group."""
    m, d = X.shape
    o = _block(data, record[1], d)
    Z = rotate(_shifted(X, o, 1.0), _matrix(data, record[2], d), np.empty(8, dtype=np.int64))
    shuffle = _block(data, record[5], d)
    P = np.empty((m, d))
    for i in range(m):
        for j in range(d):
            P[i, j] = Z[i, int(shuffle[j])]
    for i in range(m):
        out[i] = 0.0
    value = np.empty(m)
    start = 0
    for g in range(int(record[4])):
        app = int(record[3]) + g * APPLICATION
        code, size, rate = int(data[app]), int(data[app + 1]), data[app + 2]
        if code == _SCHAFFER:  # reads the code's global y: the shuffled vector's head
            cb.schaffer_f7(_columns(P, 0, size, 1.0), value)
        elif code == _BI_RASTRIGIN:
            cb.bi_rastrigin(_columns(P, start, size, 1.0), o, np.zeros((1, 1)), False, False,
                            _aux(data, app), value)
        else:
            _basic(code, _columns(P, start, size, rate), _aux(data, app), levy_shift, value)
        for i in range(m):
            out[i] = out[i] + value[i]
        start += size


@njit(cache=True)
def _component(X, data, record, levy_shift, out):
    if record[0] != 0.0:
        _hybrid(X, data, record, levy_shift, out)
    else:
        _plain(X, data, record, levy_shift, out)


@njit(cache=True)
def _maximum(a, b):  # np.maximum: NaN wins
    return a if (a > b or a != a) else b


@njit(cache=True)
def _composition(X, data, k, levy_shift, out):
    """``cec._composition``: the components' scaled values plus their biases, weighted by
    cf_cal's weights (``cec_basic.composition_weights``)."""
    m, d = X.shape
    fits = np.empty((k, m))
    value = np.empty(m)
    sq = np.empty(k * m)
    arg = np.empty(k * m)
    zero = np.empty(k * m, dtype=np.bool_)
    for c in range(k):
        record = data[HEADER + c * RECORD:HEADER + (c + 1) * RECORD]
        _component(X, data, record, levy_shift, value)
        for i in range(m):
            v = record[7] * value[i] / record[8] if record[6] != 0.0 else value[i]
            fits[c, i] = v + record[9]
        o = _block(data, record[1], d)
        for i in range(m):
            diff = X[i, 0] - o[0]
            w = diff * diff
            for j in range(1, d):
                diff = X[i, j] - o[j]
                w = w + diff * diff
            q = c * m + i
            zero[q] = w == 0.0
            safe = 1.0 if zero[q] else w
            sq[q] = np.sqrt(1.0 / safe)
            arg[q] = -safe / 2.0 / d / record[10]
    ex = np.empty(k * m)
    exp_into(arg, ex, np.empty(8, dtype=np.int64))
    W = np.empty(k)
    for i in range(m):
        for c in range(k):
            q = c * m + i
            W[c] = INF if zero[q] else sq[q] * ex[q]
        total = W[0]
        top = W[0]
        for c in range(1, k):
            total = total + W[c]
            top = _maximum(top, W[c])
        if top == 0.0:
            for c in range(k):
                W[c] = 1.0
            total = float(k)
        f = 0.0
        for c in range(k):
            term = W[c] / total * fits[c, i]
            f = term if c == 0 else f + term
        out[i] = f


@njit(cache=True)
def values_into(X, data, out):
    """f(x) - bias of every row of X (m, D) (the value before the code adds F<k>'s bias)."""
    if data[2] != 0.0:
        _composition(X, data, int(data[3]), data[4], out)
    else:
        _component(X, data, data[HEADER:HEADER + RECORD], data[4], out)


def _cec_population(m, d, xp, fp, mp, wp, dp):
    """The population objective (objectives.SIGNATURE's parameters) of every CEC function."""
    X, F, mask, data = population_views(m, d, xp, fp, mp, dp)
    raw = np.empty(m)
    values_into(X, data, raw)
    errors_into(F, mask, raw, data)


#: suite -> its function numbers with a compiled objective
COMPILED = {"cec2017": tuple(range(1, 31)), "cec2022": tuple(range(1, 13))}

#: ``cec20xx:F<k>`` -> its population function (one for all: compiled once, on first use)
POPULATIONS = {f"{suite}:F{k}": _cec_population
               for suite, numbers in COMPILED.items() for k in numbers}
