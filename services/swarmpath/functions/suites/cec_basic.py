"""The basic functions of the CEC 2017 and CEC 2022 codes, vectorized over points (..., n).

Each function repeats what the organisers' C code computes (``cec17_test_func.cpp``,
``cec22_test_func.cpp``), including what the code does differently from the definitions
document, because the competitions' published results were computed by that code
(docs/functions.md lists the differences):

* ``sr`` (shift, scale, rotate): z = M ((x - o) * rate); the code keeps the unrotated
  (x - o) * rate in a global ``y``, which Schaffer's F7 reads instead of z: the code's F7 is
  not rotated, and inside a hybrid it reads the first entries of the whole shuffled vector.
* Non-continuous Rastrigin: the code rounds ``y`` before ``sr`` overwrites it, so it is
  Rastrigin.
* Levy: CEC 2017 uses w = 1 + (z - 1)/4, CEC 2022 w = 1 + z/4 (``levy_shift``).

Sums are added in the code's order (:mod:`.sums`). ``n`` is the number of coordinates of the
(sub)vector, which a hybrid function's parts see as their dimension.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from swarmpath.functions.suites.sums import rotate, sequential

Array = NDArray[np.float64]

E = 2.7182818284590452353602874713526625
PI = 3.1415926535897932384626433832795029
INF = 1.0e99

#: sr's scale per basic function (the code's sh_rate: the search range shrunk to the
#: function's own)
RATE = {
    "rosenbrock": 2.048 / 100.0, "weierstrass": 0.5 / 100.0, "griewank": 600.0 / 100.0,
    "rastrigin": 5.12 / 100.0, "step_rastrigin": 5.12 / 100.0, "schwefel": 1000.0 / 100.0,
    "katsuura": 5.0 / 100.0, "grie_rosen": 5.0 / 100.0, "happycat": 5.0 / 100.0,
    "hgbat": 5.0 / 100.0,
}


def sr(x: Array, o: Array | None, m: Array | None, rate: float) -> tuple[Array, Array]:
    """(z, y): y = (x - o) * rate (no shift when ``o`` is None), z = m y (y when ``m`` is
    None)."""
    y = (x - o[: x.shape[-1]]) if o is not None else np.array(x, dtype=float)
    y = y * rate
    return (rotate(y, m) if m is not None else y), y


def _ramp(n: int) -> Array:
    return np.arange(n, dtype=float)


def ellips(z: Array) -> Array:
    n = z.shape[-1]
    return sequential(10.0 ** (6.0 * _ramp(n) / (n - 1)) * z * z)


def bent_cigar(z: Array) -> Array:
    return sequential(np.concatenate(
        [z[..., :1] * z[..., :1], 1e6 * z[..., 1:] * z[..., 1:]], axis=-1))


def discus(z: Array) -> Array:
    return sequential(np.concatenate(
        [1e6 * z[..., :1] * z[..., :1], z[..., 1:] * z[..., 1:]], axis=-1))


def sum_diff_pow(z: Array) -> Array:
    return sequential(np.abs(z) ** (_ramp(z.shape[-1]) + 1.0))


def zakharov(z: Array) -> Array:
    n = z.shape[-1]
    s1 = sequential(z ** 2)
    s2 = sequential(0.5 * (_ramp(n) + 1.0) * z)
    return s1 + s2 ** 2 + s2 ** 4


def levy(z: Array, levy_shift: float) -> Array:
    w = 1.0 + (z - levy_shift) / 4.0
    term1 = np.sin(PI * w[..., 0]) ** 2
    last = w[..., -1]
    term3 = (last - 1.0) ** 2 * (1.0 + np.sin(2.0 * PI * last) ** 2)
    wi = w[..., :-1]
    inner = sequential((wi - 1.0) ** 2 * (1.0 + 10.0 * np.sin(PI * wi + 1.0) ** 2))
    return term1 + inner + term3


def rosenbrock(z: Array) -> Array:
    z = z + 1.0
    a = z[..., :-1] * z[..., :-1] - z[..., 1:]
    b = z[..., :-1] - 1.0
    return sequential(100.0 * a * a + b * b)


def schaffer_f7(y: Array) -> Array:
    """On the code's ``y`` (see the module docstring), n = y.shape[-1]."""
    n = y.shape[-1]
    s = (y[..., :-1] * y[..., :-1] + y[..., 1:] * y[..., 1:]) ** 0.5
    t = np.sin(50.0 * s ** 0.2)
    f = sequential(s ** 0.5 + s ** 0.5 * t * t)
    return f * f / (n - 1) / (n - 1)


def ackley(z: Array) -> Array:
    n = z.shape[-1]
    s1 = -0.2 * np.sqrt(sequential(z * z) / n)
    s2 = sequential(np.cos(2.0 * PI * z)) / n
    return E - 20.0 * np.exp(s1) - np.exp(s2) + 20.0


_WK = np.arange(21, dtype=float)
_WA = 0.5 ** _WK
_WB = 3.0 ** _WK
_W_AT_HALF = float(sequential(_WA * np.cos(2.0 * PI * _WB * 0.5)))


def weierstrass(z: Array) -> Array:
    n = z.shape[-1]
    terms = _WA * np.cos(2.0 * PI * _WB * (z[..., None] + 0.5))
    per = sequential(terms)
    return sequential(per) - n * _W_AT_HALF


def griewank(z: Array) -> Array:
    s = sequential(z * z)
    p = np.prod(np.cos(z / np.sqrt(1.0 + _ramp(z.shape[-1]))), axis=-1)
    return 1.0 + s / 4000.0 - p


def rastrigin(z: Array) -> Array:
    return sequential(z * z - 10.0 * np.cos(2.0 * PI * z) + 10.0)


def schwefel(z: Array) -> Array:
    n = z.shape[-1]
    z = z + 4.209687462275036e002
    high = z > 500.0
    low = z < -500.0
    mid = ~(high | low)
    term = np.zeros_like(z)
    rh = 500.0 - np.fmod(np.where(high, z, 0.0), 500.0)
    term = np.where(high, -rh * np.sin(rh ** 0.5) + ((z - 500.0) / 100.0) ** 2 / n, term)
    az = np.fmod(np.abs(np.where(low, z, 0.0)), 500.0)
    term = np.where(low, -(-500.0 + az) * np.sin((500.0 - az) ** 0.5)
                    + ((z + 500.0) / 100.0) ** 2 / n, term)
    term = np.where(mid, -z * np.sin(np.abs(z) ** 0.5), term)
    return sequential(term) + 4.189828872724338e002 * n


def katsuura(z: Array) -> Array:
    n = z.shape[-1]
    powers = 2.0 ** np.arange(1, 33)
    scaled = powers * z[..., None]
    inner = sequential(np.abs(scaled - np.floor(scaled + 0.5)) / powers)
    factors = (1.0 + (_ramp(n) + 1.0) * inner) ** (10.0 / (1.0 * n) ** 1.2)
    product = np.cumprod(factors, axis=-1)[..., -1]
    scale = 10.0 / n / n
    return product * scale - scale


def bi_rastrigin(x: Array, o: Array, m: Array | None, shifted: bool) -> Array:
    """Lunacek's bi-Rastrigin as the code computes it: its own shift/scale (0.1), signs from
    the first n entries of ``o``, rotation of the cosine term only when ``m`` is given."""
    n = x.shape[-1]
    mu0, d = 2.5, 1.0
    s = 1.0 - 1.0 / (2.0 * (n + 20.0) ** 0.5 - 8.2)
    mu1 = -(((mu0 * mu0 - d) / s) ** 0.5)
    y = (x - o[:n]) if shifted else np.array(x, dtype=float)
    y = y * (10.0 / 100.0)
    t = 2.0 * y
    t = np.where(o[:n] < 0.0, t * -1.0, t)
    z = t
    t = t + mu0
    tmp1 = sequential((t - mu0) * (t - mu0))
    tmp2 = sequential((t - mu1) * (t - mu1)) * s + d * n
    waves = sequential(np.cos(2.0 * PI * (rotate(z, m) if m is not None else z)))
    return np.minimum(tmp1, tmp2) + 10.0 * (n - waves)


def grie_rosen(z: Array) -> Array:
    z = z + 1.0
    nxt = np.concatenate([z[..., 1:], z[..., :1]], axis=-1)
    a = z * z - nxt
    b = z - 1.0
    t = 100.0 * a * a + b * b
    return sequential((t * t) / 4000.0 - np.cos(t) + 1.0)


def escaffer6(z: Array) -> Array:
    nxt = np.concatenate([z[..., 1:], z[..., :1]], axis=-1)
    r = z * z + nxt * nxt
    t1 = np.sin(np.sqrt(r)) ** 2
    t2 = 1.0 + 0.001 * r
    return sequential(0.5 + (t1 - 0.5) / (t2 * t2))


def happycat(z: Array) -> Array:
    n = z.shape[-1]
    z = z - 1.0
    r2 = sequential(z * z)
    total = sequential(z)
    return np.abs(r2 - n) ** (2.0 * (1.0 / 8.0)) + (0.5 * r2 + total) / n + 0.5


def hgbat(z: Array) -> Array:
    n = z.shape[-1]
    z = z - 1.0
    r2 = sequential(z * z)
    total = sequential(z)
    return np.abs(r2 ** 2.0 - total ** 2.0) ** (2.0 * (1.0 / 4.0)) + (0.5 * r2 + total) / n + 0.5


def composition_weights(x: Array, o: Array, deltas: tuple[float, ...]) -> Array:
    """cf_cal's weights w_i / sum w (..., k) at x for optima o (k, >= n)."""
    n = x.shape[-1]
    k = len(deltas)
    ws = []
    for i in range(k):
        diff = x - o[i, :n]
        w = sequential(diff ** 2.0)
        nonzero = w != 0.0
        safe = np.where(nonzero, w, 1.0)
        value = (1.0 / safe) ** 0.5 * np.exp(-safe / 2.0 / n / deltas[i] ** 2.0)
        ws.append(np.where(nonzero, value, INF))
    w = np.stack(ws, axis=-1)
    total = sequential(w)
    none = np.max(w, axis=-1) == 0.0
    w = np.where(none[..., None], 1.0, w)
    total = np.where(none, float(k), total)
    return np.asarray(w / total[..., None])


def group_sizes(n: int, shares: tuple[float, ...]) -> list[int]:
    """A hybrid function's group sizes: ceil(share n) for all groups but the last."""
    sizes = [math.ceil(p * n) for p in shares[:-1]]
    return [*sizes, n - sum(sizes)]
