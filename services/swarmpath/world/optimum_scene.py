"""Batched exact collision checks of :mod:`swarmpath.world.optimum`: are candidate segments and
arcs free (clearance >= margin - ``TOL``) among the original obstacles, inside the world box."""

from __future__ import annotations

import math

import numpy as np

from swarmpath.world.geometry import (
    ObstacleSet,
    point_polygon_distance,
    point_segment_distance,
    segment_segment_distance,
)
from swarmpath.world.optimum_base import (
    _CHUNK,
    TOL,
    TWO_PI,
    Array,
    BoolArray,
    IntArray,
    World,
    _arc_segment_distance,
    _chunks_by_weight,
    _cross,
    _dot,
    _expand_csr,
    _in_arc,
    _norm,
    _on_circle,
    _point_arc_distance,
)
from swarmpath.world.optimum_index import EdgeIndex

_NEAR_FIRST = 16  # above this many circles, test each segment against nearby ones first
_BUCKET = 6  # circles kept per grid cell for that pre-pass
_SIDE = 1e-7  # margin 0: offset used to see obstacle on both sides of a segment


class _Scene:
    """Obstacles, margin and world box with batched exact free-ness tests for segments and arcs."""

    def __init__(
        self, obstacles: ObstacleSet, margin: float, world: World | None,
        index: EdgeIndex | None = None,
    ) -> None:
        self.index = index
        self.backend = "numpy"  # "numba": arcs_blocked compiled (margin > 0, no circles)
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
        self._build_circle_buckets()
        self._orders: tuple[IntArray, IntArray] | None = None

    def _order(self, which: int) -> IntArray:
        """Fixed random visiting orders (circles, polygons; no global RNG), drawn when needed."""
        if self._orders is None:
            rng = np.random.default_rng(0)
            self._orders = (rng.permutation(len(self.circles)), rng.permutation(len(self.polygons)))
        return self._orders[which]

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
        # A polygon whose box grown by margin + TOL does not hold p is farther than that from
        # it: only the others are measured (the same answer, the first blocking polygon).
        near = np.all((p >= self.bb_lo) & (p <= self.bb_hi), axis=-1)
        for j in np.flatnonzero(near).tolist():
            dj = float(point_polygon_distance(p, self.polygons[j]))
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
            cc = self.circles[self._order(0)[lo : lo + width]]
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
            pjs = self._order(1)[lo : lo + width]
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
        if self.backend == "numba" and self.index is None and self.m > 0 and not len(self.circles):
            from swarmpath.world import optimum_compiled_arcs as compiled

            return compiled.arcs_blocked(self, c, rho, th0, dth)
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

