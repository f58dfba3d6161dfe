"""Compiled kernels (numba) of the swarm planners' ``backend = "numba"``.

* the grid repair (:func:`swarmpath.planners.local._repair_grid`) and the hit distances;
* the MFB repair, eqs 18-22 of Ajeil et al. (:func:`swarmpath.planners.local._repair_mfb`);
* the aim's clearances: least distance from sensed points to segments
  (:func:`swarmpath.planners.sensed_map.shortcut` and ``path_clearance``);
* sensing's distances to the sensed surface (:func:`swarmpath.planners.sensed_map.motion`).

Each with the same numbers as its numpy reference: the references use + - * /, sqrt, hypot,
minima and comparisons only, and each kernel repeats every operation in the reference's order
and association, without fastmath (so no fused multiply-add); hypot is libm's in both
(``math.hypot`` in numba, ``np.hypot`` in numpy). Every value is then the same double
(``tests/test_planner_compiled.py``), and so are the episodes. The cost (arctan2, sin, cos)
stays in numpy.

Imported only by a planner whose ``backend`` is ``"numba"`` (numba is an optional dependency:
``pip install 'swarmpath[fast]'``); the first call compiles, or loads the compiled code from
numba's cache.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

import swarmpath.optimizers.compiled  # noqa: F401 - first: numba's versioned cache directory
from swarmpath.optimizers.compiled.coot_phases import _clip as clip
from swarmpath.world.optimum_compiled import _point_segment

Array = np.ndarray


@njit(cache=True)
def _point_d2(x: float, y: float, hits: Array, j: int) -> float:
    """Squared distance from (x, y) to hit j."""
    dx = x - hits[j, 0]
    dx = dx * dx
    dy = y - hits[j, 1]
    dy = dy * dy
    return dx + dy


@njit(cache=True)
def _direction(px: float, py: float, x: float, y: float) -> tuple[float, float, float]:
    """(ux, uy, |u|^2 + 1e-300) of the segment from p to (x, y)."""
    ux = x - px
    uy = y - py
    return ux, uy, ux * ux + uy * uy + 1e-300


@njit(cache=True)
def _segment_d2(ux: float, uy: float, den: float, wx: float, wy: float) -> float:
    """Squared distance from the point (wx, wy) relative to p to the segment from p to p + u
    (``den`` from :func:`_direction`)."""
    t = ux * wx + uy * wy
    t = t / den
    if t < 0.0:
        t = 0.0
    if t > 1.0:
        t = 1.0
    ex = wx - t * ux
    ex = ex * ex
    ey = wy - t * uy
    ey = ey * ey
    return ex + ey


@njit(cache=True)
def _point_nearest(x: float, y: float, hits: Array) -> tuple[float, int]:
    """(squared distance, index) of the hit nearest (x, y) (first index on ties; (inf, 0) with
    no hits)."""
    best = math.inf
    at = 0
    for j in range(hits.shape[0]):
        d2 = _point_d2(x, y, hits, j)
        if d2 < best:
            best = d2
            at = j
    return best, at


@njit(cache=True)
def _segment_nearest(px: float, py: float, x: float, y: float, wx: Array,
                     wy: Array) -> tuple[float, int]:
    """(squared distance, index) of the hit (wx, wy relative to p) nearest the segment from p to
    (x, y) (first index on ties; (inf, 0) with no hits)."""
    ux, uy, den = _direction(px, py, x, y)
    best = math.inf
    at = 0
    for j in range(wx.shape[0]):
        d2 = _segment_d2(ux, uy, den, wx[j], wy[j])
        if d2 < best:
            best = d2
            at = j
    return best, at


@njit(cache=True)
def _point_clear(x: float, y: float, hits: Array, margin: float) -> bool:
    """``sqrt(_point_nearest(x, y, hits)[0]) >= margin``, stopping at the first hit that
    decides it (the running minimum only falls, and sqrt is monotone: the same answer)."""
    best = math.inf
    for j in range(hits.shape[0]):
        d2 = _point_d2(x, y, hits, j)
        if d2 < best:
            best = d2
            if not math.sqrt(best) >= margin:
                return False
    return math.sqrt(best) >= margin


@njit(cache=True)
def _segment_clear(px: float, py: float, x: float, y: float, wx: Array, wy: Array,
                   margin: float) -> bool:
    """``sqrt(_segment_nearest(...)[0]) >= margin``, stopping as :func:`_point_clear` does."""
    ux, uy, den = _direction(px, py, x, y)
    best = math.inf
    for j in range(wx.shape[0]):
        d2 = _segment_d2(ux, uy, den, wx[j], wy[j])
        if d2 < best:
            best = d2
            if not math.sqrt(best) >= margin:
                return False
    return math.sqrt(best) >= margin


@njit(cache=True)
def _clip(v: float, lo: float, hi: float, bounded: bool) -> float:
    """v clipped to [lo, hi] when ``bounded``, else v."""
    return clip(v, lo, hi) if bounded else v


@njit(cache=True)
def repair_grid_kernel(flat: Array, p: Array, hits: Array, margin: float, resolution: float,
                       lower: Array, upper: Array, bounded: bool, reach: int) -> tuple[
                           Array, Array]:
    """(repaired (n, 2), violation (n,)) of candidates ``flat`` (n, 2); ``local._repair_grid``."""
    n = flat.shape[0]
    px, py = p[0], p[1]
    wx = hits[:, 0] - px
    wy = hits[:, 1] - py
    out = flat.copy()
    short = np.zeros(n)
    for i in range(n):
        cx, cy = flat[i, 0], flat[i, 1]
        d_pt = math.sqrt(_point_nearest(cx, cy, hits)[0])
        d_seg = math.sqrt(_segment_nearest(px, py, cx, cy, wx, wy)[0])
        s = margin - min(d_pt, d_seg)
        if not s > 0.0:
            continue
        short[i] = s
        # slide across the line's dominant axis: x for a mostly vertical line, y otherwise
        axis = 0 if abs(cy - py) > abs(cx - px) else 1
        for k in range(1, reach + 1):
            step = k * resolution
            for sign in range(2):
                offset = step if sign == 0 else -step
                tx = cx + (offset if axis == 0 else 0.0)
                ty = cy + (offset if axis == 1 else 0.0)
                tx = _clip(tx, lower[0], upper[0], bounded)
                ty = _clip(ty, lower[1], upper[1], bounded)
                if not _point_clear(tx, ty, hits, margin):
                    continue
                if not _segment_clear(px, py, tx, ty, wx, wy, margin):
                    continue
                out[i, 0] = tx
                out[i, 1] = ty
                short[i] = 0.0
                break
            if short[i] == 0.0:
                break
    return out, short


@njit(cache=True)
def distances_kernel(flat: Array, p: Array, hits: Array) -> tuple[Array, Array, Array, Array]:
    """``local._distances`` of candidates ``flat`` (n, 2): the distance to the nearest hit and its
    index, and the same for the segment from p (first index on ties, as ``np.argmin``)."""
    n = flat.shape[0]
    px, py = p[0], p[1]
    wx = hits[:, 0] - px
    wy = hits[:, 1] - py
    d_pt = np.empty(n)
    d_seg = np.empty(n)
    i_pt = np.zeros(n, dtype=np.int64)
    i_seg = np.zeros(n, dtype=np.int64)
    for i in range(n):
        x, y = flat[i, 0], flat[i, 1]
        best, i_pt[i] = _point_nearest(x, y, hits)
        d_pt[i] = math.sqrt(best)
        best, i_seg[i] = _segment_nearest(px, py, x, y, wx, wy)
        d_seg[i] = math.sqrt(best)
    return d_pt, i_pt, d_seg, i_seg


@njit(cache=True)
def _hypot(x: float, y: float) -> float:
    return math.hypot(x, y)  # libm's hypot, as np.hypot


@njit(cache=True)
def repair_mfb_kernel(flat: Array, p: Array, hits: Array, margin: float, safety: float,
                      delta: float, lower: Array, upper: Array, bounded: bool,
                      rounds: int) -> tuple[Array, Array]:
    """(repaired (n, 2), violation (n,)) of candidates ``flat`` (n, 2): ``local._repair_mfb``
    round by round (a round with no infeasible candidate ends the repair; the box clip applies
    to every candidate after a round that repaired any, as in the reference)."""
    n = flat.shape[0]
    px, py = p[0], p[1]
    c = flat.copy()
    push_base = margin + safety
    for _ in range(rounds):
        d_pt, i_pt, d_seg, i_seg = distances_kernel(c, p, hits)
        any_bad = False
        for i in range(n):
            if d_pt[i] < margin or d_seg[i] < margin:
                any_bad = True
                break
        if not any_bad:
            return c, np.zeros(n)
        for i in range(n):
            cx, cy = c[i, 0], c[i, 1]
            if d_pt[i] < margin:  # case 1 (eqs 19-20): out of the obstacle, radially
                vx = cx - hits[i_pt[i], 0]
                vy = cy - hits[i_pt[i], 1]
                nv = _hypot(vx, vy)
                if nv > 1e-12:
                    ax = vx / nv
                    ay = vy / nv
                else:
                    ax = 1.0
                    ay = 0.0
                push = push_base - d_pt[i]
                c[i, 0] = cx + push * ax
                c[i, 1] = cy + push * ay
            elif d_seg[i] < margin:  # case 2 (eqs 21-22): sideways (local._lateral)
                qx, qy = hits[i_seg[i], 0], hits[i_seg[i], 1]
                ux = cx - px
                uy = cy - py
                l2 = max(ux * ux + uy * uy, 1e-24)
                s = ((qx - px) * ux + (qy - py) * uy) / l2
                if s < 0.0:
                    s = 0.0
                if s > 1.0:
                    s = 1.0
                sx = (px + s * ux) - qx
                sy = (py + s * uy) - qy
                norm = _hypot(sx, sy)
                if norm > 1e-9:
                    ax = sx / norm
                    ay = sy / norm
                else:
                    root = math.sqrt(l2)
                    ax = -uy / root
                    ay = ux / root
                step = delta * _hypot(cx - px, cy - py)
                c[i, 0] = cx + step * ax
                c[i, 1] = cy + step * ay
            c[i, 0] = _clip(c[i, 0], lower[0], upper[0], bounded)
            c[i, 1] = _clip(c[i, 1], lower[1], upper[1], bounded)
    d_pt, i_pt, d_seg, i_seg = distances_kernel(c, p, hits)
    short = np.empty(n)
    for i in range(n):
        s = margin - min(d_pt[i], d_seg[i])
        short[i] = s if s > 0.0 else 0.0
    return c, short


@njit(cache=True)
def segments_clearance_kernel(points: Array, a: Array, b: Array) -> Array:
    """Least distance from ``points`` (h, 2) to each segment a[k] -> b[k] (m,): the minimum over
    the points of :func:`swarmpath.world.geometry.point_segment_distance`, in its operations."""
    m = a.shape[0]
    out = np.empty(m)
    for k in range(m):
        ax, ay, bx, by = a[k, 0], a[k, 1], b[k, 0], b[k, 1]
        best = math.inf
        for j in range(points.shape[0]):
            d = _point_segment(points[j, 0], points[j, 1], ax, ay, bx, by)
            if d < best:
                best = d
        out[k] = best
    return out


@njit(cache=True)
def surface_kernel(points: Array, scan: Array, surface: float, dist: Array,
                   nearest: Array) -> tuple[Array, Array]:
    """``sensed_map._to_surface_from``: (distance, nearest point) of each of ``points`` (n, 2) to
    the polyline of ``scan``'s consecutive hits closer than ``surface``, given the distance to
    the nearest hit and that hit (kept where no piece is strictly closer)."""
    n = points.shape[0]
    out_d = dist.copy()
    out_p = nearest.copy()
    m = scan.shape[0] - 1
    joined = np.zeros(max(m, 0), dtype=np.bool_)
    for i in range(m):
        gap = _hypot(scan[i + 1, 0] - scan[i, 0], scan[i + 1, 1] - scan[i, 1])
        joined[i] = gap < surface and gap > 1e-9
    for k in range(n):
        px, py = points[k, 0], points[k, 1]
        best = math.inf
        fx = 0.0
        fy = 0.0
        for i in range(m):
            if not joined[i]:
                continue
            ax, ay = scan[i, 0], scan[i, 1]
            ux = scan[i + 1, 0] - ax
            uy = scan[i + 1, 1] - ay
            t = (ux * (px - ax) + uy * (py - ay)) / (ux * ux + uy * uy)
            if t < 0.0:
                t = 0.0
            if t > 1.0:
                t = 1.0
            hx = ax + t * ux
            hy = ay + t * uy
            d = _hypot(px - hx, py - hy)
            if d < best:
                best = d
                fx = hx
                fy = hy
        if best < dist[k]:
            out_d[k] = best
            out_p[k, 0] = fx
            out_p[k, 1] = fy
    return out_d, out_p
