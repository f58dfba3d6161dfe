"""Spatial index for the exact optimum on maps with many polygon edges (imported grid maps).

:func:`swarmpath.world.optimum.shortest_path` must decide, for up to millions of candidate tangent
segments, whether each keeps a clearance of at least ``margin`` from every polygon. Testing each
segment against every edge is quadratic; this module makes the same decision exactly with two
structures:

* **Clearance bounds on a raster** (cell size ``rho``): ``low[cell]`` <= the clearance of every
  point of the cell <= ``high[cell]``. With
  ``P+`` the cells that may meet an obstacle (cells touched by a sampled edge, with their
  neighbours, and cells whose centre lies inside one) and ``I`` the cells whose centre lies inside
  an obstacle, ``low = (d(P+) - sqrt 2) rho`` and ``high = (d(I) + sqrt 2 / 2) rho``, ``d`` the
  Euclidean distance transform in cells between cell centres.
* **Edge buckets**: a uniform grid whose cells list every edge whose bounding box, grown by
  ``2 margin + rho``, meets the cell.

A segment is *marched* from its start: at a sample ``q`` with ``low(q) - margin >= margin`` every
point within ``low(q) - margin`` of ``q`` is clear; at a sample with ``high(q) < margin`` the
segment is blocked (every point of that cell is too close); any other sample is *uncertain* and
covers the points within ``margin`` of it. Every sample covers at least ``margin`` on each side, so
the next sample is placed at its covered reach plus ``margin``.
Segments that end the march with uncertain samples are tested exactly (segment-to-segment
distance) against the edges in the buckets of those samples: an edge closer than ``margin`` to a
point within ``margin`` of a sample is within ``2 margin`` of the sample, hence listed in its
bucket. Each point of the segment is therefore certified clear or tested exactly, so the
result equals the brute-force test. Before any tangent is built, :meth:`EdgeIndex.pairs_blocked`
drops a pair of disks of radius <= ``margin`` whose centre segment passes through a cell lying
wholly inside an obstacle (a finer raster: centre inside and no edge near). Arcs on vertex
disks (radius ``margin`` around a vertex ``v``) are tested exactly against the edges in the
bucket of ``v`` (every such edge closer than ``margin`` to the arc is within ``2 margin`` of
``v``).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from swarmpath.world.geometry import segment_segment_distance

Array = NDArray[np.float64]
IntArray = NDArray[np.intp]
BoolArray = NDArray[np.bool_]

__all__ = ["EdgeIndex"]

MAX_RASTER_CELLS = 4_000_000
MAX_DEEP_CELLS = 16_000_000
PAIR_STAGES = 4  # pairs_blocked samples at most 2 ** (PAIR_STAGES + 1) - 1 points
_SQRT2 = math.sqrt(2.0)
_PAIR_CHUNK = 1 << 20


def _cells(
    P: Array, origin: Array, rho: float, shape: tuple[int, int]
) -> tuple[IntArray, IntArray]:
    ij = np.floor((P - origin) / rho).astype(np.intp)
    return np.clip(ij[..., 1], 0, shape[0] - 1), np.clip(ij[..., 0], 0, shape[1] - 1)


def _inside(
    polygons: list[Array], origin: Array, rho: float, shape: tuple[int, int]
) -> BoolArray:
    """Cells whose centre lies inside a polygon: nonzero winding of the polygons made ccw."""
    rows, cols = shape
    ox, oy = float(origin[0]), float(origin[1])
    wind = np.zeros((rows, cols + 1), dtype=np.int16)
    for poly in polygons:
        p = poly
        area2 = float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))
        if area2 < 0:
            p = p[::-1]
        a, b = p, np.roll(p, -1, axis=0)
        for (ax, ay), (bx, by) in zip(a.tolist(), b.tolist(), strict=True):
            if ay == by:
                continue
            lo, hi = (ay, by) if ay < by else (by, ay)
            j0 = max(math.ceil((lo - oy) / rho - 0.5), 0)
            j1 = min(math.ceil((hi - oy) / rho - 0.5), rows)  # centres in [lo, hi)
            if j1 <= j0:
                continue
            yc = oy + (np.arange(j0, j1) + 0.5) * rho
            xc = ax + (yc - ay) * (bx - ax) / (by - ay)
            k = np.clip(np.ceil((xc - ox) / rho - 0.5).astype(np.intp), 0, cols)
            np.add.at(wind, (np.arange(j0, j1), k), 1 if by > ay else -1)
    return np.asarray(np.cumsum(wind, axis=1, dtype=np.int16)[:, :cols] != 0)


def _near_edges(
    e0: Array, e1: Array, origin: Array, rho: float, shape: tuple[int, int]
) -> BoolArray:
    """A superset of the cells an edge passes through: the cells of samples every rho / 2
    along the edges, with their 8 neighbours."""
    hit = np.zeros(shape, dtype=bool)
    if len(e0):
        lengths = np.hypot(*(e1 - e0).T)
        n = np.maximum(np.ceil(lengths / (0.5 * rho)).astype(np.intp), 1) + 1
        edge = np.repeat(np.arange(len(e0)), n)
        start = np.repeat(np.cumsum(n) - n, n)
        t = (np.arange(int(n.sum())) - start) / np.repeat(n - 1, n)
        r, c = _cells(e0[edge] + t[:, None] * (e1 - e0)[edge], origin, rho, shape)
        hit[r, c] = True
    return np.asarray(ndimage.binary_dilation(hit, structure=np.ones((3, 3), dtype=bool)))


class EdgeIndex:
    """Raster clearance bounds plus edge buckets for polygon edges ``e0[k] -> e1[k]``.

    ``polygons``: the polygons (each (m, 2), either orientation); ``extent``: (xmin, ymin, xmax,
    ymax) containing every point that will be queried; ``margin`` > 0; ``tol``: the tangency
    tolerance (a distance >= margin - tol counts as clear).
    """

    def __init__(
        self, polygons: list[Array], extent: tuple[float, float, float, float], margin: float,
        tol: float,
    ) -> None:
        self.m = float(margin)
        self.tol = float(tol)
        self.e0 = np.concatenate(polygons) if polygons else np.zeros((0, 2))
        self.e1 = (
            np.concatenate([np.roll(p, -1, axis=0) for p in polygons]) if polygons
            else np.zeros((0, 2))
        )
        x0, y0, x1, y1 = extent
        area = max((x1 - x0) * (y1 - y0), 1e-12)
        self.rho = max(self.m / 2.0, math.sqrt(area / MAX_RASTER_CELLS))
        self.ustep = 2.0 * self.m  # an uncertain sample covers margin either side
        pad = 2.0 * self.m + 3.0 * self.rho
        self.origin = np.array([x0 - pad, y0 - pad])
        self.shape = (
            math.ceil((y1 - y0 + 2 * pad) / self.rho) + 1,
            math.ceil((x1 - x0 + 2 * pad) / self.rho) + 1,
        )
        self._raster(polygons)
        self._buckets()

    # ------------------------------------------------------------------------- raster bounds
    def _cells(self, P: Array) -> tuple[IntArray, IntArray]:
        return _cells(P, self.origin, self.rho, self.shape)

    def _raster(self, polygons: list[Array]) -> None:
        rho = self.rho
        inside = _inside(polygons, self.origin, rho, self.shape)
        touched = inside | _near_edges(self.e0, self.e1, self.origin, rho, self.shape)
        self.low = ((ndimage.distance_transform_edt(~touched) - _SQRT2) * rho).astype(np.float32)
        if inside.any():
            d_in = ndimage.distance_transform_edt(~inside)
            self.high = ((d_in + _SQRT2 / 2) * rho).astype(np.float32)
        else:
            self.high = np.full(self.shape, np.inf, dtype=np.float32)
        # a finer raster of cells lying wholly inside an obstacle, for pairs_blocked
        width = self.shape[1] * rho
        height = self.shape[0] * rho
        self.rho_d = max(rho / 4.0, math.sqrt(width * height / MAX_DEEP_CELLS))
        self.shape_d = (math.ceil(height / self.rho_d), math.ceil(width / self.rho_d))
        inside_d = _inside(polygons, self.origin, self.rho_d, self.shape_d)
        self.deep = inside_d & ~_near_edges(self.e0, self.e1, self.origin, self.rho_d,
                                            self.shape_d)

    def pairs_blocked(self, U: Array, V: Array) -> BoolArray:
        """True where the segment UV passes through a point inside an obstacle (sampled: False
        means only that no sample found one).

        Used on the centres of two disks of radius <= margin: every point of a tangent segment
        of the two disks lies within margin of a point of UV (the offset varies linearly
        between the two ends, each at most margin), and the signed clearance is 1-Lipschitz, so
        a point of UV strictly inside an obstacle makes every tangent segment come closer than
        margin to it.
        """
        n = len(U)
        out = np.zeros(n, dtype=bool)
        length = np.hypot(*(V - U).T)
        # cell coordinates (float32: the raster covers every centre, so no clipping is needed)
        uc = ((U - self.origin) / self.rho_d).astype(np.float32)
        dc = ((V - U) / self.rho_d).astype(np.float32)
        cols = self.shape_d[1]
        deep = self.deep.ravel()
        active = np.arange(n)
        k = 0
        while len(active) and k <= PAIR_STAGES:
            f = ((2.0 * np.arange(2**k) + 1.0) / 2.0 ** (k + 1)).astype(np.float32)
            step = max(1, (1 << 21) // len(f))
            for lo in range(0, len(active), step):
                sl = active[lo : lo + step]
                x = (uc[sl, 0, None] + f * dc[sl, 0, None]).astype(np.intp)
                y = (uc[sl, 1, None] + f * dc[sl, 1, None]).astype(np.intp)
                out[sl] = deep[y * cols + x].any(axis=1)
            # continue while the samples are still farther apart than a fine cell
            active = active[~out[active] & (length[active] / 2.0 ** (k + 1) > self.rho_d)]
            k += 1
        return out

    # ------------------------------------------------------------------------------- buckets
    def _buckets(self) -> None:
        reach = 2.0 * self.m + self.rho
        self.h = max(4.0 * reach, 0.25)
        lo = np.minimum(self.e0, self.e1) - reach
        hi = np.maximum(self.e0, self.e1) + reach
        self.bshape = (
            math.ceil(self.shape[0] * self.rho / self.h) + 1,
            math.ceil(self.shape[1] * self.rho / self.h) + 1,
        )
        b_lo = np.clip(np.floor((lo - self.origin) / self.h).astype(np.intp), 0,
                       np.array(self.bshape[::-1]) - 1)
        b_hi = np.clip(np.floor((hi - self.origin) / self.h).astype(np.intp), 0,
                       np.array(self.bshape[::-1]) - 1)
        nx = b_hi[:, 0] - b_lo[:, 0] + 1
        ny = b_hi[:, 1] - b_lo[:, 1] + 1
        count = nx * ny
        edge = np.repeat(np.arange(len(self.e0)), count)
        k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
        bx = b_lo[edge, 0] + k % nx[edge]
        by = b_lo[edge, 1] + k // nx[edge]
        key = by * self.bshape[1] + bx
        order = np.argsort(key, kind="stable")
        self.b_edges = edge[order]
        self.b_ptr = np.searchsorted(key[order], np.arange(self.bshape[0] * self.bshape[1] + 1))

    def _bucket_of(self, P: Array) -> IntArray:
        ij = np.floor((P - self.origin) / self.h).astype(np.intp)
        bx = np.clip(ij[..., 0], 0, self.bshape[1] - 1)
        by = np.clip(ij[..., 1], 0, self.bshape[0] - 1)
        return np.asarray(by * self.bshape[1] + bx)

    def _pairs(self, items: IntArray, buckets: IntArray) -> tuple[IntArray, IntArray]:
        """All (item, edge) pairs for the given distinct (item, bucket) pairs (an edge listed in
        two buckets of one item comes twice: cheaper to test twice than to deduplicate)."""
        counts = self.b_ptr[buckets + 1] - self.b_ptr[buckets]
        rep = np.repeat(items, counts)
        pos = np.repeat(self.b_ptr[buckets], counts) + (
            np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
        )
        return rep.astype(np.intp), self.b_edges[pos].astype(np.intp)

    # ----------------------------------------------------------------------------- segments
    def segments_blocked(self, A: Array, B: Array) -> BoolArray:
        """Exact: True where segment AB comes closer than margin - tol to some edge."""
        n = len(A)
        blocked = np.zeros(n, dtype=bool)
        if n == 0 or len(self.e0) == 0:
            return blocked
        d = B - A
        length = np.hypot(d[:, 0], d[:, 1])
        u = d / np.where(length > 0, length, 1.0)[:, None]
        half = 0.5 * self.ustep
        pos = np.zeros(n)
        active = np.arange(n)
        last = np.full(n, -1, dtype=np.intp)  # bucket of each segment's last uncertain sample
        unc_seg: list[IntArray] = []
        unc_bucket: list[IntArray] = []
        while len(active):
            t = np.minimum(pos[active], length[active])
            q = A[active] + t[:, None] * u[active]
            r, c = self._cells(q)
            lo, hi = self.low[r, c], self.high[r, c]
            bad = hi < self.m - self.tol
            blocked[active[bad]] = True
            clear = lo - self.m
            sure = clear >= half
            unsure = ~sure & ~bad
            # a line meets each bucket in one run of samples: record each bucket once
            us = active[unsure]
            ub = self._bucket_of(q[unsure])
            new = last[us] != ub
            last[us] = ub
            unc_seg.append(us[new])
            unc_bucket.append(ub[new])
            cover = np.where(sure, clear, half)  # certified up to t + cover
            pos[active] = t + cover + half  # the next sample covers at least half back
            keep = ~bad & (t + cover < length[active])
            active = active[keep]
        segs = np.concatenate(unc_seg)
        if not len(segs):
            return blocked
        buckets = np.concatenate(unc_bucket)
        live = ~blocked[segs]
        si, ej = self._pairs(segs[live], buckets[live])
        reach = self.m - self.tol
        for lo_ in range(0, len(si), _PAIR_CHUNK):
            s_, e_ = si[lo_ : lo_ + _PAIR_CHUNK], ej[lo_ : lo_ + _PAIR_CHUNK]
            a, b, ea, eb = A[s_], B[s_], self.e0[e_], self.e1[e_]
            near = np.all(
                (np.minimum(a, b) - reach < np.maximum(ea, eb))
                & (np.maximum(a, b) + reach > np.minimum(ea, eb)),
                axis=1,
            )  # boxes grown by the margin overlap: only then can the distance be below it
            s_, a, b, ea, eb = s_[near], a[near], b[near], ea[near], eb[near]
            dist = segment_segment_distance(a, b, ea, eb)
            blocked[s_[dist < self.m - self.tol]] = True
        return blocked

    def near_edges(self, centres: Array) -> tuple[IntArray, IntArray]:
        """(item, edge) pairs: edges listed in the bucket of each centre (within 2 margin)."""
        return self._pairs(np.arange(len(centres)), self._bucket_of(centres))
