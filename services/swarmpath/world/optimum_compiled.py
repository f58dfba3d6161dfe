"""Compiled kernels (numba) of :func:`swarmpath.world.optimum.shortest_path`'s ``backend =
"numba"``: the tangent candidates of all disk pairs and the segment checks, for small scenes.

The swarm planners plan the exact shortest path in their sensed map 16-20 times per run, among
one to three hulls of a few vertices: tens of disks, where numpy's cost per call is the time.
These kernels repeat :mod:`swarmpath.world.optimum_tangents`' and
:mod:`swarmpath.world.optimum_scene`'s operations in order (+ - * /, sqrt, hypot, comparisons;
no fastmath, so no fused multiply-add; ``math.hypot`` is libm's, as ``np.hypot``) and return the
same tangents in the same order, so the graph, the path and its length are the same doubles
(``tests/test_optimum_compiled.py``). Only for margin > 0 without the spatial index, in one
chunk of disk pairs; the arcs (cos, sin, arctan2: numpy's may differ from libm's in the last
bit) stay in numpy.

Imported only when ``backend = "numba"`` is asked for (``pip install 'swarmpath[fast]'``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

Array = np.ndarray

TOL = 1e-9  # optimum_base.TOL


@njit(cache=True)
def _point_segment(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> float:
    """geometry.point_segment_distance for one point and one segment."""
    dx = bx - ax
    dy = by - ay
    dd = dx * dx + dy * dy
    safe = dd if dd > 0.0 else 1.0
    t = ((px - ax) * dx + (py - ay) * dy) / safe
    if t < 0.0:
        t = 0.0
    if t > 1.0:
        t = 1.0
    if not dd > 0.0:
        t = 0.0
    return math.hypot(px - (ax + t * dx), py - (ay + t * dy))


@njit(cache=True)
def _segment_segment(ax: float, ay: float, bx: float, by: float, cx: float, cy: float,
                     ex: float, ey: float) -> float:
    """geometry.segment_segment_distance for one pair (A B, C D = e)."""
    d = min(min(_point_segment(ax, ay, cx, cy, ex, ey), _point_segment(bx, by, cx, cy, ex, ey)),
            min(_point_segment(cx, cy, ax, ay, bx, by), _point_segment(ex, ey, ax, ay, bx, by)))
    ux = bx - ax
    uy = by - ay
    o1 = ux * (cy - ay) - uy * (cx - ax)
    o2 = ux * (ey - ay) - uy * (ex - ax)
    vx = ex - cx
    vy = ey - cy
    o3 = vx * (ay - cy) - vy * (ax - cx)
    o4 = vx * (by - cy) - vy * (bx - cx)
    if o1 * o2 < 0.0 and o3 * o4 < 0.0:
        return 0.0
    return d


@njit(cache=True)
def segments_blocked_kernel(A: Array, B: Array, m: float, box: Array, circles: Array,
                            e0: Array, e1: Array, starts: Array, counts: Array, bb_lo: Array,
                            bb_hi: Array) -> Array:
    """_Scene.segments_blocked with margin m > 0 and no spatial index: outside the box (``box``
    = lo - TOL, hi + TOL, or empty for none), within m - TOL of a circle, or of a polygon whose
    box grown by m + TOL overlaps the segment's."""
    n = A.shape[0]
    out = np.zeros(n, dtype=np.bool_)
    reach_m = m - TOL
    limit = m - TOL
    for s in range(n):
        ax, ay, bx, by = A[s, 0], A[s, 1], B[s, 0], B[s, 1]
        if box.shape[0] == 4:
            if not (ax >= box[0] and ay >= box[1] and ax <= box[2] and ay <= box[3]
                    and bx >= box[0] and by >= box[1] and bx <= box[2] and by <= box[3]):
                out[s] = True
                continue
        ex = bx - ax
        ey = by - ay
        ee = ex * ex + ey * ey
        inv = 1.0 / ee if ee > 0.0 else 0.0
        hit = False
        for c in range(circles.shape[0]):
            wx = circles[c, 0] - ax
            wy = circles[c, 1] - ay
            t = (wx * ex + wy * ey) * inv
            if t < 0.0:
                t = 0.0
            if t > 1.0:
                t = 1.0
            dx = wx - t * ex
            dy = wy - t * ey
            reach = circles[c, 2] + reach_m
            if reach > 0.0 and dx * dx + dy * dy < reach * reach:
                hit = True
                break
        if hit:
            out[s] = True
            continue
        lox, hix = min(ax, bx), max(ax, bx)
        loy, hiy = min(ay, by), max(ay, by)
        for j in range(counts.shape[0]):
            if not (lox <= bb_hi[j, 0] and loy <= bb_hi[j, 1] and hix >= bb_lo[j, 0]
                    and hiy >= bb_lo[j, 1]):
                continue
            dmin = math.inf
            for k in range(starts[j], starts[j] + counts[j]):
                dmin = min(dmin, _segment_segment(ax, ay, bx, by, e0[k, 0], e0[k, 1],
                                                  e1[k, 0], e1[k, 1]))
            if dmin < limit:
                hit = True
                break
        out[s] = hit
    return out


@njit(cache=True)
def _tangent(ci: Array, cj: Array, ri: float, rj: float, s_j: float, h: float,
             dsafe: float, out: Array) -> None:
    """optimum_tangents._tangents for one pair and one (s_j, h): [px, py, qx, qy]."""
    vx = (cj[0] - ci[0]) / dsafe
    vy = (cj[1] - ci[1]) / dsafe
    delta = (s_j * rj - ri) / dsafe
    if delta < -1.0:
        delta = -1.0
    if delta > 1.0:
        delta = 1.0
    hs = h * math.sqrt(1.0 - delta * delta)
    nx = delta * vx + hs * -vy
    ny = delta * vy + hs * vx
    sr = s_j * rj
    out[0] = ci[0] - ri * nx
    out[1] = ci[1] - ri * ny
    out[2] = cj[0] - sr * nx
    out[3] = cj[1] - sr * ny


@njit(cache=True)
def _locally_free(px: float, py: float, qx: float, qy: float, k: int, centres: Array,
                  radii: Array, na: Array, nb: Array) -> bool:
    """optimum_tangents._locally_free at the end p (on disk k) of the tangent p -> q."""
    if radii[k] > 0.0:
        rx = px - centres[k, 0]
        ry = py - centres[k, 1]
        return (rx * na[k, 0] + ry * na[k, 1] <= TOL) and (rx * nb[k, 0] + ry * nb[k, 1] <= TOL)
    dx = qx - px
    dy = qy - py
    dn = math.hypot(dx, dy)
    safe = dn if dn > 0.0 else 1.0
    dx = dx / safe
    dy = dy / safe
    ca = dx * na[k, 1] - dy * na[k, 0]
    cb = dx * nb[k, 1] - dy * nb[k, 0]
    return ca * cb >= -TOL


@njit(cache=True)
def tangents_kernel(centres: Array, radii: Array, na: Array, nb: Array, m: float, box: Array,
                    circles: Array, e0: Array, e1: Array, starts: Array, counts: Array,
                    bb_lo: Array, bb_hi: Array) -> tuple[Array, Array, Array, Array]:
    """The free tangents of all disk pairs (i < j, row by row) in :func:`shortest_path`'s
    order for one chunk: by (s_j, h) = (1, 1), (1, -1), (-1, 1), (-1, -1), then by pair; kept
    when both ends pass the local test and the segment is free."""
    n = centres.shape[0]
    cap = 2 * n * (n - 1) + 1
    ti = np.empty(cap, dtype=np.intp)
    tj = np.empty(cap, dtype=np.intp)
    tp = np.empty((cap, 2))
    tq = np.empty((cap, 2))
    one = np.empty(4)
    found = 0
    signs = ((1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0))
    for s_j, h in signs:
        for i in range(n - 1):
            for j in range(i + 1, n):
                dist = math.hypot(centres[j, 0] - centres[i, 0], centres[j, 1] - centres[i, 1])
                if not dist > TOL:
                    continue
                ri = radii[i]
                rj = radii[j]
                zi = ri == 0.0
                zj = rj == 0.0
                if s_j < 0 and (zi or zj):
                    continue
                if h < 0 and (zi and zj):
                    continue
                if not abs((s_j * rj - ri) / dist) <= 1.0 + 1e-12:
                    continue
                _tangent(centres[i], centres[j], ri, rj, s_j, h, dist, one)
                if not _locally_free(one[0], one[1], one[2], one[3], i, centres, radii, na, nb):
                    continue
                if not _locally_free(one[2], one[3], one[0], one[1], j, centres, radii, na, nb):
                    continue
                ti[found] = i
                tj[found] = j
                tp[found, 0] = one[0]
                tp[found, 1] = one[1]
                tq[found, 0] = one[2]
                tq[found, 1] = one[3]
                found += 1
    ti, tj, tp, tq = ti[:found], tj[:found], tp[:found], tq[:found]
    free = ~segments_blocked_kernel(tp, tq, m, box, circles, e0, e1, starts, counts, bb_lo,
                                    bb_hi)
    return ti[free], tj[free], tp[free], tq[free]
