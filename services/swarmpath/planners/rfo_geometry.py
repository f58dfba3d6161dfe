"""Exact clearance queries of the RFO family's safety rules (Ketafa & Al-Darraji 2024,
section 4.1): distances to the static map restricted to nearby obstacles, sensed-hit
boxes, and path length."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from swarmpath.world.geometry import (
    ObstacleSet,
    _segments_cross,  # the crossing test inside segment_segment_distance, reused as is
    point_segment_distance,
    segment_segment_distance,
)

Array = NDArray[np.float64]
class _Clearance:
    """Exact unsigned clearances against a static map, restricted to nearby obstacles.

    Same formulas as :class:`ObstacleSet` (``point_segment_distance``/``segment_segment_distance``
    per edge, ``|p - c| - R`` per circle), but only obstacles whose bounding box lies within
    ``reach`` of the query's bounding box are examined: results are exact whenever the true value
    is below ``reach`` and otherwise some value >= ``reach`` (possibly +inf), which is all a
    threshold test ``clearance > reach`` needs.

    Polygon interiors are not tested: every node the planners hold is reached from the start
    through checked segments, so it lies outside every polygon, and a segment from such a node
    into a polygon crosses an edge (clearance 0). The planner checks the start once with
    :meth:`ObstacleSet.point_clearance` and the final path with
    :meth:`ObstacleSet.segment_clearance`.
    """

    def __init__(self, obstacles: ObstacleSet):
        c = obstacles.circles
        self.circles = c
        self.kc = int(c.shape[0])
        boxes = [np.column_stack([c[:, :2] - c[:, 2:3], c[:, :2] + c[:, 2:3]])]
        e0, e1, owner, spans = [], [], [], []
        start = 0
        for j, poly in enumerate(obstacles.polygons):
            e0.append(poly)
            e1.append(np.roll(poly, -1, axis=0))
            owner.append(np.full(len(poly), self.kc + j))
            spans.append((start, start + len(poly)))
            start += len(poly)
            boxes.append(np.concatenate([poly.min(axis=0), poly.max(axis=0)])[None, :])
        self.e0 = np.concatenate(e0) if e0 else np.zeros((0, 2))
        self.e1 = np.concatenate(e1) if e1 else np.zeros((0, 2))
        self.owner = np.concatenate(owner) if owner else np.zeros(0, dtype=np.intp)
        self.spans = spans
        self.boxes = np.concatenate(boxes)
        self.K = int(self.boxes.shape[0])

    def _near(self, A: Array, B: Array, reach: float) -> NDArray[np.bool_]:
        """(S, K): obstacle k's box is within ``reach`` of segment s's box."""
        lo = np.minimum(A, B) - reach
        hi = np.maximum(A, B) + reach
        b = self.boxes
        return np.asarray(
            (b[None, :, 0] <= hi[:, None, 0]) & (b[None, :, 2] >= lo[:, None, 0])
            & (b[None, :, 1] <= hi[:, None, 1]) & (b[None, :, 3] >= lo[:, None, 1])
        )

    def _pair_distances(
        self, A: Array, B: Array, reach: float
    ) -> tuple[NDArray[np.intp], NDArray[np.intp], Array]:
        """(segment index, obstacle index, distance) for every segment-circle/edge pair examined."""
        near = self._near(A, B, reach)
        seg_i: list[NDArray[np.intp]] = []
        obs_k: list[NDArray[np.intp]] = []
        dist: list[Array] = []
        if self.kc:
            si, cj = np.nonzero(near[:, : self.kc])
            if si.size:
                c = self.circles[cj]
                d = point_segment_distance(c[:, :2], A[si], B[si]) - c[:, 2]
                seg_i.append(si)
                obs_k.append(cj)
                dist.append(np.maximum(d, 0.0))
        if self.e0.shape[0]:
            si, ej = np.nonzero(near[:, self.owner])
            if si.size:
                seg_i.append(si)
                obs_k.append(self.owner[ej])
                dist.append(segment_segment_distance(A[si], B[si], self.e0[ej], self.e1[ej]))
        if not seg_i:
            empty = np.zeros(0, dtype=np.intp)
            return empty, empty, np.zeros(0)
        return np.concatenate(seg_i), np.concatenate(obs_k), np.concatenate(dist)

    def segment(self, A: Array, B: Array, reach: float) -> Array:
        """Clearance of segments AB (S, 2) -> (S,), exact below ``reach``."""
        A, B = np.atleast_2d(A), np.atleast_2d(B)
        A, B = np.broadcast_arrays(A, B)
        out = np.full(A.shape[0], np.inf)
        si, _, d = self._pair_distances(A, B, reach)
        if si.size:
            np.minimum.at(out, si, d)
        return out

    def segment_and_end(self, A: Array, B: Array, reach: float) -> tuple[Array, Array]:
        """Clearance of segments AB and of their ends B (S, 2) -> (S,), (S,); exact below reach.

        :func:`segment_segment_distance` unrolled so that the distance of B to each edge serves
        both results (one pass over the pairs instead of two).
        """
        near = self._near(A, B, reach)
        seg = np.full(A.shape[0], np.inf)
        end = np.full(A.shape[0], np.inf)
        if self.kc:
            si, cj = np.nonzero(near[:, : self.kc])
            if si.size:
                c = self.circles[cj]
                d = point_segment_distance(c[:, :2], A[si], B[si]) - c[:, 2]
                np.minimum.at(seg, si, np.maximum(d, 0.0))
                np.minimum.at(end, si, np.hypot(B[si, 0] - c[:, 0], B[si, 1] - c[:, 1]) - c[:, 2])
        if self.e0.shape[0]:
            si, ej = np.nonzero(near[:, self.owner])
            if si.size:
                a, b, c, d = A[si], B[si], self.e0[ej], self.e1[ej]
                n = si.size
                pts = point_segment_distance(
                    np.concatenate([a, b, c, d]),
                    np.concatenate([c, c, a, a]),
                    np.concatenate([d, d, b, b]),
                )
                db = pts[n : 2 * n]
                dseg = np.minimum(np.minimum(pts[:n], db),
                                  np.minimum(pts[2 * n : 3 * n], pts[3 * n :]))
                dseg = np.where(_segments_cross(a, b, c, d), 0.0, dseg)
                np.minimum.at(seg, si, dseg)
                np.minimum.at(end, si, db)
        return seg, end

    def nearest(self, A: Array, B: Array, reach: float) -> NDArray[np.intp]:
        """Index of the obstacle nearest to each segment AB (S, 2) within ``reach`` (-1: none)."""
        si, k, d = self._pair_distances(A, B, reach)
        per = np.full((A.shape[0], self.K), np.inf)
        if k.size:
            np.minimum.at(per, (si, k), d)
        out = np.argmin(per, axis=1) if self.K else np.zeros(A.shape[0], dtype=np.intp)
        return np.where(np.isfinite(per.min(axis=1, initial=np.inf)), out, -1)

    def to_obstacles(self, P: Array, ks: NDArray[np.intp]) -> Array:
        """Unsigned distance from each point P[s] (S, 2) to the boundary of obstacle ks[s]."""
        out = np.full(P.shape[0], np.inf)
        circ = ks < self.kc
        if circ.any():
            c = self.circles[ks[circ]]
            out[circ] = np.abs(np.hypot(P[circ, 0] - c[:, 0], P[circ, 1] - c[:, 1]) - c[:, 2])
        if self.e0.shape[0]:
            si, ej = np.nonzero(self.owner[None, :] == ks[:, None])
            if si.size:
                d = point_segment_distance(P[si], self.e0[ej], self.e1[ej])
                np.minimum.at(out, si, d)
        return out


class _BoxQuery:
    """Clearances of wolves that stay in known boxes: F boxes of m wolves each, wolf f*m + w.

    Each box's wolves are paired once with the obstacles that can matter (within ``reach`` of
    the box) and with the box's blocked obstacle ``ks[f]``; a call is then a few array gathers.
    The segment distance fox -> wolf is :func:`segment_segment_distance` unrolled (0 where the
    segments cross properly, else the least of the four endpoint-to-segment distances) so that
    the fox's own endpoint distances are computed once and the wolf's are shared with its node
    clearance.
    """

    def __init__(self, geo: _Clearance, P: Array, lower: Array, upper: Array, reach: float,
                 m: int, ks: NDArray[np.intp]):
        self.n = P.shape[0] * m
        near = geo._near(lower, upper, reach)
        wolves = np.arange(m)

        def expand(f: NDArray[np.intp], j: NDArray[np.intp]) -> tuple[NDArray[np.intp], ...]:
            return (f[:, None] * m + wolves).ravel(), np.repeat(j, m)

        A = np.repeat(P, m, axis=0)  # the fox of each wolf
        cw, cc = expand(*np.nonzero(near[:, : geo.kc]))
        ew, ee = expand(*np.nonzero(near[:, geo.owner]))
        circ = (ks >= 0) & (ks < geo.kc)
        kcw, kcc = expand(np.flatnonzero(circ), ks[circ])
        kew, kee = expand(*np.nonzero(geo.owner[None, :] == ks[:, None]))
        self.cw, self.ew, self.kcw, self.kew = cw, ew, kcw, kew
        self.c, self.kc = geo.circles[cc], geo.circles[kcc]
        self.Ae, self.Ac = A[ew], A[cw]
        self.C = np.concatenate([geo.e0[ee], geo.e0[kee]])
        self.D = np.concatenate([geo.e1[ee], geo.e1[kee]])
        self.CD = np.concatenate([geo.e0[ee], geo.e1[ee], self.c[:, :2]])
        self.fox_end = point_segment_distance(self.Ae, geo.e0[ee], geo.e1[ee])
        self.ne = ew.size
        self.rows = np.concatenate([
            np.zeros(ew.size + cw.size, dtype=np.intp), np.ones(ew.size + cw.size, dtype=np.intp),
            np.full(kew.size + kcw.size, 2, dtype=np.intp)])
        self.cols = np.concatenate([ew, cw, ew, cw, kew, kcw])

    def __call__(self, W: Array) -> tuple[Array, Array, Array]:
        """Segment clearance fox -> W, node clearance of W, distance of W from its obstacle."""
        ne, c, kc = self.ne, self.c, self.kc
        We, Wc, Wk = W[self.ew], W[self.cw], W[self.kcw]
        # wolf endpoint to edge (node clearance and blocked-obstacle distance share one call)
        wd = point_segment_distance(np.concatenate([We, W[self.kew]]), self.C, self.D)
        node_e, obs_e = wd[:ne], wd[ne:]
        # edge endpoints and circle centres to the segment fox -> wolf
        ends = point_segment_distance(
            self.CD, np.concatenate([self.Ae, self.Ae, self.Ac]), np.concatenate([We, We, Wc]))
        C, D = self.C[:ne], self.D[:ne]
        seg_e = np.minimum(np.minimum(self.fox_end, node_e), np.minimum(ends[:ne], ends[ne:2 * ne]))
        seg_e = np.where(_segments_cross(self.Ae, We, C, D), 0.0, seg_e)
        seg_c = np.maximum(ends[2 * ne:] - c[:, 2], 0.0)
        node_c = np.hypot(Wc[:, 0] - c[:, 0], Wc[:, 1] - c[:, 1]) - c[:, 2]
        obs_c = np.abs(np.hypot(Wk[:, 0] - kc[:, 0], Wk[:, 1] - kc[:, 1]) - kc[:, 2])
        out = np.full((3, self.n), np.inf)
        np.minimum.at(out, (self.rows, self.cols),
                      np.concatenate([seg_e, seg_c, node_e, node_c, obs_e, obs_c]))
        return out[0], out[1], out[2]


def _hit_clearance(a: Array, b: Array, hits: Array) -> float:
    """Least distance from the segment ab to the sensed points (inf with none)."""
    if len(hits) == 0:
        return math.inf
    n = len(hits)
    d = point_segment_distance(hits, np.broadcast_to(a, (n, 2)), np.broadcast_to(b, (n, 2)))
    return float(np.min(d))


def path_length(path: Array) -> float:
    return float(np.hypot(*np.diff(path, axis=0).T).sum()) if len(path) > 1 else 0.0
