"""Exact shortest collision-free path for a disk robot among circles and polygons (static maps).

The robot of radius ``margin`` is shrunk to a point and every obstacle is inflated by ``margin``:
a circle of radius R becomes a circle of radius R + margin; a polygon becomes its Minkowski sum
with a disk of radius ``margin``, whose boundary is the polygon's edges offset outwards joined by
circular arcs of radius ``margin`` centred on the convex vertices. Every inflated boundary that a
shortest path can bend around is therefore a union of circle arcs ("disks"):

* one disk (c, R + margin) per circle obstacle,
* one disk (v, margin) per convex polygon vertex v (reflex and flat vertices never carry a
  shortest path: the free space is locally convex there),
* the start and the goal as disks of radius 0.

A shortest path in the plane among such obstacles is a chain of straight segments that are common
tangents of two disks (point-to-disk tangents at the start and goal) joined by arcs along one
disk. The *tangent graph* has a node per tangent point, an edge per collision-free common tangent
and an edge per collision-free arc between consecutive tangent points on the same disk; Dijkstra
on it gives the exact optimum. With margin 0 the vertex disks have radius 0 and the construction
reduces to the classic visibility graph over polygon vertices (plus circle tangents).

Validity of an edge is decided against the *original* obstacles: a segment or arc is free when
its distance to every obstacle is >= margin - 1e-9 (``TOL``), so tangent segments (distance
exactly ``margin``) are accepted. Arcs are checked exactly (closed-form arc-to-circle and
arc-to-segment distances), not by sampling. With margin 0 a distance test cannot tell a chord
through a polygon from a segment touching it, so segments and arcs that touch a polygon are split
at the touching points and each piece is tested for lying strictly inside. The returned length is
therefore the infimum over paths whose clearance is >= margin, i.e. paths that may touch the
inflated obstacles; under the product's collision rule (touching counts) it is a lower bound that
collision-free paths approach arbitrarily closely.

World box
---------
``world = (xmin, ymin, xmax, ymax)`` constrains the robot *centre* (shrink it by the radius
yourself if the walls are obstacles for the body). Tangent points outside the box are discarded
and so are arcs that leave it (checked exactly with the arc's axis-aligned extreme points). This
keeps the answer exact: the box is convex, so a shortest path inside it bends only around
obstacle boundary points that lie inside the box, and all of its tangent points and arcs survive
the pruning. Start or goal outside the box, or inside an inflated obstacle (clearance < margin -
1e-9), raise ``ValueError`` naming the point and the obstacle.

Scale
-----
Only convex vertices of the *union* carry paths: a convex polygon vertex strictly inside another
polygon, or (margin > 0) lying on another polygon when both are orthogonal (the touching parts of
an imported grid map), is dropped (:func:`_covered_vertices`). Disk pairs are processed in chunks
(bounded memory). Above ``INDEX_ABOVE`` disks the spatial index of
:mod:`swarmpath.world.optimum_index` decides pairs, segments and arcs exactly without testing
every edge: raster clearance bounds, edge buckets, and a pair prefilter (the centre segment of
two vertex disks through an obstacle's interior blocks all four tangents).

Limits
------
``budget`` (default ``DEFAULT_BUDGET`` = 30 s of wall time) and ``max_disks`` (default 20,000):
past either, the result has ``length = nan``, ``exact = False`` and a ``reason`` that says which
limit and how far the search got. If no collision-free path exists the length is ``inf``
(``exact = True``). At margin 0 separate polygons that share an edge are separate closed sets:
a path may run along the shared edge.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from swarmpath.world.geometry import (
    ObstacleSet,
    point_polygon_distance,
    point_segment_distance,
    segment_segment_distance,
)
from swarmpath.world.optimum_index import EdgeIndex

Array = NDArray[np.float64]
IntArray = NDArray[np.intp]
BoolArray = NDArray[np.bool_]

__all__ = ["DEFAULT_BUDGET", "MAX_DISKS", "TOL", "OptimalPath", "shortest_path"]

TOL = 1e-9
MAX_DISKS = 20_000
DEFAULT_BUDGET = 30.0  # s of wall time (a loaded machine shares its cores)
INDEX_ABOVE = 600  # disks above which the spatial index decides pairs, segments and arcs
_PAIRS = 1 << 17  # disk pairs per chunk
TWO_PI = 2.0 * math.pi
_CHUNK = 1 << 18  # work items (pair x obstacle or pair x edge) per numpy batch
_NEAR_FIRST = 16  # above this many circles, test each segment against nearby ones first
_BUCKET = 6  # circles kept per grid cell for that pre-pass
_SIDE = 1e-7  # margin 0: offset used to see obstacle on both sides of a segment
_TINY_WEIGHT = 1e-300  # zero-length edges must stay edges in the sparse graph

World = tuple[float, float, float, float]


@dataclass(frozen=True, eq=False)
class OptimalPath:
    """Result of :func:`shortest_path`.

    length: optimum length (m); ``inf`` if no path exists, ``nan`` if not computed.
    points: (n, 2) polyline from start to goal, arcs sampled so that the chord error is at most
        ``arc_tol`` (the polyline lies on or inside the exact arcs by that much).
    exact: True if ``length`` is the exact optimum (up to the 1e-9 m tangency tolerance).
    reason: why the result is not exact / not available, else None.
    """

    length: float
    points: Array
    exact: bool
    reason: str | None = None


# ----------------------------------------------------------------------------- small helpers


def _cross(u: Array, v: Array) -> Array:
    return np.asarray(u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0], dtype=np.float64)


def _dot(u: Array, v: Array) -> Array:
    return np.asarray(u[..., 0] * v[..., 0] + u[..., 1] * v[..., 1], dtype=np.float64)


def _norm(u: Array) -> Array:
    return np.asarray(np.hypot(u[..., 0], u[..., 1]), dtype=np.float64)


def _in_arc(phi: Array, th0: Array, dth: Array) -> BoolArray:
    """Angle phi lies on the arc starting at th0 and sweeping dth >= 0 counter-clockwise."""
    return np.asarray(np.mod(phi - th0, TWO_PI) <= dth + 1e-12)


def _on_circle(c: Array, rho: Array, th: Array) -> Array:
    return np.asarray(c + rho[..., None] * np.stack([np.cos(th), np.sin(th)], axis=-1))


def _point_arc_distance(q: Array, c: Array, rho: Array, th0: Array, dth: Array) -> Array:
    """Exact distance from points q to arcs (centre c, radius rho, from th0 sweeping dth ccw)."""
    w = q - c
    r = _norm(w)
    phi = np.arctan2(w[..., 1], w[..., 0])
    d_end = np.minimum(_norm(q - _on_circle(c, rho, th0)), _norm(q - _on_circle(c, rho, th0 + dth)))
    radial = np.where(_in_arc(phi, th0, dth), np.abs(r - rho), np.inf)
    return np.asarray(np.minimum(d_end, radial))


def _arc_segment_distance(
    c: Array, rho: Array, th0: Array, dth: Array, a: Array, b: Array
) -> Array:
    """Exact distance between arcs and closed segments ab (all inputs broadcast together).

    The minimum is attained either at an end of one of the two curves, at an intersection (0), or
    at the foot f of the perpendicular from the centre onto the segment paired with the arc
    point on the ray c->f. Every candidate below is the distance of a real pair of points, so the
    minimum over them is exact.
    """
    e0 = _on_circle(c, rho, th0)
    e1 = _on_circle(c, rho, th0 + dth)
    best = np.minimum(
        np.minimum(
            _point_arc_distance(a, c, rho, th0, dth), _point_arc_distance(b, c, rho, th0, dth)
        ),
        np.minimum(point_segment_distance(e0, a, b), point_segment_distance(e1, a, b)),
    )
    e = b - a
    ee = _dot(e, e)
    safe = np.where(ee > 0.0, ee, 1.0)
    t = np.clip(_dot(c - a, e) / safe, 0.0, 1.0)
    f = a + t[..., None] * e
    wf = f - c
    rf = _norm(wf)
    ok = _in_arc(np.arctan2(wf[..., 1], wf[..., 0]), th0, dth) & (rf > 0.0)
    best = np.minimum(best, np.where(ok, np.abs(rf - rho), np.inf))
    # Intersections of the segment with the full circle, kept if they lie on the arc.
    ac = a - c
    bq = 2.0 * _dot(e, ac)
    cq = _dot(ac, ac) - rho * rho
    disc = bq * bq - 4.0 * ee * cq
    has = (ee > 0.0) & (disc >= 0.0)
    sq = np.sqrt(np.where(has, disc, 0.0))
    for sign in (-1.0, 1.0):
        tt = (-bq + sign * sq) / (2.0 * safe)
        p = a + tt[..., None] * e - c
        hit = has & (tt >= 0.0) & (tt <= 1.0) & _in_arc(np.arctan2(p[..., 1], p[..., 0]), th0, dth)
        best = np.where(hit, 0.0, best)
    return np.asarray(best)


def _expand_csr(
    items: IntArray, counts: IntArray, first: IntArray, col: IntArray
) -> tuple[IntArray, IntArray]:
    """Pairs (item, col[first[i] + r]) for r < counts[i]: a CSR row gather, vectorised."""
    rep = np.repeat(items, counts)
    starts = np.repeat(first - (np.cumsum(counts) - counts), counts)
    return rep, col[starts + np.arange(len(rep))]


def _chunks_by_weight(weights: IntArray, budget: int) -> list[slice]:
    """Split range(len(weights)) into consecutive slices whose weight sums stay near budget."""
    if len(weights) == 0:
        return []
    cum = np.cumsum(weights)
    out: list[slice] = []
    lo = 0
    while lo < len(weights):
        base = cum[lo - 1] if lo else 0
        hi = int(np.searchsorted(cum, base + budget, side="right"))
        hi = max(hi, lo + 1)
        out.append(slice(lo, hi))
        lo = hi
    return out


# ----------------------------------------------------------------------------- collision checks


class _Scene:
    """Obstacles, margin and world box with batched exact free-ness tests for segments and arcs."""

    def __init__(
        self, obstacles: ObstacleSet, margin: float, world: World | None,
        index: EdgeIndex | None = None,
    ) -> None:
        self.index = index
        self.obstacles = obstacles
        self.circles = obstacles.circles
        self.polygons = obstacles.polygons
        self.m = float(margin)
        self.lo = None if world is None else np.array(world[:2], dtype=np.float64)
        self.hi = None if world is None else np.array(world[2:], dtype=np.float64)
        polys = self.polygons
        self.counts = np.array([len(p) for p in polys], dtype=np.intp)
        self.starts = np.concatenate([[0], np.cumsum(self.counts)[:-1]]).astype(np.intp)
        if polys:
            self.e0 = np.concatenate(polys)
            self.e1 = np.concatenate([np.roll(p, -1, axis=0) for p in polys])
            self.pc = np.array([p.mean(axis=0) for p in polys])
            self.pr = np.array([_norm(p - p.mean(axis=0)).max() for p in polys])
            grow = self.m + TOL
            self.bb_lo = np.array([p.min(axis=0) for p in polys]) - grow
            self.bb_hi = np.array([p.max(axis=0) for p in polys]) + grow
        else:
            self.e0 = self.e1 = self.pc = self.bb_lo = self.bb_hi = np.zeros((0, 2))
            self.pr = np.zeros(0)
        # Fixed pseudo-random visiting order for early elimination (no global RNG state).
        order_rng = np.random.default_rng(0)
        self.circle_order = order_rng.permutation(len(self.circles))
        self._build_circle_buckets()
        self.polygon_order = order_rng.permutation(len(polys))

    def _build_circle_buckets(self) -> None:
        """Uniform grid: for each cell, up to _BUCKET circles that could block a point in it."""
        circ, k = self.circles, len(self.circles)
        self._circles_pad = np.vstack([circ, [[0.0, 0.0, -self.m - 1.0]]])  # row k never blocks
        if k <= _NEAR_FIRST:
            return
        reach = circ[:, 2] + self.m
        lo = circ[:, :2].min(axis=0) - reach.max()
        hi = circ[:, :2].max(axis=0) + reach.max()
        # ~2 circles per cell; at most 128 cells per axis even for degenerate (collinear) sets
        h = max(float(np.sqrt(np.prod(hi - lo) / k)) * 1.5, float(np.max(hi - lo)) / 128, 1e-9)
        shape = np.maximum(np.ceil((hi - lo) / h).astype(np.intp), 1)
        gx, gy = np.meshgrid(np.arange(shape[0]), np.arange(shape[1]), indexing="ij")
        cell_lo = lo + h * np.column_stack([gx.ravel(), gy.ravel()])
        # distance from each circle centre to each cell rectangle
        dx = np.maximum(
            np.maximum(cell_lo[:, None, 0] - circ[:, 0], circ[:, 0] - cell_lo[:, None, 0] - h), 0.0
        )
        dy = np.maximum(
            np.maximum(cell_lo[:, None, 1] - circ[:, 1], circ[:, 1] - cell_lo[:, None, 1] - h), 0.0
        )
        close = np.hypot(dx, dy) < reach
        ranked = np.argsort(~close, axis=1, kind="stable")[:, :_BUCKET]
        table = np.where(np.take_along_axis(close, ranked, axis=1), ranked, k)
        self._grid = (lo, h, shape, table)

    def _bucket(self, P: Array) -> IntArray:
        lo, h, shape, table = self._grid
        ij = np.clip(np.floor((P - lo) / h).astype(np.intp), 0, shape - 1)
        return np.asarray(table[ij[:, 0] * shape[1] + ij[:, 1]])

    # -- box
    def in_box(self, P: Array) -> BoolArray:
        if self.lo is None or self.hi is None:
            return np.ones(P.shape[:-1], dtype=bool)
        return np.asarray(np.all((P >= self.lo - TOL) & (P <= self.hi + TOL), axis=-1))

    # -- start / goal
    def blocker(self, p: Array) -> str | None:
        """Name of an obstacle whose inflation contains p (clearance < margin - TOL), or None."""
        if len(self.circles):
            d = _norm(self.circles[:, :2] - p) - self.circles[:, 2]
            i = int(np.argmin(d))
            if d[i] < self.m - TOL:
                return f"circle {i} (clearance {d[i]:.6g} < margin {self.m:g})"
        for j, poly in enumerate(self.polygons):
            dj = float(point_polygon_distance(p, poly))
            if dj < self.m - TOL:
                return f"polygon {j} (clearance {dj:.6g} < margin {self.m:g})"
        return None

    # -- pair expansion: candidate (item, polygon) pairs -> (item, edge) work items
    def _expand(self, pj: IntArray) -> tuple[IntArray, IntArray, IntArray]:
        counts = self.counts[pj]
        offsets = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.intp)
        rep = np.repeat(np.arange(len(pj)), counts)
        eidx = self.starts[pj][rep] + (np.arange(int(counts.sum())) - offsets[rep])
        return rep, eidx, offsets

    # -- segments
    def segments_blocked(self, A: Array, B: Array) -> BoolArray:
        """True where the closed segment AB is not free (A == B tests a point).

        Obstacles are visited in a fixed shuffled order, a few at a time, and segments drop out
        as soon as one obstacle blocks them: in clutter most candidate tangents are blocked by
        some obstacle early, which keeps the work far below segments x obstacles.
        """
        blocked = ~(self.in_box(A) & self.in_box(B))
        active = np.flatnonzero(~blocked)
        k = len(self.circles)
        if k > _NEAR_FIRST and len(active):
            # Pre-pass: each segment against the circles bucketed near a few of its points, in
            # stages (a heuristic that only orders the work; the full pass below decides).
            for fractions in ((0.5,), (0.25, 0.75), (0.1, 0.4, 0.6, 0.9)):
                a, e = A[active], B[active] - A[active]
                near = np.concatenate([self._bucket(a + f * e) for f in fractions], axis=1)
                hit = np.any(self._circle_hits(a, a + e, self._circles_pad[near]), axis=1)
                blocked[active[hit]] = True
                active = active[~hit]
        lo = 0
        while lo < k and len(active):
            width = int(np.clip(_CHUNK // len(active), 8, k))
            cc = self.circles[self.circle_order[lo : lo + width]]
            lo += width
            hit = np.any(self._circle_hits(A[active], B[active], cc), axis=1)
            blocked[active[hit]] = True
            active = active[~hit]
        p = len(self.polygons)
        if self.index is not None and len(active):
            blocked[active[self.index.segments_blocked(A[active], B[active])]] = True
            return blocked
        lo = 0
        while lo < p and len(active):
            width = int(np.clip(_CHUNK // len(active), 4, p))
            pjs = self.polygon_order[lo : lo + width]
            lo += width
            s_lo = np.minimum(A[active], B[active])[:, None, :]
            s_hi = np.maximum(A[active], B[active])[:, None, :]
            near = np.all((s_lo <= self.bb_hi[pjs]) & (s_hi >= self.bb_lo[pjs]), axis=-1)
            si, pk = np.nonzero(near)
            pj = pjs[pk]
            hit = np.zeros(len(active), dtype=bool)
            for sl in _chunks_by_weight(self.counts[pj], _CHUNK):
                seg = active[si[sl]]
                h = self._segment_polygon_pairs(A[seg], B[seg], pj[sl])
                hit[si[sl][h]] = True
            blocked[active[hit]] = True
            active = active[~hit]
        if self.m == 0.0 and len(self.polygons) > 1 and len(active):
            blocked[active[self._between_touching_polygons(A[active], B[active])]] = True
        return blocked

    def _between_touching_polygons(self, A: Array, B: Array) -> BoolArray:
        """Margin 0: segments that run along a boundary shared by two touching polygons.

        Each polygon alone is a closed set the segment only touches, but their union has the
        shared edge in its interior. The segment is split at the polygon vertices lying on it and
        each piece is blocked if both points at +-_SIDE off its midpoint are inside obstacles.
        """
        out = np.zeros(len(A), dtype=bool)
        e = B - A
        length = _norm(e)
        n = np.stack([-e[:, 1], e[:, 0]], axis=1) / np.where(length > 0, length, 1.0)[:, None]
        verts = self.e0
        step = max(1, _CHUNK // len(verts))
        for lo in range(0, len(A), step):
            sl = slice(lo, lo + step)
            d = point_segment_distance(verts, A[sl, None, :], B[sl, None, :])
            t = (
                _dot(verts - A[sl, None, :], e[sl, None, :])
                / np.where(length[sl] > 0, length[sl] ** 2, 1.0)[:, None]
            )
            lsl = length[sl, None]
            on = (d <= TOL) & (t * lsl > TOL) & ((1.0 - t) * lsl > TOL)
            simple = np.flatnonzero(~on.any(axis=1) & (length[sl] > TOL))
            g = lo + simple
            mids = 0.5 * (A[g] + B[g])
            inside_p = self.obstacles.point_clearance(mids + _SIDE * n[g]) < -0.5 * _SIDE
            inside_m = self.obstacles.point_clearance(mids - _SIDE * n[g]) < -0.5 * _SIDE
            out[g] = inside_p & inside_m
            for q in np.flatnonzero(on.any(axis=1)):
                g1 = lo + int(q)
                ts = np.sort(np.concatenate([[0.0, 1.0], t[q][on[q]]]))
                mids = A[g1] + (0.5 * (ts[:-1] + ts[1:]))[:, None] * e[g1]
                side = np.concatenate([mids + _SIDE * n[g1], mids - _SIDE * n[g1]])
                inside = self.obstacles.point_clearance(side) < -0.5 * _SIDE
                out[g1] = bool(np.any(inside[: len(mids)] & inside[len(mids) :]))
        return out

    def _circle_hits(self, A: Array, B: Array, cc: Array) -> BoolArray:
        """(s, w): segment s (A, B: (s, 2)) comes closer than margin - TOL to circle cc[s, w].

        ``cc`` is (w, 3) (the same circles for every segment) or (s, w, 3). Squared distances on
        separate x / y planes keep this kernel cheap; it runs on segments x circles.
        """
        ax, ay = A[:, 0:1], A[:, 1:2]
        ex, ey = B[:, 0:1] - ax, B[:, 1:2] - ay
        ee = ex * ex + ey * ey
        inv = np.where(ee > 0.0, 1.0 / np.where(ee > 0.0, ee, 1.0), 0.0)
        wx, wy = cc[..., 0] - ax, cc[..., 1] - ay
        t = np.clip((wx * ex + wy * ey) * inv, 0.0, 1.0)
        dx, dy = wx - t * ex, wy - t * ey
        reach = cc[..., 2] + (self.m - TOL)
        return np.asarray((reach > 0.0) & (dx * dx + dy * dy < reach * reach))

    def _segment_polygon_pairs(self, A: Array, B: Array, pj: IntArray) -> BoolArray:
        rep, eidx, offsets = self._expand(pj)
        a, b, c, d = A[rep], B[rep], self.e0[eidx], self.e1[eidx]
        dist = segment_segment_distance(a, b, c, d)
        dmin = np.minimum.reduceat(dist, offsets)
        if self.m > 0.0:
            return np.asarray(dmin < self.m - TOL)
        return self._segment_polygon_pairs_margin0(A, B, pj, a, b, c, d, rep, offsets, dmin)

    def _segment_polygon_pairs_margin0(
        self,
        A: Array,
        B: Array,
        pj: IntArray,
        a: Array,
        b: Array,
        c: Array,
        d: Array,
        rep: IntArray,
        offsets: IntArray,
        dmin: Array,
    ) -> BoolArray:
        """Margin 0: blocked iff the segment meets the polygon's interior."""
        ab, cd = b - a, d - c
        lab, lcd = _norm(ab), _norm(cd)
        o1, o2 = _cross(ab, c - a), _cross(ab, d - a)
        o3, o4 = _cross(cd, a - c), _cross(cd, b - c)
        proper = (
            (o1 * o2 < 0.0)
            & (o3 * o4 < 0.0)
            & (np.abs(o1) > TOL * lab)
            & (np.abs(o2) > TOL * lab)
            & (np.abs(o3) > TOL * lcd)
            & (np.abs(o4) > TOL * lcd)
        )
        safe = np.where(lab > 0.0, lab * lab, 1.0)
        t = _dot(c - a, ab) / safe
        on_open = (np.abs(o1) <= TOL * lab) & (t * lab > TOL) & ((1.0 - t) * lab > TOL)
        mid = 0.5 * (a + b)
        ray = ((c[:, 1] > mid[:, 1]) != (d[:, 1] > mid[:, 1])) & (
            mid[:, 0]
            < c[:, 0] + (mid[:, 1] - c[:, 1]) * cd[:, 0] / np.where(cd[:, 1] != 0.0, cd[:, 1], 1.0)
        )
        dmid = point_segment_distance(mid, c, d)
        any_proper = np.add.reduceat(proper.astype(np.intp), offsets) > 0
        any_on = np.add.reduceat(on_open.astype(np.intp), offsets) > 0
        mid_in = (np.add.reduceat(ray.astype(np.intp), offsets) % 2 == 1) & (
            np.minimum.reduceat(dmid, offsets) > TOL
        )
        out = any_proper | (~any_on & mid_in)
        # Rare: polygon vertices on the open segment. Test every piece between them.
        for q in np.flatnonzero(any_on & ~any_proper):
            poly = self.polygons[int(pj[q])]
            ts = np.sort(np.concatenate([[0.0, 1.0], t[rep == q][on_open[rep == q]]]))
            mids = A[q] + (0.5 * (ts[:-1] + ts[1:]))[:, None] * (B[q] - A[q])
            out[q] = bool(np.any(point_polygon_distance(mids, poly) < -TOL))
        return np.asarray(out)

    # -- arcs
    def arcs_blocked(self, c: Array, rho: Array, th0: Array, dth: Array) -> BoolArray:
        """True where the arc (centre c, radius rho, from th0 sweeping dth ccw) is not free."""
        n = len(c)
        blocked = np.zeros(n, dtype=bool)
        if self.lo is not None:
            ends = np.stack([th0, th0 + dth], axis=1)
            axes = np.broadcast_to(np.arange(4) * (math.pi / 2), (n, 4))
            inside = self.in_box(_on_circle(c[:, None, :], rho[:, None], ends)).all(axis=1)
            ext_ok = self.in_box(_on_circle(c[:, None, :], rho[:, None], axes))
            ext_on = _in_arc(axes, th0[:, None], dth[:, None])
            blocked |= ~inside | np.any(ext_on & ~ext_ok, axis=1)
        k = len(self.circles)
        if k and n:
            # Only circles that overlap the arc's whole inflated disk can come within margin.
            disks, inv = np.unique(np.column_stack([c, rho]), axis=0, return_inverse=True)
            inv = inv.reshape(-1)
            gap = _norm(self.circles[None, :, :2] - disks[:, None, :2])
            near = gap < disks[:, 2:3] + self.circles[:, 2] + self.m
            row_counts = near.sum(axis=1).astype(np.intp)
            row_ptr = np.concatenate([[0], np.cumsum(row_counts)[:-1]]).astype(np.intp)
            col = np.nonzero(near)[1]
            counts = row_counts[inv]
            for sl in _chunks_by_weight(counts, _CHUNK):
                arcs = np.arange(n)[sl]
                rep, cj = _expand_csr(arcs, counts[arcs], row_ptr[inv[arcs]], col)
                if not len(rep):
                    continue
                d = _point_arc_distance(self.circles[cj, :2], c[rep], rho[rep], th0[rep], dth[rep])
                hit = d - self.circles[cj, 2] < self.m - TOL
                blocked[rep[hit]] = True
        if not self.polygons:
            return blocked
        idx = np.flatnonzero(~blocked)
        if self.index is not None:
            small = rho[idx] <= self.m + TOL  # vertex disks: the edge buckets around the centre
            ii = idx[small]
            ai, ej = self.index.near_edges(c[ii])
            for lo in range(0, len(ai), _CHUNK):
                a_, e_ = ii[ai[lo : lo + _CHUNK]], ej[lo : lo + _CHUNK]
                dist = _arc_segment_distance(
                    c[a_], rho[a_], th0[a_], dth[a_], self.index.e0[e_], self.index.e1[e_]
                )
                blocked[a_[dist < self.m - TOL]] = True
            idx = idx[~small]
        step = max(1, _CHUNK // len(self.polygons))
        for lo in range(0, len(idx), step):
            ii = idx[lo : lo + step]
            dc = _norm(self.pc - c[ii, None, :])
            near = dc <= rho[ii, None] + self.pr + self.m + TOL
            si, pj = np.nonzero(near)
            for sl in _chunks_by_weight(self.counts[pj], _CHUNK):
                arc = ii[si[sl]]
                rep, eidx, offsets = self._expand(pj[sl])
                ar = arc[rep]
                dist = _arc_segment_distance(
                    c[ar], rho[ar], th0[ar], dth[ar], self.e0[eidx], self.e1[eidx]
                )
                dmin = np.minimum.reduceat(dist, offsets)
                if self.m > 0.0:
                    blocked[arc[dmin < self.m - TOL]] = True
                    continue
                # Margin 0: arcs that touch a polygon are split where they meet its edges.
                for q in np.flatnonzero(dmin <= TOL):
                    blocked[arc[q]] |= self._arc_enters_polygon(
                        c[arc[q]], rho[arc[q]], th0[arc[q]], dth[arc[q]], int(pj[sl][q])
                    )
        return blocked

    def _arc_enters_polygon(self, c: Array, rho: float, th0: float, dth: float, j: int) -> bool:
        poly = self.polygons[j]
        a, b = poly, np.roll(poly, -1, axis=0)
        e = b - a
        ee = _dot(e, e)
        ac = a - c
        bq = 2.0 * _dot(e, ac)
        cq = _dot(ac, ac) - rho * rho
        disc = bq * bq - 4.0 * ee * cq
        cuts = [0.0, dth]
        for sign in (-1.0, 1.0):
            tt = (-bq + sign * np.sqrt(np.maximum(disc, 0.0))) / (2.0 * ee)
            ok = (disc >= 0.0) & (tt >= -TOL) & (tt <= 1.0 + TOL)
            p = a[ok] + tt[ok, None] * e[ok] - c
            s = np.mod(np.arctan2(p[:, 1], p[:, 0]) - th0, TWO_PI)
            cuts.extend(float(x) for x in s[s <= dth])
        ts = np.sort(np.asarray(cuts))
        mids = th0 + 0.5 * (ts[:-1] + ts[1:])
        pts = c + rho * np.stack([np.cos(mids), np.sin(mids)], axis=1)
        return bool(np.any(point_polygon_distance(pts, poly) < -TOL))


# ----------------------------------------------------------------------------- tangent graph


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


def shortest_path(
    start: ArrayLike,
    goal: ArrayLike,
    obstacles: ObstacleSet,
    margin: float,
    world: World | None = None,
    *,
    max_disks: int = MAX_DISKS,
    arc_tol: float = 1e-7,
    budget: float | None = DEFAULT_BUDGET,
    progress: Callable[[float], None] | None = None,
    index: bool | None = None,
) -> OptimalPath:
    """Exact shortest path from start to goal for a disk robot of radius ``margin``.

    See the module docstring for the method, the tolerance, the world-box handling and the
    limits. ``budget``: seconds of wall time after which the search gives up (``None``: no
    limit); ``progress(fraction)`` is called as the tangent pairs are processed; ``index``: use
    the spatial index of :mod:`swarmpath.world.optimum_index` (``None``: when there are more than
    ``INDEX_ABOVE`` disks; only with margin > 0 and polygons). Raises ValueError if start or
    goal is outside ``world`` or inside an inflated obstacle.
    """
    started = time.perf_counter()
    s = np.asarray(start, dtype=np.float64).reshape(2)
    g = np.asarray(goal, dtype=np.float64).reshape(2)
    if not (math.isfinite(margin) and margin >= 0.0):
        raise ValueError(f"margin must be finite and >= 0, got {margin}")
    scene = _Scene(obstacles, margin, world)
    for name, p in (("start", s), ("goal", g)):
        if not bool(scene.in_box(p)):
            raise ValueError(f"{name} {p.tolist()} is outside the world box {world}")
        who = scene.blocker(p)
        if who is not None:
            raise ValueError(f"{name} {p.tolist()} is inside the inflated {who}")

    if not scene.segments_blocked(s[None], g[None])[0]:
        return OptimalPath(float(_norm(g - s)), np.stack([s, g]), True, None)

    centres, radii, na, nb = _disks(s, g, obstacles, margin)
    if len(centres) - 2 > max_disks:
        return OptimalPath(
            math.nan,
            np.zeros((0, 2)),
            False,
            f"{len(centres) - 2} disks (convex vertices and circles) exceed "
            f"max_disks={max_disks:,}; optimum not computed (raise max_disks)",
        )

    use_index = (len(centres) > INDEX_ABOVE) if index is None else bool(index)
    edge_index = None
    if use_index and margin > 0.0 and obstacles.polygons:
        pts = [centres, *obstacles.polygons]
        if len(obstacles.circles):
            pts.append(obstacles.circles[:, :2] - obstacles.circles[:, 2:3])
            pts.append(obstacles.circles[:, :2] + obstacles.circles[:, 2:3])
        allp = np.concatenate(pts)
        lo, hi = allp.min(axis=0), allp.max(axis=0)
        edge_index = EdgeIndex(list(obstacles.polygons), (lo[0], lo[1], hi[0], hi[1]), margin, TOL)
        scene.index = edge_index

    # Tangent candidates, pruned by a local test at their ends (cheap), then as segments; in
    # chunks of disk pairs so that memory stays bounded and the budget is checked regularly.
    n_disks = len(centres)
    n_pairs = n_disks * (n_disks - 1) // 2
    found: list[tuple[IntArray, IntArray, Array, Array]] = []
    done = 0
    i0 = 0
    while i0 < n_disks - 1:
        if budget is not None and time.perf_counter() - started > budget:
            return OptimalPath(
                math.nan, np.zeros((0, 2)), False,
                f"time budget of {budget:g} s exhausted after {done:,} of {n_pairs:,} disk "
                f"pairs ({n_disks - 2:,} disks); optimum not computed (raise the budget)",
            )
        i1 = i0 + 1  # rows i0 .. i1 - 1 of the upper triangle: about _PAIRS pairs
        while i1 < n_disks - 1 and (n_disks - i0) * (i1 + 1 - i0) <= _PAIRS:
            i1 += 1
        ii, jj = _pair_rows(i0, i1, n_disks)
        done += len(ii)
        if edge_index is not None:  # small disks whose centre line crosses an interior
            small = (radii[ii] <= margin + TOL) & (radii[jj] <= margin + TOL)
            drop = np.zeros(len(ii), dtype=bool)
            drop[small] = edge_index.pairs_blocked(centres[ii[small]], centres[jj[small]])
            ii, jj = ii[~drop], jj[~drop]
        ti, tj, tp, tq = _tangents(centres, radii, ii, jj)
        ok = _locally_free(tp, tq, ti, centres, radii, na, nb)
        ok &= _locally_free(tq, tp, tj, centres, radii, na, nb)
        ti, tj, tp, tq = ti[ok], tj[ok], tp[ok], tq[ok]
        ok = ~scene.segments_blocked(tp, tq)
        found.append((ti[ok], tj[ok], tp[ok], tq[ok]))
        if progress is not None:
            progress(done / max(n_pairs, 1))
        i0 = i1
    ti = np.concatenate([f[0] for f in found]) if found else np.zeros(0, dtype=np.intp)
    tj = np.concatenate([f[1] for f in found]) if found else np.zeros(0, dtype=np.intp)
    tp = np.concatenate([f[2] for f in found]) if found else np.zeros((0, 2))
    tq = np.concatenate([f[3] for f in found]) if found else np.zeros((0, 2))

    # Nodes: one per zero-radius disk (start = 0, goal = 1), one per tangent end on other disks.
    zero = np.flatnonzero(radii == 0.0)
    zero_node = np.full(len(radii), -1, dtype=np.intp)
    zero_node[zero] = np.arange(len(zero))
    m = len(ti)
    pos = radii > 0.0
    node_u = np.where(pos[ti], len(zero) + np.arange(m), zero_node[ti])
    node_v = np.where(pos[tj], len(zero) + m + np.arange(m), zero_node[tj])
    n_nodes = len(zero) + 2 * m
    node_xy = np.zeros((n_nodes, 2))
    node_xy[zero_node[zero]] = centres[zero]
    node_xy[node_u] = tp
    node_xy[node_v] = tq
    node_disk = np.full(n_nodes, -1, dtype=np.intp)
    node_disk[zero_node[zero]] = zero
    node_disk[node_u] = ti
    node_disk[node_v] = tj

    # Arc candidates: consecutive tangent points (by angle) around each positive-radius disk.
    on_pos = np.flatnonzero((node_disk >= 0) & pos[np.maximum(node_disk, 0)])
    rel = node_xy[on_pos] - centres[node_disk[on_pos]]
    ang = np.mod(np.arctan2(rel[:, 1], rel[:, 0]), TWO_PI)
    order = np.lexsort((ang, node_disk[on_pos]))
    nodes_sorted, disk_sorted, ang_sorted = on_pos[order], node_disk[on_pos][order], ang[order]
    nxt = np.arange(1, len(order) + 1)
    first = np.ones(len(order), dtype=bool)
    first[1:] = disk_sorted[1:] != disk_sorted[:-1]
    last = np.ones(len(order), dtype=bool)
    last[:-1] = disk_sorted[1:] != disk_sorted[:-1]
    group_first = np.maximum.accumulate(np.where(first, np.arange(len(order)), 0))
    nxt = np.where(last, group_first, nxt)
    single = first & last
    au, av = nodes_sorted[~single], nodes_sorted[nxt[~single]]
    adisk = disk_sorted[~single]
    ath0 = ang_sorted[~single]
    adth = np.mod(ang_sorted[nxt[~single]] - ath0, TWO_PI)
    arc_ok = ~scene.arcs_blocked(centres[adisk], radii[adisk], ath0, adth)
    au, av, adisk, ath0, adth = au[arc_ok], av[arc_ok], adisk[arc_ok], ath0[arc_ok], adth[arc_ok]

    # Graph: tangent edges then arc edges; keep the lightest edge per node pair.
    eu = np.concatenate([node_u, au])
    ev = np.concatenate([node_v, av])
    ew = np.concatenate([_norm(tq - tp), radii[adisk] * adth])
    lo_, hi_ = np.minimum(eu, ev), np.maximum(eu, ev)
    keep = lo_ != hi_
    key = lo_.astype(np.int64) * n_nodes + hi_
    srt = np.lexsort((ew, key))
    srt = srt[keep[srt]]
    uniq = np.ones(len(srt), dtype=bool)
    uniq[1:] = key[srt][1:] != key[srt][:-1]
    sel = srt[uniq]
    graph = coo_matrix(
        (np.maximum(ew[sel], _TINY_WEIGHT), (lo_[sel], hi_[sel])), shape=(n_nodes, n_nodes)
    ).tocsr()
    dist, pred = dijkstra(graph, directed=False, indices=0, return_predecessors=True)
    length = float(dist[1])
    if not math.isfinite(length):
        return OptimalPath(math.inf, np.zeros((0, 2)), True, "no collision-free path exists")

    # Polyline: walk the predecessors back from the goal, expanding arcs.
    chain = [1]
    while chain[-1] != 0:
        chain.append(int(pred[chain[-1]]))
    chain.reverse()
    pts = [node_xy[0]]
    n_tan = len(node_u)
    for a, b in itertools.pairwise(chain):
        cand = np.flatnonzero((lo_ == min(a, b)) & (hi_ == max(a, b)))
        e = int(cand[np.argmin(ew[cand])])
        if e < n_tan:
            pts.append(node_xy[b])
            continue
        k = e - n_tan
        dk, th0, dth = int(adisk[k]), float(ath0[k]), float(adth[k])
        if au[k] == a:
            arc = _arc_points(centres[dk], float(radii[dk]), th0, dth, arc_tol)
        else:
            arc = _arc_points(centres[dk], float(radii[dk]), th0 + dth, -dth, arc_tol)
        arc[-1] = node_xy[b]
        pts.extend(arc)
    poly = np.asarray(pts)
    dup = np.zeros(len(poly), dtype=bool)
    dup[1:] = np.all(poly[1:] == poly[:-1], axis=1)
    return OptimalPath(length, poly[~dup], True, None)
