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
from typing import Any

import numpy as np
from numba import njit

from swarmpath.world.optimum_base import _on_circle

Array = np.ndarray

TOL = 1e-9  # optimum_base.TOL
_f = np.ascontiguousarray


def arcs_near_polygons(scene: Any, c: Array, rho: Array, th0: Array, dth: Array) -> Array:
    """The polygon part of ``_Scene.arcs_blocked`` (margin > 0, no index) for the arcs (c,
    rho, th0, dth): the same pairs and distances as numpy (:func:`_arc_edge`); the arcs' ends
    and the angles of the in-arc tests come from numpy, computed as there."""
    E0 = _f(_on_circle(c, rho, th0))
    E1 = _f(_on_circle(c, rho, th0 + dth))
    c, rho = _f(c), _f(rho)
    e0, e1 = _f(scene.e0), _f(scene.e1)
    arcs, edges, vecs = arcs_pending_kernel(c, rho, E0, E1, scene.m, _f(scene.pc), _f(scene.pr),
                                            e0, e1, scene.starts, scene.counts)
    phi = np.arctan2(vecs[..., 0], vecs[..., 1])
    return np.asarray(arcs_decide_kernel(len(c), arcs, edges, _f(phi), c, rho, _f(th0), _f(dth),
                                         E0, E1, scene.m, e0, e1))


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


_TWO_PI = 2.0 * math.pi


@njit(cache=True)
def _in_arc(phi: float, th0: float, dth: float) -> bool:
    """optimum_base._in_arc: np.mod(phi - th0, 2 pi) <= dth + 1e-12 (numpy's float remainder:
    C fmod, moved into [0, 2 pi) when the signs differ, +0 for an exact multiple)."""
    a = phi - th0
    mod = np.fmod(a, _TWO_PI)
    if mod != 0.0:
        if mod < 0.0:
            mod += _TWO_PI
    else:
        mod = 0.0
    return mod <= dth + 1e-12


@njit(cache=True)
def _arc_edge(c: Array, rho: float, E0: Array, E1: Array, a0: float, a1: float, b0: float,
              b1: float, phi: Array, exact: bool, vec: Array) -> float:
    """optimum_base._arc_segment_distance of one arc (centre c, radius rho, ends E0 and E1,
    angles phi of its in-arc tests) and one segment a b. ``exact = False``: a lower bound
    without the in-arc tests (every candidate of the reference, unconditionally: the least of
    a superset of the reference's values), and the five vectors whose angles those tests need
    written to ``vec`` (y, x) pairs: a - c, b - c, the foot's, the two circle crossings'."""
    cx, cy = c[0], c[1]
    # _point_arc_distance(a) and (b)
    wx, wy = a0 - cx, a1 - cy
    ra = math.hypot(wx, wy)
    dea = min(math.hypot(a0 - E0[0], a1 - E0[1]), math.hypot(a0 - E1[0], a1 - E1[1]))
    radial_a = abs(ra - rho)
    vec[0], vec[1] = wy, wx
    wx, wy = b0 - cx, b1 - cy
    rb = math.hypot(wx, wy)
    deb = min(math.hypot(b0 - E0[0], b1 - E0[1]), math.hypot(b0 - E1[0], b1 - E1[1]))
    radial_b = abs(rb - rho)
    vec[2], vec[3] = wy, wx
    if exact:
        pa = min(dea, radial_a if _in_arc(phi[0], phi[5], phi[6]) else math.inf)
        pb = min(deb, radial_b if _in_arc(phi[1], phi[5], phi[6]) else math.inf)
    else:
        pa = min(dea, radial_a)
        pb = min(deb, radial_b)
    best = min(min(pa, pb), min(_point_segment(E0[0], E0[1], a0, a1, b0, b1),
                                _point_segment(E1[0], E1[1], a0, a1, b0, b1)))
    ex = b0 - a0
    ey = b1 - a1
    ee = ex * ex + ey * ey
    safe = ee if ee > 0.0 else 1.0
    t = ((cx - a0) * ex + (cy - a1) * ey) / safe
    if t < 0.0:
        t = 0.0
    if t > 1.0:
        t = 1.0
    fx = a0 + t * ex - cx
    fy = a1 + t * ey - cy
    rf = math.hypot(fx, fy)
    vec[4], vec[5] = fy, fx
    if rf > 0.0 and (not exact or _in_arc(phi[2], phi[5], phi[6])):
        best = min(best, abs(rf - rho))
    acx = a0 - cx
    acy = a1 - cy
    bq = 2.0 * (ex * acx + ey * acy)
    cq = (acx * acx + acy * acy) - rho * rho
    disc = bq * bq - 4.0 * ee * cq
    has = ee > 0.0 and disc >= 0.0
    sq = math.sqrt(disc if has else 0.0)
    for k in range(2):
        sign = -1.0 if k == 0 else 1.0
        tt = (-bq + sign * sq) / (2.0 * safe)
        px = a0 + tt * ex - cx
        py = a1 + tt * ey - cy
        vec[6 + 2 * k], vec[7 + 2 * k] = py, px
        if has and tt >= 0.0 and tt <= 1.0 and (not exact or _in_arc(phi[3 + k], phi[5],
                                                                    phi[6])):
            best = 0.0
    return best


@njit(cache=True)
def arcs_pending_kernel(c: Array, rho: Array, E0: Array, E1: Array, m: float, pc: Array,
                        pr: Array, e0: Array, e1: Array, starts: Array,
                        counts: Array) -> tuple[Array, Array, Array]:
    """The (arc, edge) pairs that may block an arc (_Scene.arcs_blocked's polygons, margin
    > 0): the polygon near the arc (centre distance <= rho + its radius + m + TOL) and the
    lower bound of :func:`_arc_edge` below m - TOL; with the vectors (P, 5, 2: y, x) whose
    angles the exact test needs."""
    n = c.shape[0]
    limit = m - TOL
    cap = 16
    arcs = np.empty(cap, dtype=np.intp)
    edges = np.empty(cap, dtype=np.intp)
    vecs = np.empty((cap, 10))
    vec = np.empty(10)
    phi = np.empty(7)
    found = 0
    for i in range(n):
        for j in range(counts.shape[0]):
            dc = math.hypot(pc[j, 0] - c[i, 0], pc[j, 1] - c[i, 1])
            if not dc <= rho[i] + pr[j] + m + TOL:
                continue
            for k in range(starts[j], starts[j] + counts[j]):
                low = _arc_edge(c[i], rho[i], E0[i], E1[i], e0[k, 0], e0[k, 1], e1[k, 0],
                                e1[k, 1], phi, False, vec)
                if not low < limit:
                    continue
                if found == cap:
                    cap *= 2
                    arcs2 = np.empty(cap, dtype=np.intp)
                    edges2 = np.empty(cap, dtype=np.intp)
                    vecs2 = np.empty((cap, 10))
                    arcs2[:found] = arcs[:found]
                    edges2[:found] = edges[:found]
                    vecs2[:found] = vecs[:found]
                    arcs, edges, vecs = arcs2, edges2, vecs2
                arcs[found] = i
                edges[found] = k
                vecs[found] = vec
                found += 1
    return arcs[:found], edges[:found], vecs[:found].reshape(found, 5, 2)


@njit(cache=True)
def arcs_decide_kernel(n: int, arcs: Array, edges: Array, phi: Array, c: Array, rho: Array,
                       th0: Array, dth: Array, E0: Array, E1: Array, m: float, e0: Array,
                       e1: Array) -> Array:
    """Which of the n arcs a pending pair blocks: the exact :func:`_arc_edge` (with the angles
    ``phi`` (P, 5) numpy computed) below m - TOL."""
    out = np.zeros(n, dtype=np.bool_)
    limit = m - TOL
    vec = np.empty(10)
    ang = np.empty(7)
    for q in range(arcs.shape[0]):
        i = arcs[q]
        if out[i]:
            continue
        k = edges[q]
        for r in range(5):
            ang[r] = phi[q, r]
        ang[5] = th0[i]
        ang[6] = dth[i]
        d = _arc_edge(c[i], rho[i], E0[i], E1[i], e0[k, 0], e0[k, 1], e1[k, 0], e1[k, 1], ang,
                      True, vec)
        if d < limit:
            out[i] = True
    return out


@njit(cache=True)
def _pairwise_sum(a: Array, lo: int, n: int) -> float:
    """``np.sum`` of a[lo:lo + n] (contiguous float64): numpy's pairwise summation (plain below
    8 terms, 8 running sums up to 128, halves above)."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[lo + i]
        return res
    if n <= 128:
        r = a[lo : lo + 8].copy()
        i = 8
        while i < n - (n % 8):
            for k in range(8):
                r[k] += a[lo + i + k]
            i += 8
        res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
        while i < n:
            res += a[lo + i]
            i += 1
        return res
    n2 = n // 2
    n2 -= n2 % 8
    return _pairwise_sum(a, lo, n2) + _pairwise_sum(a, lo + n2, n - n2)


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
