"""The tangent graph's candidates for :mod:`swarmpath.world.optimum`: the disks a shortest path
can bend around (convex vertices of the union, circles, start and goal), their common tangents
with a local free-ness test at the ends, and the sampled arcs of the returned polyline."""

from __future__ import annotations

import math

import numpy as np

from swarmpath.world.geometry import ObstacleSet, point_polygon_distance
from swarmpath.world.optimum_base import (
    _CHUNK,
    TOL,
    Array,
    BoolArray,
    IntArray,
    _cross,
    _dot,
    _norm,
)


def _orthogonal(poly: Array) -> bool:
    e = np.roll(poly, -1, axis=0) - poly
    return bool(np.all((e[:, 0] == 0.0) | (e[:, 1] == 0.0)))


def _covered_vertices(
    points: Array, owner: IntArray, polygons: tuple[Array, ...], margin: float
) -> BoolArray:
    """Convex vertices no shortest path bends around although their own polygon is convex there.

    A vertex strictly inside another polygon (its whole disk is then closer than margin to that
    polygon). A vertex of an orthogonal polygon lying on another orthogonal polygon: near the
    vertex both are unions of axis-aligned quadrants, the other one covers at least one more
    quadrant, so the union is flat or reflex there (grid maps cut into touching parts, and cells
    meeting at a corner, produce exactly these vertices). Only with margin > 0: at margin 0 a path
    may pass through the point where two squares meet at a corner, and bend there.
    """
    out = np.zeros(len(points), dtype=bool)
    if len(polygons) < 2 or not len(points):
        return out
    lo = np.array([p.min(axis=0) for p in polygons]) - TOL
    hi = np.array([p.max(axis=0) for p in polygons]) + TOL
    ortho = np.array([_orthogonal(p) for p in polygons])
    step = max(1, _CHUNK // len(polygons))
    for a in range(0, len(points), step):
        pts = points[a : a + step]
        near = np.all((pts[:, None, :] >= lo) & (pts[:, None, :] <= hi), axis=-1)
        near[np.arange(len(pts)), owner[a : a + step]] = False
        vi, pj = np.nonzero(near)
        for j in np.unique(pj):
            sel = vi[pj == j]
            d = point_polygon_distance(pts[sel], polygons[int(j)])
            both = ortho[int(j)] & ortho[owner[a + sel]] & (margin > 0.0)
            out[a + sel[(d < -TOL) | ((np.abs(d) <= TOL) & both)]] = True
    return out


def _disks(
    start: Array, goal: Array, obstacles: ObstacleSet, margin: float
) -> tuple[Array, Array, Array, Array]:
    """Disks: centres, radii, and for polygon vertices the unit vectors towards both neighbours.

    Order: start, goal, inflated circles, convex polygon vertices (minus those of
    :func:`_covered_vertices`). The neighbour vectors are 0 for disks that are not polygon
    vertices.
    """
    centres = [start[None], goal[None]]
    radii = [np.zeros(2)]
    circ = obstacles.circles
    keep = circ[:, 2] + margin > 0.0  # a point obstacle at margin 0 bends no path
    centres.append(circ[keep, :2])
    radii.append(circ[keep, 2] + margin)
    n_plain = 2 + int(keep.sum())
    to_prev, to_next = [np.zeros((n_plain, 2))], [np.zeros((n_plain, 2))]
    vert: list[Array] = [np.zeros((0, 2))]
    owner: list[IntArray] = [np.zeros(0, dtype=np.intp)]
    na: list[Array] = []
    nb: list[Array] = []
    for j, poly in enumerate(obstacles.polygons):
        prev, nxt = np.roll(poly, 1, axis=0), np.roll(poly, -1, axis=0)
        area2 = float(np.sum(_cross(poly, nxt)))
        turn = _cross(poly - prev, nxt - poly) * math.copysign(1.0, area2)
        convex = turn > 0.0
        vert.append(poly[convex])
        owner.append(np.full(int(convex.sum()), j, dtype=np.intp))
        for out, other in ((na, prev), (nb, nxt)):
            u = other[convex] - poly[convex]
            out.append(u / _norm(u)[:, None])
    v = np.concatenate(vert)
    keep_v = ~_covered_vertices(v, np.concatenate(owner), obstacles.polygons, margin)
    centres.append(v[keep_v])
    radii.append(np.full(int(keep_v.sum()), float(margin)))
    to_prev.append(np.concatenate(na)[keep_v] if na else np.zeros((0, 2)))
    to_next.append(np.concatenate(nb)[keep_v] if nb else np.zeros((0, 2)))
    return (
        np.concatenate(centres),
        np.concatenate(radii),
        np.concatenate(to_prev),
        np.concatenate(to_next),
    )


def _locally_free(
    p: Array, q: Array, disk: IntArray, centres: Array, radii: Array, na: Array, nb: Array
) -> BoolArray:
    """Cheap necessary test at the end p (on ``disk``) of tangent segment p->q.

    On a vertex disk of radius margin > 0 the tangent point must lie in the vertex's normal cone
    (else it is closer than margin to an adjacent edge): (p - v).a <= 0 and (p - v).b <= 0 with
    a, b the unit vectors to the neighbouring vertices. On a zero-radius vertex (margin 0) the
    segment must be tangent to the polygon at v: both neighbours on one side of its line (a
    shortest path only bends around a vertex it wraps). Other disks always pass (a = b = 0).
    """
    rel = p - centres[disk]
    a, b = na[disk], nb[disk]
    cone = (_dot(rel, a) <= TOL) & (_dot(rel, b) <= TOL)
    d = q - p
    dn = _norm(d)
    d = d / np.where(dn > 0.0, dn, 1.0)[:, None]
    tangent = _cross(d, a) * _cross(d, b) >= -TOL
    return np.asarray(np.where(radii[disk] > 0.0, cone, tangent))


def _pair_rows(i0: int, i1: int, n: int) -> tuple[IntArray, IntArray]:
    """Pairs (i, j), i0 <= i < i1, i < j < n (rows of the upper triangle), vectorised."""
    rows = np.arange(i0, i1, dtype=np.intp)
    counts = n - 1 - rows
    ii = np.repeat(rows, counts)
    jj = ii + 1 + (np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts))
    return ii, jj.astype(np.intp)


def _tangents(
    centres: Array, radii: Array, ii: IntArray, jj: IntArray
) -> tuple[IntArray, IntArray, Array, Array]:
    """All common tangents of all disk pairs: disk indices i, j and tangent points on each.

    Line n.x = k with unit normal n touches disk i when n.c_i - k = s_i r_i, at c_i - s_i r_i n.
    With s_i = +1, s_j = +1 gives the outer and s_j = -1 the inner tangents, h = +-1 the two
    mirror images. A zero-radius disk (a point) only needs s_j = +1, two points only one line.
    """
    ci, cj, ri, rj = centres[ii], centres[jj], radii[ii], radii[jj]
    dv = cj - ci
    dist = _norm(dv)
    ok_pair = dist > TOL
    dsafe = np.where(ok_pair, dist, 1.0)
    v = dv / dsafe[:, None]
    vp = np.stack([-v[:, 1], v[:, 0]], axis=1)
    zero_i, zero_j = ri == 0.0, rj == 0.0
    I_, J_, P_, Q_ = [], [], [], []
    for s_j, h in ((1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)):
        delta = (s_j * rj - ri) / dsafe
        ok = ok_pair & (np.abs(delta) <= 1.0 + 1e-12)
        if s_j < 0:
            ok &= ~(zero_i | zero_j)
        if h < 0:
            ok &= ~(zero_i & zero_j)
        delta = np.clip(delta, -1.0, 1.0)
        n = delta[:, None] * v + (h * np.sqrt(1.0 - delta * delta))[:, None] * vp
        P_.append((ci - ri[:, None] * n)[ok])
        Q_.append((cj - (s_j * rj)[:, None] * n)[ok])
        I_.append(ii[ok])
        J_.append(jj[ok])
    return (
        np.concatenate(I_).astype(np.intp),
        np.concatenate(J_).astype(np.intp),
        np.concatenate(P_),
        np.concatenate(Q_),
    )


def _arc_points(c: Array, rho: float, th0: float, dth: float, arc_tol: float) -> Array:
    """Points strictly after the arc start up to and including its end (chord error <= arc_tol)."""
    step = 2.0 * math.acos(max(-1.0, 1.0 - arc_tol / rho)) if rho > 0 else math.pi
    n = max(1, math.ceil(abs(dth) / max(step, 1e-12)))
    th = th0 + dth * np.arange(1, n + 1) / n
    return np.asarray(c + rho * np.stack([np.cos(th), np.sin(th)], axis=1))

