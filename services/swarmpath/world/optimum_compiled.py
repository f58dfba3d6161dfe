"""Compiled kernels (numba) of :func:`swarmpath.world.optimum.shortest_path`'s ``backend =
"numba"``: the disks, the tangent candidates of all disk pairs and the segment checks, for
small scenes (the arcs' checks: :mod:`swarmpath.world.optimum_compiled_arcs`).

The swarm planners plan the exact shortest path in their sensed map 16-20 times per run, among
one to three hulls of a few vertices: tens of disks, where numpy's cost per call is the time.
These kernels repeat :mod:`swarmpath.world.optimum_tangents`' and
:mod:`swarmpath.world.optimum_scene`'s operations in order (+ - * /, sqrt, hypot, comparisons;
no fastmath, so no fused multiply-add; ``math.hypot`` is libm's, as ``np.hypot``) and return the
same tangents in the same order, so the graph, the path and its length are the same doubles
(``tests/test_optimum_compiled.py``; a polygon's orientation by numpy's own pairwise sum).
Only for margin > 0 without the spatial index, the tangents in one chunk of disk pairs.

Imported only when ``backend = "numba"`` is asked for (``pip install 'swarmpath[fast]'``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

import swarmpath.optimizers.compiled  # noqa: F401 - first: numba's versioned cache directory

# ``np.sum`` of a[lo:lo + n]: numpy's pairwise summation (without recursion: a recursive cached
# kernel fails to load in the next process)
from swarmpath.optimizers.compiled.functions import pairwise_sum as _pairwise_sum

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
    limit = m - TOL  # a circle's reach (radius + m - TOL) and a polygon's least distance
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
            reach = circles[c, 2] + limit
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


@njit(cache=True)
def _signed_polygon(px: float, py: float, verts: Array, start: int, count: int) -> float:
    """geometry.point_polygon_distance of one point: the least edge distance, negative inside
    (even-odd ray casting toward +x)."""
    d = math.inf
    crossings = 0
    for k in range(start, start + count):
        nxt = k + 1 if k + 1 < start + count else start
        ax, ay, bx, by = verts[k, 0], verts[k, 1], verts[nxt, 0], verts[nxt, 1]
        d = min(d, _point_segment(px, py, ax, ay, bx, by))
        if (ay > py) != (by > py):
            dy = by - ay
            safe = dy if dy != 0.0 else 1.0
            if px < ax + (py - ay) * (bx - ax) / safe:
                crossings += 1
    return -d if crossings % 2 == 1 else d


@njit(cache=True, error_model="numpy")
def disks_kernel(s: Array, g: Array, circles: Array, verts: Array, counts: Array,
                 margin: float) -> tuple[Array, Array, Array, Array]:
    """optimum_tangents._disks: start, goal, the circles inflated by the margin (those with r +
    margin > 0), the convex polygon vertices (turn of the edges, signed by the polygon's
    orientation: ``np.sum`` of the edge cross products) that no other polygon covers
    (_covered_vertices); with the unit vectors to each vertex's neighbours."""
    n_poly = counts.shape[0]
    n_v = verts.shape[0]
    convex = np.zeros(n_v, dtype=np.bool_)
    owner = np.empty(n_v, dtype=np.intp)
    ortho = np.zeros(n_poly, dtype=np.bool_)
    lo = np.empty((n_poly, 2))
    hi = np.empty((n_poly, 2))
    cross = np.empty(n_v)
    start = 0
    for j in range(n_poly):
        m = counts[j]
        ortho[j] = True
        lo[j, 0] = lo[j, 1] = math.inf
        hi[j, 0] = hi[j, 1] = -math.inf
        for i in range(m):
            k = start + i
            nx = start + (i + 1) % m
            cross[k] = verts[k, 0] * verts[nx, 1] - verts[k, 1] * verts[nx, 0]
            ex = verts[nx, 0] - verts[k, 0]
            ey = verts[nx, 1] - verts[k, 1]
            if not (ex == 0.0 or ey == 0.0):
                ortho[j] = False
            lo[j, 0] = min(lo[j, 0], verts[k, 0])
            lo[j, 1] = min(lo[j, 1], verts[k, 1])
            hi[j, 0] = max(hi[j, 0], verts[k, 0])
            hi[j, 1] = max(hi[j, 1], verts[k, 1])
        sign = math.copysign(1.0, _pairwise_sum(cross, start, m))
        for i in range(m):
            k = start + i
            pv = start + (i - 1) % m
            nx = start + (i + 1) % m
            d1x = verts[k, 0] - verts[pv, 0]
            d1y = verts[k, 1] - verts[pv, 1]
            d2x = verts[nx, 0] - verts[k, 0]
            d2y = verts[nx, 1] - verts[k, 1]
            convex[k] = (d1x * d2y - d1y * d2x) * sign > 0.0
            owner[k] = j
        lo[j, 0] -= TOL
        lo[j, 1] -= TOL
        hi[j, 0] += TOL
        hi[j, 1] += TOL
        start += m
    starts = np.empty(n_poly, dtype=np.intp)
    start = 0
    for j in range(n_poly):
        starts[j] = start
        start += counts[j]
    keep = convex.copy()
    if n_poly >= 2:
        for k in range(n_v):
            if not convex[k]:
                continue
            px, py = verts[k, 0], verts[k, 1]
            for j in range(n_poly):
                if j == owner[k] or not (px >= lo[j, 0] and py >= lo[j, 1] and px <= hi[j, 0]
                                         and py <= hi[j, 1]):
                    continue
                d = _signed_polygon(px, py, verts, starts[j], counts[j])
                both = ortho[j] and ortho[owner[k]] and margin > 0.0
                if d < -TOL or (abs(d) <= TOL and both):
                    keep[k] = False
                    break
    n_c = 0
    for c in range(circles.shape[0]):
        if circles[c, 2] + margin > 0.0:
            n_c += 1
    n = 2 + n_c + int(keep.sum())
    centres = np.empty((n, 2))
    radii = np.zeros(n)
    na = np.zeros((n, 2))
    nb = np.zeros((n, 2))
    centres[0] = s
    centres[1] = g
    at = 2
    for c in range(circles.shape[0]):
        if circles[c, 2] + margin > 0.0:
            centres[at, 0] = circles[c, 0]
            centres[at, 1] = circles[c, 1]
            radii[at] = circles[c, 2] + margin
            at += 1
    start = 0
    for j in range(n_poly):
        m = counts[j]
        for i in range(m):
            k = start + i
            if not keep[k]:
                continue
            pv = start + (i - 1) % m
            nx = start + (i + 1) % m
            centres[at, 0] = verts[k, 0]
            centres[at, 1] = verts[k, 1]
            radii[at] = margin
            ux = verts[pv, 0] - verts[k, 0]
            uy = verts[pv, 1] - verts[k, 1]
            norm = math.hypot(ux, uy)
            na[at, 0] = ux / norm
            na[at, 1] = uy / norm
            ux = verts[nx, 0] - verts[k, 0]
            uy = verts[nx, 1] - verts[k, 1]
            norm = math.hypot(ux, uy)
            nb[at, 0] = ux / norm
            nb[at, 1] = uy / norm
            at += 1
        start += m
    return centres, radii, na, nb
