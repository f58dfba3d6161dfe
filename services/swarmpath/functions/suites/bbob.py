"""The 24 noiseless BBOB functions with COCO's instances (``bbob:f1`` .. ``bbob:f24``).

Definitions: Hansen, Finck, Ros, Auger, "Real-parameter black-box optimization benchmarking
2009: noiseless functions definitions", INRIA RR-6829 (updated 2010), as COCO 2.x computes
them (its ``suite_bbob``): where COCO's code differs from the report (f4's optimum with
non-negative odd coordinates, f5 without the clipping of x, f19 and f9 rotated about 0.5 instead
of shifted), the code is followed, since the instances are COCO's. Any dimension d >= 2; the
box is [-5, 5]^d. ``values(number, X, dim, instance)`` is f(X) with f_opt included.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmpath.functions.suites import bbob_instances as gen
from swarmpath.functions.suites.bbob_parts import (
    asymmetric,
    conditioning,
    ellipsoid,
    oscillate,
    penalty,
    rastrigin,
    rosenbrock,
    rotate,
    sequential,
)

Array = NDArray[np.float64]
Data = dict[str, Any]

NAMES: dict[int, str] = {
    1: "sphere", 2: "separable ellipsoid", 3: "Rastrigin", 4: "Bueche-Rastrigin",
    5: "linear slope", 6: "attractive sector", 7: "step ellipsoid", 8: "Rosenbrock",
    9: "rotated Rosenbrock", 10: "ellipsoid", 11: "discus", 12: "bent cigar", 13: "sharp ridge",
    14: "different powers", 15: "rotated Rastrigin", 16: "Weierstrass",
    17: "Schaffer F7, condition 10", 18: "Schaffer F7, condition 1000",
    19: "composite Griewank-Rosenbrock F8F2", 20: "Schwefel x sin(x)",
    21: "Gallagher, 101 peaks", 22: "Gallagher, 21 peaks", 23: "Katsuura",
    24: "Lunacek bi-Rastrigin",
}
BOUND = 5.0
SCHWEFEL_XOPT = 0.5 * 4.2096874637
SCHWEFEL_BEST = 0.5 * 4.2096874633


def _common(fid: int, dim: int, instance: int) -> Data:
    seed = gen.seed_of(fid, instance)
    return {"seed": seed, "fopt": gen.f_opt(fid, instance), "xopt": gen.x_opt(dim, seed)}


def _two_rotations(data: Data, dim: int) -> Data:
    data["r1"] = gen.rotation(dim, data["seed"] + 1000000)
    data["r2"] = gen.rotation(dim, data["seed"])
    return data


def _sandwich(data: Data, dim: int, alpha: float) -> Array:
    """r1 Lambda^alpha r2 (COCO's M of f6, f13, f23), summed over k in order."""
    left = data["r1"] * conditioning(dim, alpha)
    m = np.zeros((dim, dim))
    for k in range(dim):
        m += left[:, k, None] * data["r2"][k]
    return m


@lru_cache(maxsize=512)
def instance_data(fid: int, dim: int, instance: int) -> Data:
    """Everything instance ``instance`` of f``fid`` in ``dim`` dimensions needs (cached)."""
    data = _common(fid, dim, instance)
    seed = data["seed"]
    if fid == 4:
        data["xopt"][::2] = np.abs(data["xopt"][::2])
    elif fid == 5:
        data["xopt"] = np.where(data["xopt"] > 0.0, BOUND, -BOUND)
    elif fid in (6, 13, 23):
        _two_rotations(data, dim)
        data["m"] = _sandwich(data, dim, {6: 10.0, 13: 10.0, 23: 100.0}[fid])
    elif fid in (7, 15, 16, 17, 18, 24):
        _two_rotations(data, dim)
        if fid in (15, 16):
            data["m"] = _sandwich(data, dim, 10.0 if fid == 15 else 0.01)
    elif fid == 8:
        data["xopt"] = 0.75 * data["xopt"]
    elif fid in (9, 19):
        r = gen.rotation(dim, seed)
        data["m"] = max(1.0, math.sqrt(dim) / 8.0) * r
        data["xopt"] = r.sum(axis=0) / (2.0 * max(1.0, math.sqrt(dim) / 8.0))
    elif fid in (10, 11, 12, 14):
        data["r1"] = gen.rotation(dim, seed + 1000000)
        if fid == 12:
            data["xopt"] = gen.x_opt(dim, seed + 1000000)
    elif fid == 20:
        signs = np.where(gen.uniform(dim, seed) - 0.5 < 0.0, -1.0, 1.0)
        data["xopt"] = SCHWEFEL_XOPT * signs
        data["signs"] = signs
        data["best"] = SCHWEFEL_BEST * signs  # COCO reports this one (same f, 2e-10 apart)
    elif fid in (21, 22):
        _gallagher(data, dim, 101 if fid == 21 else 21)
    if fid == 24:
        data["xopt"] = np.where(gen.gauss(dim, seed) < 0.0, -1.25, 1.25)
    return data


def _gallagher(data: Data, dim: int, peaks: int) -> None:
    seed = data["seed"]
    r = gen.rotation(dim, seed)
    first, b, c = (math.sqrt(1000.0), 10.0, 5.0) if peaks == 101 else (1000.0, 9.8, 4.9)
    order = np.argsort(gen.uniform(peaks - 1, seed), kind="stable")
    condition = np.empty(peaks)
    condition[0] = first
    condition[1:] = 1000.0 ** (order / (peaks - 2.0))
    heights = np.empty(peaks)
    heights[0] = 10.0
    heights[1:] = np.arange(peaks - 1) / (peaks - 2.0) * (9.1 - 1.1) + 1.1
    scales = np.empty((peaks, dim))
    for i in range(peaks):
        ranks = np.argsort(gen.uniform(dim, seed + 1000 * i), kind="stable")
        scales[i] = condition[i] ** (ranks / (dim - 1.0) - 0.5)
    u = gen.uniform(dim * peaks, seed)
    data["xopt"] = 0.8 * (b * u[:dim] - c)
    local = (b * u.reshape(peaks, dim) - c) @ r.T  # row j: r @ (b u_j - c)
    local[0] *= 0.8
    data.update(r=r, local=local, scales=scales, heights=heights)


def _obj_oscillate(f: Array) -> Array:
    return oscillate(f)


def _sphere(x: Array, d: Data) -> Array:
    z = x - d["xopt"]
    return np.einsum("...i,...i->...", z, z)


def _ellipsoid_separable(x: Array, d: Data) -> Array:
    return ellipsoid(oscillate(x - d["xopt"]))


def _rastrigin_separable(x: Array, d: Data) -> Array:
    dim = x.shape[-1]
    z = conditioning(dim, 10.0) * asymmetric(oscillate(x - d["xopt"]), 0.2)
    return rastrigin(z)


def _bueche_rastrigin(x: Array, d: Data) -> Array:
    dim = x.shape[-1]
    y = oscillate(x - d["xopt"])
    factor = np.broadcast_to(10.0 ** (0.5 * np.arange(dim) / (dim - 1.0)), y.shape).copy()
    odd = np.zeros(dim, dtype=bool)
    odd[::2] = True
    factor[(y > 0.0) & odd] *= 10.0
    return rastrigin(factor * y) + 100.0 * penalty(x)


def _linear_slope(x: Array, d: Data) -> Array:
    dim = x.shape[-1]
    s = np.sign(d["xopt"]) * math.sqrt(100.0) ** (np.arange(dim) / (dim - 1.0))
    return np.einsum("...i->...", 5.0 * np.abs(s) - s * x)


def _attractive_sector(x: Array, d: Data) -> Array:
    z = rotate(x - d["xopt"], d["m"])
    w = np.where(d["xopt"] * z > 0.0, 100.0 * 100.0, 1.0)
    raw = np.einsum("...i,...i->...", w * z, z)
    return np.asarray(_obj_oscillate(raw) ** 0.9)


def _step_ellipsoid(x: Array, d: Data) -> Array:
    dim = x.shape[-1]
    c1 = np.sqrt((100.0 / 10.0) ** (np.arange(dim) / (dim - 1.0)))
    y = rotate(x - d["xopt"], c1[:, None] * d["r2"])
    x1 = y[..., 0]
    y = np.where(np.abs(y) > 0.5, np.floor(y + 0.5), np.floor(10.0 * y + 0.5) / 10.0)
    z = rotate(y, d["r1"])
    core = ellipsoid(z, 100.0)
    return 0.1 * np.maximum(np.abs(x1) * 1e-4, core) + penalty(x)


def _rosenbrock(x: Array, d: Data) -> Array:
    factor = max(1.0, math.sqrt(x.shape[-1]) / 8.0)
    return rosenbrock(factor * (x - d["xopt"]) + 1.0)


def _rosenbrock_rotated(x: Array, d: Data) -> Array:
    return rosenbrock(rotate(x, d["m"], 0.5))


def _ellipsoid_rotated(x: Array, d: Data) -> Array:
    return ellipsoid(oscillate(rotate(x - d["xopt"], d["r1"])))


def _discus(x: Array, d: Data) -> Array:
    z = oscillate(rotate(x - d["xopt"], d["r1"]))
    rest = z[..., 1:]
    return 1e6 * z[..., 0] ** 2 + np.einsum("...i,...i->...", rest, rest)


def _bent_cigar(x: Array, d: Data) -> Array:
    r = d["r1"]
    z = rotate(asymmetric(rotate(x - d["xopt"], r), 0.5), r)
    rest = z[..., 1:]
    return z[..., 0] ** 2 + 1e6 * np.einsum("...i,...i->...", rest, rest)


def _sharp_ridge(x: Array, d: Data) -> Array:
    z = rotate(x - d["xopt"], d["m"])
    rest = z[..., 1:]
    return z[..., 0] ** 2 + 100.0 * np.sqrt(np.einsum("...i,...i->...", rest, rest))


def _different_powers(x: Array, d: Data) -> Array:
    dim = x.shape[-1]
    z = rotate(x - d["xopt"], d["r1"])
    return np.sqrt(np.einsum("...i->...", np.abs(z) ** (2.0 + 4.0 * np.arange(dim) / (dim - 1))))


def _rastrigin_rotated(x: Array, d: Data) -> Array:
    x.shape[-1]
    y = asymmetric(oscillate(rotate(x - d["xopt"], d["r1"])), 0.2)
    return rastrigin(rotate(y, d["m"]))


_W_K = np.arange(12)
_W_A = 0.5 ** _W_K
_W_B = 3.0 ** _W_K
_W_F0 = float(np.sum(_W_A * np.cos(2.0 * math.pi * _W_B * 0.5)))


def _weierstrass(x: Array, d: Data) -> Array:
    dim = x.shape[-1]
    y = oscillate(rotate(x - d["xopt"], d["r1"]))
    z = rotate(y, d["m"])
    terms = np.cos(2.0 * math.pi * (z[..., None] + 0.5) * _W_B) * _W_A
    total = sequential(terms.reshape((*terms.shape[:-2], -1)))
    return 10.0 * (total / dim - _W_F0) ** 3 + 10.0 / dim * penalty(x)


def _schaffers(condition: float) -> Callable[[Array, Data], Array]:
    def f(x: Array, d: Data) -> Array:
        dim = x.shape[-1]
        y = asymmetric(rotate(x - d["xopt"], d["r1"]), 0.5)
        z = rotate(y, d["r2"]) * math.sqrt(condition) ** (np.arange(dim) / (dim - 1.0))
        s = z[..., :-1] ** 2 + z[..., 1:] ** 2
        core = np.einsum("...i->...", s ** 0.25 * (1.0 + np.sin(50.0 * s ** 0.1) ** 2))
        return (core / (dim - 1.0)) ** 2 + 10.0 * penalty(x)
    return f


def _griewank_rosenbrock(x: Array, d: Data) -> Array:
    dim = x.shape[-1]
    z = rotate(x, d["m"], 0.5)
    a = z[..., :-1] * z[..., :-1] - z[..., 1:]
    b = 1.0 - z[..., :-1]
    s = 100.0 * a * a + b * b
    return 10.0 + 10.0 * sequential(s / 4000.0 - np.cos(s)) / (dim - 1.0)


def _schwefel(x: Array, d: Data) -> Array:
    dim = x.shape[-1]
    y = 2.0 * d["signs"] * x
    twice = 2.0 * np.abs(d["xopt"])
    z = y.copy()
    z[..., 1:] = y[..., 1:] + 0.25 * (y[..., :-1] - twice[:-1])
    z = 100.0 * ((z - twice) * conditioning(dim, 10.0) + twice)
    excess = np.maximum(np.abs(z) - 500.0, 0.0)
    pen = np.einsum("...i,...i->...", excess, excess)
    core = np.einsum("...i->...", z * np.sin(np.sqrt(np.abs(z))))
    return 0.01 * (pen + 418.9828872724339 - core / dim)


def _gallagher_f(x: Array, d: Data) -> Array:
    dim = x.shape[-1]
    t = rotate(x, d["r"])
    diff = t[..., None, :] - d["local"]
    weighted = np.einsum("...pi,pi->...p", diff * diff, d["scales"])
    best = np.max(d["heights"] * np.exp(-0.5 / dim * weighted), axis=-1)
    f = _obj_oscillate(10.0 - np.maximum(best, 0.0))
    return f * f + penalty(x)


def _katsuura(x: Array, d: Data) -> Array:
    dim = x.shape[-1]
    z = rotate(x - d["xopt"], d["m"])
    powers = 2.0 ** np.arange(1, 33)
    scaled = powers * z[..., None]
    inner = np.einsum("...ij->...i", np.abs(scaled - np.floor(scaled + 0.5)) / powers)
    product = np.prod(1.0 + (np.arange(dim) + 1.0) * inner, axis=-1)
    return 10.0 / dim / dim * (-1.0 + product ** (10.0 / dim ** 1.2)) + penalty(x)


def _lunacek(x: Array, d: Data) -> Array:
    dim = x.shape[-1]
    mu0, unit = 2.5, 1.0
    s = 1.0 - 0.5 / (math.sqrt(dim + 20.0) - 4.1)
    mu1 = -math.sqrt((mu0 * mu0 - unit) / s)
    xh = 2.0 * x * np.where(d["xopt"] < 0.0, -1.0, 1.0)
    z = rotate(rotate(xh - mu0, conditioning(dim, 100.0)[:, None] * d["r2"]), d["r1"])
    a = xh - mu0
    b = xh - mu1
    sum1 = np.einsum("...i,...i->...", a, a)
    sum2 = np.einsum("...i,...i->...", b, b)
    waves = np.einsum("...i->...", np.cos(2.0 * math.pi * z))
    return np.minimum(sum1, unit * dim + s * sum2) + 10.0 * (dim - waves) + 1e4 * penalty(x)


RAW: dict[int, Callable[[Array, Data], Array]] = {
    1: _sphere, 2: _ellipsoid_separable, 3: _rastrigin_separable, 4: _bueche_rastrigin,
    5: _linear_slope, 6: _attractive_sector, 7: _step_ellipsoid, 8: _rosenbrock,
    9: _rosenbrock_rotated, 10: _ellipsoid_rotated, 11: _discus, 12: _bent_cigar,
    13: _sharp_ridge, 14: _different_powers, 15: _rastrigin_rotated, 16: _weierstrass,
    17: _schaffers(10.0), 18: _schaffers(1000.0), 19: _griewank_rosenbrock, 20: _schwefel,
    21: _gallagher_f, 22: _gallagher_f, 23: _katsuura, 24: _lunacek,
}


def values(fid: int, X: Array, dim: int, instance: int) -> Array:
    """f(X) of BBOB function ``fid`` on instance ``instance``, for X (..., dim)."""
    data = instance_data(fid, dim, instance)
    x = np.asarray(X, dtype=float)
    return np.asarray(RAW[fid](x, data) + data["fopt"], dtype=float)


def optimum(fid: int, dim: int, instance: int) -> tuple[Array, float]:
    """(x_opt, f_opt) of the instance: where COCO puts the optimum and its value."""
    data = instance_data(fid, dim, instance)
    return np.array(data.get("best", data["xopt"])), float(data["fopt"])
