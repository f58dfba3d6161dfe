"""Compiled kernels (numba) of :func:`swarmpath.world.optimum.shortest_path`'s ``backend =
"numba"``: the arcs' checks (the world box and the polygons), for small scenes.

See :mod:`swarmpath.world.optimum_compiled` for the rule (the numpy code's operations in its
order, the same doubles). The trigonometry stays numpy's: the arcs' ends and the angles of the
in-arc tests are computed by numpy (on AVX-512 its cos, sin and arctan2 are not the C
library's); :func:`arcs_pending_kernel` bounds each (arc, edge) pair without the in-arc tests
(the least of a superset of the reference's candidate distances: never above the exact one), so
only the pairs that bound does not clear need angles, and :func:`arcs_decide_kernel` tests them
exactly.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

import swarmpath.optimizers.compiled  # noqa: F401 - first: numba's versioned cache directory
from swarmpath.world.optimum_base import _on_circle
from swarmpath.world.optimum_compiled import TOL, _point_segment

Array = np.ndarray
_f = np.ascontiguousarray


def arcs_near_polygons(scene: Any, c: Array, rho: Array, th0: Array, dth: Array, E0: Array,
                       E1: Array) -> Array:
    """The polygon part of ``_Scene.arcs_blocked`` (margin > 0, no index) for the arcs (c,
    rho, th0, dth) with ends E0, E1 (:func:`_ends`): the same pairs and distances as numpy
    (:func:`_arc_edge`); the angles of the in-arc tests come from numpy, computed as there."""
    c, rho = _f(c), _f(rho)
    e0, e1 = _f(scene.e0), _f(scene.e1)
    arcs, edges, vecs = arcs_pending_kernel(c, rho, E0, E1, scene.m, _f(scene.pc), _f(scene.pr),
                                            e0, e1, scene.starts, scene.counts)
    phi = np.arctan2(vecs[..., 0], vecs[..., 1])
    return np.asarray(arcs_decide_kernel(len(c), arcs, edges, _f(phi), c, rho, _f(th0), _f(dth),
                                         E0, E1, scene.m, e0, e1))


def arcs_blocked(scene: Any, c: Array, rho: Array, th0: Array, dth: Array) -> Array:
    """``_Scene.arcs_blocked`` of a scene without circles (margin > 0, no index): the world box
    (the arc's ends and its axis-extreme points on it: :func:`arcs_box_kernel`) and the
    polygons (:func:`arcs_near_polygons`), with the ends computed once by numpy."""
    E0, E1 = _ends(c, rho, th0, dth)
    blocked = np.zeros(len(c), dtype=bool)
    if scene.lo is not None:
        axes = np.arange(4) * (math.pi / 2)  # as arcs_blocked's: cos, sin by numpy
        box = np.concatenate([scene.lo - TOL, scene.hi + TOL])
        blocked = arcs_box_kernel(_f(c), _f(rho), _f(th0), _f(dth), E0, E1, box, axes,
                                  np.cos(axes), np.sin(axes))
    if scene.polygons and len(c):
        blocked |= arcs_near_polygons(scene, c, rho, th0, dth, E0, E1)
    return blocked


def _ends(c: Array, rho: Array, th0: Array, dth: Array) -> tuple[Array, Array]:
    """The arcs' start and end points (``_on_circle``: numpy's cos and sin)."""
    return _f(_on_circle(c, rho, th0)), _f(_on_circle(c, rho, th0 + dth))


@njit(cache=True)
def arcs_box_kernel(c: Array, rho: Array, th0: Array, dth: Array, E0: Array, E1: Array,
                    box: Array, axes: Array, cos: Array, sin: Array) -> Array:
    """The box part of ``_Scene.arcs_blocked``: an arc is out when an end is outside the box
    (grown by TOL) or one of its axis-extreme points (angle k pi / 2) lies on the arc and
    outside."""
    n = c.shape[0]
    out = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        if not (_in_box(E0[i, 0], E0[i, 1], box) and _in_box(E1[i, 0], E1[i, 1], box)):
            out[i] = True
            continue
        for k in range(4):
            x = c[i, 0] + rho[i] * cos[k]
            y = c[i, 1] + rho[i] * sin[k]
            if _in_arc(axes[k], th0[i], dth[i]) and not _in_box(x, y, box):
                out[i] = True
                break
    return out


@njit(cache=True)
def _in_box(x: float, y: float, box: Array) -> bool:
    return x >= box[0] and y >= box[1] and x <= box[2] and y <= box[3]


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
