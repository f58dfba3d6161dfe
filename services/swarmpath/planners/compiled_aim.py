"""Compiled kernels (numba) of the swarm planners' sensing and aim, ``backend = "numba"``.

The per-decision pieces outside the optimizer: merging the known points on a grid
(:func:`swarmpath.planners.sensed_map.condense`), the nearest previous hit of each hit (motion,
:func:`sensed_map.motion`), a scan's corners (:func:`sensed_map.has_corner`), the hit groups of
the known map (:func:`sensed_map.known_obstacles`), and the aim's walk along the known path
(:func:`sensed_map.shortcut`, ``rejoin``, ``path_clearance``). They run on tens to hundreds of
points per call, where numpy's cost per call, not the arithmetic, is the time.

Each repeats its numpy reference's operations in order (+ - * /, sqrt, hypot, floor and
comparisons; no fastmath, so no fused multiply-add; ``math.hypot`` is libm's, as ``np.hypot``),
so every value is the same double and the episodes are the same
(``tests/test_planner_compiled_aim.py``). The one choice a reference leaves open: the nearest
hit of a point equally far from two hits is the first of them here; scipy's k-d tree picks one
by its traversal order (an exact tie of two float distances; the digests of
``scripts/bench/plan_time.py`` are the same with either backend).

Imported only by a planner whose ``backend`` is ``"numba"`` (``pip install 'swarmpath[fast]'``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

import swarmpath.optimizers.compiled  # noqa: F401 - first: numba's versioned cache directory
from swarmpath.planners.compiled import (
    _segment_nearest,
    segments_clearance_kernel,
    surface_kernel,
)
from swarmpath.world.optimum_compiled import _signed_polygon

Array = np.ndarray
_f = np.ascontiguousarray


# ------------------------------------------------ sensed_map's backend = "numba", same signatures
def condense(hits: Array, position: Array, reach: float, cell: float) -> Array:
    h = _f(hits, dtype=float)
    idx, ok = condense_kernel(h, float(position[0]), float(position[1]), float(reach),
                              float(cell))
    if not ok:  # a span of over 2e9 cells per axis: the numpy reference
        from swarmpath.planners.sensed_map import condense as reference

        return reference(hits, position, reach, cell)
    return h[idx]


def nearest(ref: Array, points: Array) -> tuple[Array, Array]:
    return nearest_kernel(_f(ref, dtype=float), _f(points, dtype=float))


def surface(points: Array, scan: Array, link: float, dist: Array,
            near: Array) -> tuple[Array, Array]:
    return surface_kernel(_f(points, dtype=float), _f(scan, dtype=float), float(link),
                          _f(dist, dtype=float), _f(near, dtype=float))


def motion(previous: Array, current: Array, dt: float, max_speed: float, min_speed: float,
           surface: float) -> tuple[Array, Array]:
    return motion_kernel(_f(previous, dtype=float), _f(current, dtype=float), float(dt),
                         float(max_speed), float(min_speed), float(surface))


def has_corner(scan: Array, surface: float, angle_deg: float) -> bool:
    return bool(has_corner_kernel(_f(scan, dtype=float), float(surface),
                                  math.cos(math.radians(angle_deg))))


def groups(hits: Array, link: float) -> tuple[int, Array]:
    labels = groups_kernel(_f(hits, dtype=float), float(link))
    return int(labels.max()) + 1, labels


def rejoin(pts: Array, position: Array, tolerance: float) -> Array | None:
    dk, k = rejoin_kernel(_f(pts, dtype=float), float(position[0]), float(position[1]))
    if dk > tolerance:
        return None
    return np.vstack([position[None, :], pts[k + 1:]])


def path_clearance(pts: Array, hits: Array, reach: float) -> float:
    return float(path_clearance_kernel(_f(pts, dtype=float), _f(hits, dtype=float), reach))


def shortcut(pts: Array, hits: Array, margin: float, lookahead: float, samples: int) -> Array:
    return np.asarray(shortcut_kernel(_f(pts, dtype=float), _f(hits, dtype=float).reshape(-1, 2),
                                      float(margin), float(lookahead), int(samples)))


# ------------------------------------------------------------------------------------ kernels


@njit(cache=True)
def condense_kernel(hits: Array, px: float, py: float, reach: float,
                    cell: float) -> tuple[Array, bool]:
    """Indices of :func:`sensed_map.condense`'s result: the hits within ``reach`` of (px, py)
    (``np.hypot``), the first of each ``cell`` grid cell (``np.floor(x / cell)``), in order;
    False when the cells spanned are too many for one int64 key each (then none)."""
    n = hits.shape[0]
    near = np.empty(n, dtype=np.int64)
    m = 0
    for i in range(n):
        if math.hypot(hits[i, 0] - px, hits[i, 1] - py) <= reach:
            near[m] = i
            m += 1
    if m == 0:
        return near[:0], True
    kx = np.empty(m, dtype=np.int64)
    ky = np.empty(m, dtype=np.int64)
    for k in range(m):
        kx[k] = np.int64(math.floor(hits[near[k], 0] / cell))
        ky[k] = np.int64(math.floor(hits[near[k], 1] / cell))
    kx = kx - kx.min()
    ky = ky - ky.min()
    cols = ky.max() + 1
    if float(kx.max() + 1) * float(cols) >= 2.0**62:
        return near[:0], False
    key = kx * cols + ky
    order = np.argsort(key, kind="mergesort")  # stable: the first hit of a cell comes first
    keep = np.zeros(m, dtype=np.bool_)
    for k in range(m):
        if k == 0 or key[order[k]] != key[order[k - 1]]:
            keep[order[k]] = True
    return near[:m][keep], True


@njit(cache=True)
def nearest_kernel(ref: Array, points: Array) -> tuple[Array, Array]:
    """Distance to and index of the point of ``ref`` nearest each of ``points`` (what
    ``cKDTree(ref).query(points)`` returns: sqrt of dx * dx + dy * dy; the first on ties)."""
    n = points.shape[0]
    dist = np.empty(n)
    idx = np.zeros(n, dtype=np.intp)
    for i in range(n):
        best = math.inf
        at = 0
        for j in range(ref.shape[0]):
            dx = points[i, 0] - ref[j, 0]
            dy = points[i, 1] - ref[j, 1]
            d2 = dx * dx + dy * dy
            if d2 < best:
                best = d2
                at = j
        dist[i] = math.sqrt(best)
        idx[i] = at
    return dist, idx


@njit(cache=True)
def has_corner_kernel(scan: Array, surface: float, limit: float) -> bool:
    """:func:`sensed_map.has_corner` with ``limit`` = cos(angle): two successive pieces of the
    surface (both shorter than ``surface``, longer than 1e-9) whose cosine is below it."""
    for i in range(scan.shape[0] - 2):
        ax = scan[i + 1, 0] - scan[i, 0]
        ay = scan[i + 1, 1] - scan[i, 1]
        bx = scan[i + 2, 0] - scan[i + 1, 0]
        by = scan[i + 2, 1] - scan[i + 1, 1]
        na = math.hypot(ax, ay)
        nb = math.hypot(bx, by)
        if na < surface and na > 1e-9 and nb < surface and nb > 1e-9:
            if (ax * bx + ay * by) / (na * nb) < limit:
                return True
    return False


@njit(cache=True)
def groups_kernel(hits: Array, link: float) -> Array:
    """Connected components of the hits linked when dx * dx + dy * dy <= link * link (what
    ``cKDTree.query_pairs`` pairs), labelled in order of their first hit (as scipy's
    ``connected_components`` numbers them)."""
    n = hits.shape[0]
    r2 = link * link
    parent = np.arange(n)
    for i in range(n):
        for j in range(i + 1, n):
            dx = hits[i, 0] - hits[j, 0]
            dy = hits[i, 1] - hits[j, 1]
            if dx * dx + dy * dy <= r2:
                a = i
                while parent[a] != a:
                    a = parent[a]
                b = j
                while parent[b] != b:
                    b = parent[b]
                if a != b:
                    if a < b:
                        parent[b] = a
                    else:
                        parent[a] = b
    labels = np.empty(n, dtype=np.int64)
    count = 0
    for i in range(n):
        a = i
        while parent[a] != a:
            a = parent[a]
        if a == i:
            labels[i] = count
            count += 1
        else:
            labels[i] = labels[a]
    return labels


@njit(cache=True)
def _cumulative(pts: Array) -> Array:
    """Length along the polyline at each vertex (``np.cumsum`` of ``np.hypot`` of the steps)."""
    cum = np.zeros(pts.shape[0])
    for i in range(1, pts.shape[0]):
        cum[i] = cum[i - 1] + math.hypot(pts[i, 0] - pts[i - 1, 0], pts[i, 1] - pts[i - 1, 1])
    return cum


@njit(cache=True)
def _interp(s: float, cum: Array, f: Array) -> float:
    """``np.interp(s, cum, f)`` for one s (numpy's rule: the last j with cum[j] <= s; its value
    where s == cum[j], else the slope of the piece times the offset plus its start)."""
    n = cum.shape[0]
    if s < cum[0]:
        return f[0]
    if s > cum[n - 1]:
        return f[n - 1]
    lo = 0
    hi = n
    while hi - lo > 1:  # cum[lo] <= s < cum[hi] (hi = n: beyond the end)
        mid = (lo + hi) // 2
        if cum[mid] <= s:
            lo = mid
        else:
            hi = mid
    j = lo
    if j == n - 1 or s == cum[j]:
        return f[j]
    slope = (f[j + 1] - f[j]) / (cum[j + 1] - cum[j])
    value = slope * (s - cum[j]) + f[j]
    if math.isnan(value):
        value = slope * (s - cum[j + 1]) + f[j + 1]
        if math.isnan(value) and f[j] == f[j + 1]:
            value = f[j]
    return value


@njit(cache=True)
def shortcut_kernel(pts: Array, hits: Array, margin: float, lookahead: float,
                    samples: int) -> Array:
    """:func:`sensed_map.shortcut`: the ``samples`` points ``lookahead * k / samples`` along
    the polyline (``np.interp`` on its cumulative length), the last whose chord from pts[0]
    keeps ``margin`` from every hit (the first with none)."""
    cum = _cumulative(pts)
    cand = np.empty((samples, 2))
    for k in range(samples):
        s = lookahead * float(k + 1) / samples
        if s < 0.0:
            s = 0.0
        if s > cum[-1]:
            s = cum[-1]
        cand[k, 0] = _interp(s, cum, pts[:, 0])
        cand[k, 1] = _interp(s, cum, pts[:, 1])
    if hits.shape[0] == 0:
        return cand[samples - 1].copy()
    start = np.empty((samples, 2))
    start[:, 0] = pts[0, 0]
    start[:, 1] = pts[0, 1]
    clear = segments_clearance_kernel(hits, start, cand)
    best = 0
    for k in range(samples):
        if clear[k] >= margin:
            best = k
    return cand[best].copy()


@njit(cache=True)
def rejoin_kernel(pts: Array, px: float, py: float) -> tuple[float, int]:
    """(distance, index) of the segment of the polyline nearest (px, py) (the first on ties),
    as :func:`sensed_map.rejoin` measures it."""
    best = math.inf
    at = 0
    for i in range(pts.shape[0] - 1):
        ax = pts[i, 0]
        ay = pts[i, 1]
        ux = pts[i + 1, 0] - ax
        uy = pts[i + 1, 1] - ay
        uu = ux * ux + uy * uy
        t = ((px - ax) * ux + (py - ay) * uy) / (uu if uu > 0 else 1.0)
        if t < 0.0:
            t = 0.0
        if t > 1.0:
            t = 1.0
        d = math.hypot(px - (ax + t * ux), py - (ay + t * uy))
        if d < best:
            best = d
            at = i
    return best, at


@njit(cache=True)
def path_clearance_kernel(pts: Array, hits: Array, reach: float) -> float:
    """:func:`sensed_map.path_clearance`: the least distance from the hits to the segments of
    the polyline that start within ``reach`` of its start (along it), the first one past it
    included."""
    cum = _cumulative(pts)
    n = 0
    while n < cum.shape[0] and cum[n] <= reach:  # np.searchsorted(cum, reach, "right")
        n += 1
    m = min(n + 1, pts.shape[0] - 1)
    return segments_clearance_kernel(hits, pts[:m], pts[1 : m + 1]).min()


@njit(cache=True)
def line_clearance_kernel(px: float, py: float, x: float, y: float, hits: Array) -> float:
    """``local.segment_hit_distance(p, [(x, y)], hits)[0][0]``: the distance from the segment
    p -> (x, y) to its nearest hit (the hits taken relative to p, as the reference does)."""
    wx = np.empty(hits.shape[0])
    wy = np.empty(hits.shape[0])
    for j in range(hits.shape[0]):
        wx[j] = hits[j, 0] - px
        wy[j] = hits[j, 1] - py
    best, _ = _segment_nearest(px, py, x, y, wx, wy)
    return math.sqrt(best)


@njit(cache=True)
def point_clearance_kernel(px: float, py: float, circles: Array, verts: Array,
                           counts: Array) -> float:
    """``ObstacleSet.point_clearance`` of one point: the least of the circles' hypot - r and
    the polygons' edge distances, negative inside a polygon (even-odd ray casting toward +x);
    ``verts`` are the polygons' vertices one after the other, ``counts`` how many each."""
    out = math.inf
    for c in range(circles.shape[0]):
        out = min(out, math.hypot(px - circles[c, 0], py - circles[c, 1]) - circles[c, 2])
    start = 0
    for j in range(counts.shape[0]):
        out = min(out, _signed_polygon(px, py, verts, start, counts[j]))
        start += counts[j]
    return out


@njit(cache=True)
def _gather(points: Array, idx: Array) -> Array:
    out = np.empty((idx.shape[0], 2))
    for k in range(idx.shape[0]):
        out[k, 0] = points[idx[k], 0]
        out[k, 1] = points[idx[k], 1]
    return out


@njit(cache=True)
def motion_kernel(previous: Array, current: Array, dt: float, max_speed: float,
                  min_speed: float, surface: float) -> tuple[Array, Array]:
    """:func:`sensed_map.motion` with ``surface`` > 0 (both scans non-empty, dt > 0): each hit's
    distance to the previous surface (kept where the previous scan's nearest hit is as far from
    the current surface), its velocity from the surface point it left, moving between the two
    speeds."""
    d0, i0 = nearest_kernel(previous, current)
    dist, near = surface_kernel(current, previous, surface, d0, _gather(previous, i0))
    d1, i1 = nearest_kernel(current, previous)
    back, _ = surface_kernel(previous, current, surface, d1, _gather(current, i1))
    slow = min_speed * dt
    n = current.shape[0]
    moving = np.empty(n, dtype=np.bool_)
    velocity = np.empty((n, 2))
    for k in range(n):
        d = dist[k] if back[i0[k]] >= slow else 0.0
        velocity[k, 0] = (current[k, 0] - near[k, 0]) / dt
        velocity[k, 1] = (current[k, 1] - near[k, 1]) / dt
        speed = d / dt
        moving[k] = speed >= min_speed and speed <= max_speed
    return moving, velocity
