"""The transformations the BBOB functions are built from, vectorized over points (..., d).

Definitions: Hansen et al., "Real-parameter black-box optimization benchmarking 2009: noiseless
functions definitions", INRIA RR-6829, section 0.2 (T_osz, T_asy, Lambda^alpha, f_pen), as COCO
evaluates them (its ``transform_vars_*`` and ``transform_obj_*`` steps).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from swarmpath.functions.suites.sums import rotate, sequential

Array = NDArray[np.float64]

__all__ = ["asymmetric", "conditioning", "ellipsoid", "oscillate", "penalty", "rastrigin",
           "rosenbrock", "rotate", "sequential"]


def oscillate(x: Array) -> Array:
    """T_osz elementwise: sign(x) exp(x^ + 0.049 (sin(c1 x^) + sin(c2 x^))), x^ = log|x|
    (c1, c2 = 10, 7.9 for x > 0 and 5.5, 3.1 for x < 0), 0 at 0; COCO computes it as
    (exp(t + 0.49 (sin(a t) + sin(b t))))^0.1 with t = log|x| / 0.1."""
    x = np.asarray(x, dtype=float)
    out = np.zeros_like(x)
    a = np.abs(x)
    nonzero = a > 0.0
    t = np.zeros_like(x)
    t[nonzero] = np.log(a[nonzero]) / 0.1
    pos = x > 0.0
    neg = x < 0.0
    out[pos] = np.exp(t[pos] + 0.49 * (np.sin(t[pos]) + np.sin(0.79 * t[pos]))) ** 0.1
    out[neg] = -(np.exp(t[neg] + 0.49 * (np.sin(0.55 * t[neg]) + np.sin(0.31 * t[neg]))) ** 0.1)
    return out


def asymmetric(x: Array, beta: float) -> Array:
    """T_asy^beta: x_i^(1 + beta i/(d-1) sqrt(x_i)) where x_i > 0, else x_i."""
    x = np.asarray(x, dtype=float)
    d = x.shape[-1]
    ramp = np.arange(d) / (d - 1.0)
    pos = x > 0.0
    safe = np.where(pos, x, 1.0)
    return np.where(pos, safe ** (1.0 + beta * ramp * np.sqrt(safe)), x)


def conditioning(d: int, alpha: float) -> Array:
    """The diagonal of Lambda^alpha: alpha^(0.5 i/(d-1)), i = 0..d-1."""
    return np.sqrt(alpha) ** (np.arange(d) / (d - 1.0))


def penalty(x: Array, bound: float = 5.0) -> Array:
    """f_pen: sum of max(0, |x_i| - bound)^2."""
    excess = np.maximum(np.abs(np.asarray(x, dtype=float)) - bound, 0.0)
    return np.einsum("...i,...i->...", excess, excess)


def rastrigin(z: Array) -> Array:
    d = z.shape[-1]
    return 10.0 * (d - np.cos(2.0 * np.pi * z).sum(axis=-1)) + np.einsum("...i,...i->...", z, z)


def rosenbrock(z: Array) -> Array:
    a = z[..., :-1] ** 2 - z[..., 1:]
    b = z[..., :-1] - 1.0
    return 100.0 * np.einsum("...i,...i->...", a, a) + np.einsum("...i,...i->...", b, b)


def ellipsoid(z: Array, condition: float = 1e6) -> Array:
    d = z.shape[-1]
    weights = condition ** (np.arange(d) / (d - 1.0))
    return np.einsum("...i,i->...", z * z, weights)
