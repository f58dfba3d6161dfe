"""The swarm planners' objective (:func:`swarmpath.planners.local.score`) compiled (numba).

:func:`score_into` repairs a batch of candidates (the kernels of :mod:`.compiled`) and scores
them: w1 f1 + w2 f2 (eqs 3-6), MFB's fitness -1 / (f + eps) (eq 8) with ``objective =
"inverse"``, ``PENALTY`` plus the violation where a candidate stays infeasible. The operations
are the numpy reference's, in its order, on arrays of the reference's shapes; the trigonometry
(arctan2, sin, cos) runs through numpy's own loops (:mod:`swarmpath.optimizers.compiled.ufuncs`:
on AVX-512 they are not the C library's), called on contiguous arrays as numpy calls them, so
every value is the same double. The heading to the aim, one arctan2 per decision, comes from
numpy itself (:func:`setup`).

A context is two arrays: ``geo`` (8,) = position, aim, lower, upper, and ``k`` (:data:`FIELDS`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

import swarmpath.optimizers.compiled  # noqa: F401 - first: numba's versioned cache directory
from swarmpath.optimizers.compiled.ufuncs import _linked_loop
from swarmpath.planners.compiled import (
    _hypot,
    distances_kernel,
    repair_grid_kernel,
    repair_mfb_kernel,
)
from swarmpath.planners.local import StepContext

Array = np.ndarray

PENALTY = 1e6  # local.PENALTY
REPAIRS = ("mfb", "grid", "none")
#: The scalars of a context, in ``k``'s order.
FIELDS = ("margin", "w1", "w2", "eps", "delta", "safety", "resolution", "to_goal", "repair",
          "inverse", "bounded")

_atan2 = _linked_loop("swarmpath_numpy_arctan2_ddd", np.arctan2, "ddd")
_sin = _linked_loop("swarmpath_numpy_sin_dd", np.sin, "dd")
_cos = _linked_loop("swarmpath_numpy_cos_dd", np.cos, "dd")


def setup(ctx: StepContext) -> tuple[Array, Array]:
    """(geo, k) of a ``local.StepContext``; the heading to the aim as ``local.raw_cost``
    computes it."""
    g, p = ctx.goal, ctx.position
    to_goal = float(np.arctan2(g[1] - p[1], g[0] - p[0]))
    bounded = ctx.lower is not None and ctx.upper is not None
    lower = ctx.lower if bounded else np.zeros(2)
    upper = ctx.upper if bounded else np.zeros(2)
    geo = np.concatenate([p, g, lower, upper]).astype(float)
    if ctx.objective not in ("cost", "inverse"):
        raise ValueError(f"unknown objective {ctx.objective!r}; valid: cost, inverse")
    if ctx.repair not in REPAIRS:
        raise ValueError(f"unknown repair {ctx.repair!r}; valid: mfb, grid, none")
    k = np.array([ctx.margin, ctx.w1, ctx.w2, ctx.eps, ctx.delta, ctx.safety, ctx.resolution,
                  to_goal, REPAIRS.index(ctx.repair), ctx.objective == "inverse", bounded],
                 dtype=float)
    return geo, k


@njit(cache=True)
def _binary(a: Array, b: Array, out: Array, call: Array) -> None:
    """out = arctan2(a, b) with numpy's loop (contiguous, distinct arrays)."""
    call[0] = a.ctypes.data
    call[1] = b.ctypes.data
    call[2] = out.ctypes.data
    call[3] = out.size
    call[4] = 8
    call[5] = 8
    call[6] = 8
    _atan2(call.ctypes.data, call[3:].ctypes.data, call[4:].ctypes.data)


@njit(cache=True)
def _unary(cosine: bool, a: Array, out: Array, call: Array) -> None:
    """out = sin(a) (or cos(a)) with numpy's loop (contiguous, distinct arrays)."""
    call[0] = a.ctypes.data
    call[1] = out.ctypes.data
    call[2] = out.size
    call[3] = 8
    call[4] = 8
    if cosine:
        _cos(call.ctypes.data, call[2:].ctypes.data, call[3:].ctypes.data)
    else:
        _sin(call.ctypes.data, call[2:].ctypes.data, call[3:].ctypes.data)


@njit(cache=True)
def unary_inplace(cosine: bool, a: Array, call: Array) -> None:
    """a = sin(a) (or cos(a)) in place with numpy's loop, as ``np.cos(a, out=a)`` calls it."""
    _unary(cosine, a, a, call)


@njit(cache=True)
def repaired(C: Array, geo: Array, hits: Array, k: Array) -> tuple[Array, Array]:
    """(repaired candidates, remaining violation) of C (m, 2): ``local.score``'s repair."""
    p = geo[0:2]
    lower = geo[4:6]
    upper = geo[6:8]
    margin = k[0]
    repair = int(k[8])
    bounded = k[10] == 1.0
    if repair == 0:
        return repair_mfb_kernel(C, p, hits, margin, k[5], k[4], lower, upper, bounded, 3)
    if repair == 1:
        return repair_grid_kernel(C, p, hits, margin, k[6], lower, upper, bounded, 24)
    d_pt, _, d_seg, _ = distances_kernel(C, p, hits)
    short = np.empty(C.shape[0])
    for i in range(C.shape[0]):
        s = margin - min(d_pt[i], d_seg[i])
        short[i] = s if s > 0.0 else 0.0
    return C.copy(), short


@njit(cache=True)
def score_into(C: Array, geo: Array, hits: Array, k: Array, F: Array) -> Array:
    """F[:m] = ``local.score``'s objective of candidates C (m, 2); returns the repaired ones."""
    m = C.shape[0]
    fixed, short = repaired(C, geo, hits, k)
    px, py, gx, gy = geo[0], geo[1], geo[2], geo[3]
    w1, w2, eps, to_goal = k[1], k[2], k[3], k[7]
    inverse = k[9] == 1.0
    dy = np.empty(m)
    dx = np.empty(m)
    heading = np.empty(m)
    for i in range(m):
        dy[i] = fixed[i, 1] - py
        dx[i] = fixed[i, 0] - px
    call = np.empty(7, dtype=np.int64)
    _binary(dy, dx, heading, call)
    for i in range(m):
        heading[i] = heading[i] - to_goal
    _unary(False, heading, dy, call)  # sin
    _unary(True, heading, dx, call)  # cos
    _binary(dy, dx, heading, call)  # wrapped to [-pi, pi]
    for i in range(m):
        f1 = _hypot(gx - fixed[i, 0], gy - fixed[i, 1])
        cost = w1 * f1 + w2 * abs(heading[i])
        if inverse:
            cost = -1.0 / (cost + eps)
        F[i] = PENALTY + short[i] if short[i] > 0 else cost
    return fixed
