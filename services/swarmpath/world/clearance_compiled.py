"""Compiled kernels (numba) of the simulator's geometry on large maps: swept clearances along a
trajectory (:func:`swarmpath.metrics.step_clearances`), segment clearances to a static map
(:meth:`swarmpath.world.geometry.ObstacleSet.segment_clearance`, the motion guard) and range
rays against polygons (:func:`swarmpath.robot.sensors.read_sensors`).

The numpy references compare every query with every polygon edge of the map: on a 512 x 512
MovingAI grid (hundreds of polygons, thousands of edges) that was most of an episode's time. The
kernels visit only the polygons a query can reach, found through a uniform grid over the
polygons' bounding boxes (:func:`build_index`), and compute each distance they do evaluate with
the reference's operations in its order (+ - * /, hypot, comparisons; no fastmath, so no fused
multiply-add): the per-edge functions are :mod:`swarmpath.world.optimum_compiled`'s, already
proven equal to :mod:`swarmpath.world.geometry`. A polygon is skipped only when its bounding box
is provably farther than a value already found (by more than :data:`SLACK`), so a minimum over
the polygons is the same double as the reference's minimum over all of them
(``tests/test_clearance_compiled.py``).

Imported only through :mod:`swarmpath.world.clearance` when numba is installed.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

import swarmpath.optimizers.compiled  # noqa: F401 - first: numba's versioned cache directory
from swarmpath.world.optimum_compiled import _point_segment, _segment_segment, _signed_polygon

Array = np.ndarray

#: m: a polygon whose bounding box is farther than the best distance found plus this much is
#: skipped. Rounding in a distance is below 1e-8 m for coordinates up to MAX_METRES (1e7 m).
SLACK = 1e-6


# ------------------------------------------------------------------------------ the grid index
@njit(cache=True)
def _cell_range(lo: float, hi: float, origin: float, cell: float, n: int) -> tuple[int, int]:
    """First and last cell (clipped to [0, n - 1]) that the interval [lo, hi] overlaps (the
    clip comes first: a huge reach must not overflow the integer conversion)."""
    top = n - 1.0
    a = min(max((lo - origin) / cell, 0.0), top)
    b = min(max((hi - origin) / cell, 0.0), top)
    return math.floor(a), math.floor(b)


@njit(cache=True)
def build_index(bb_lo: Array, bb_hi: Array, x0: float, y0: float, cell: float, nx: int,
                ny: int) -> tuple[Array, Array]:
    """CSR lists of the polygons whose bounding box overlaps each cell (row-major, y then x):
    cell c's polygons are ``items[start[c]:start[c + 1]]``, in increasing order."""
    count = np.zeros(nx * ny + 1, dtype=np.int64)
    for j in range(bb_lo.shape[0]):
        ia, ib = _cell_range(bb_lo[j, 0], bb_hi[j, 0], x0, cell, nx)
        ja, jb = _cell_range(bb_lo[j, 1], bb_hi[j, 1], y0, cell, ny)
        for cy in range(ja, jb + 1):
            for cx in range(ia, ib + 1):
                count[cy * nx + cx + 1] += 1
    start = np.cumsum(count)
    fill = start[:-1].copy()
    items = np.empty(start[-1], dtype=np.int64)
    for j in range(bb_lo.shape[0]):
        ia, ib = _cell_range(bb_lo[j, 0], bb_hi[j, 0], x0, cell, nx)
        ja, jb = _cell_range(bb_lo[j, 1], bb_hi[j, 1], y0, cell, ny)
        for cy in range(ja, jb + 1):
            for cx in range(ia, ib + 1):
                items[fill[cy * nx + cx]] = j
                fill[cy * nx + cx] += 1
    return start, items


@njit(cache=True)
def _box_gap(lox: float, loy: float, hix: float, hiy: float, bb_lo: Array, bb_hi: Array,
             j: int) -> float:
    """Distance between the box [lo, hi] and polygon j's bounding box (0 when they overlap): a
    lower bound of any distance from a point of the box to the polygon."""
    gx = max(bb_lo[j, 0] - hix, lox - bb_hi[j, 0], 0.0)
    gy = max(bb_lo[j, 1] - hiy, loy - bb_hi[j, 1], 0.0)
    return math.sqrt(gx * gx + gy * gy)


@njit(cache=True)
def _candidates(lox: float, loy: float, hix: float, hiy: float, grid: Array, start: Array,
                items: Array, stamp: Array, mark: int, out: Array) -> int:
    """The polygons listed in the cells overlapping [lo, hi] (each once: ``stamp[j] = mark``),
    written to ``out``; their number. ``grid`` = (x0, y0, cell, nx, ny); with more cells than
    polygons every polygon is listed instead (a scan of the boxes is cheaper)."""
    x0, y0, cell = grid[0], grid[1], grid[2]
    nx, ny = int(grid[3]), int(grid[4])
    npoly = stamp.shape[0]
    wide = math.isinf(hix - lox) or math.isinf(hiy - loy)
    if not wide:
        ia, ib = _cell_range(lox, hix, x0, cell, nx)
        ja, jb = _cell_range(loy, hiy, y0, cell, ny)
        wide = (ib - ia + 1) * (jb - ja + 1) > npoly
    n = 0
    if wide:
        for j in range(npoly):
            out[n] = j
            n += 1
        return n
    for cy in range(ja, jb + 1):
        for cx in range(ia, ib + 1):
            c = cy * nx + cx
            for k in range(start[c], start[c + 1]):
                j = items[k]
                if stamp[j] != mark:
                    stamp[j] = mark
                    out[n] = j
                    n += 1
    return n


# ------------------------------------------------------------------------- segment clearances
@njit(cache=True)
def _segment_polygon(ax: float, ay: float, bx: float, by: float, verts: Array, start: int,
                     count: int) -> float:
    """geometry.segment_polygon_distance of one segment: 0 when A lies inside the polygon
    (even-odd ray casting toward +x, geometry._crossings), else the least edge distance."""
    d = math.inf
    crossings = 0
    for k in range(start, start + count):
        nxt = k + 1 if k + 1 < start + count else start
        cx, cy, ex, ey = verts[k, 0], verts[k, 1], verts[nxt, 0], verts[nxt, 1]
        d = min(d, _segment_segment(ax, ay, bx, by, cx, cy, ex, ey))
        if (cy > ay) != (ey > ay):
            dy = ey - cy
            safe = dy if dy != 0.0 else 1.0
            if ax < cx + (ay - cy) * (ex - cx) / safe:
                crossings += 1
    return 0.0 if crossings % 2 == 1 else d


@njit(cache=True)
def _search(ax: float, ay: float, bx: float, by: float, reach: float, verts: Array,
            starts: Array, counts: Array, bb_lo: Array, bb_hi: Array, fixed: Array,
            grid: Array, start: Array, items: Array, stamp: Array, mark: int,
            buf: Array) -> tuple[float, bool]:
    """Least distance from segment AB to the static polygons whose box comes within ``reach``
    of the segment's box (inf when none), and whether every polygon was listed (then the
    least distance over all of them, whatever the reach)."""
    lox, hix = min(ax, bx), max(ax, bx)
    loy, hiy = min(ay, by), max(ay, by)
    n = _candidates(lox - reach, loy - reach, hix + reach, hiy + reach, grid, start, items,
                    stamp, mark, buf)
    every = n == stamp.shape[0]
    if every:
        reach = math.inf
    best = math.inf
    for q in range(n):
        j = buf[q]
        if fixed.shape[0] and not fixed[j]:
            continue
        gap = _box_gap(lox, loy, hix, hiy, bb_lo, bb_hi, j)
        if gap > reach or gap > best + SLACK:
            continue
        best = min(best, _segment_polygon(ax, ay, bx, by, verts, starts[j], counts[j]))
    return best, every


@njit(cache=True)
def _static_polygons(ax: float, ay: float, bx: float, by: float, bound: float, verts: Array,
                     starts: Array, counts: Array, bb_lo: Array, bb_hi: Array, fixed: Array,
                     grid: Array, start: Array, items: Array, stamp: Array, mark: int,
                     buf: Array) -> float:
    """Least distance from segment AB to the static polygons (those ``fixed`` marks; all of
    them when ``fixed`` is empty), inf when none. ``bound``, at least that distance (inf:
    unknown), only limits the search: every polygon whose box comes within it is evaluated
    unless its box is farther than a distance already found. With no bound the reach grows
    from one cell, fourfold, until it holds the least distance found (polygons beyond the reach
    are farther than it)."""
    if not math.isinf(bound):
        return _search(ax, ay, bx, by, bound + SLACK, verts, starts, counts, bb_lo, bb_hi,
                       fixed, grid, start, items, stamp, mark * 64, buf)[0]
    reach = grid[2]
    for round_ in range(1, 64):  # each round lists the polygons again under its own mark
        best, every = _search(ax, ay, bx, by, reach, verts, starts, counts, bb_lo, bb_hi, fixed,
                              grid, start, items, stamp, mark * 64 + round_, buf)
        if best <= reach or every:
            return best
        reach *= 4.0
    return _search(ax, ay, bx, by, math.inf, verts, starts, counts, bb_lo, bb_hi, fixed, grid,
                   start, items, stamp, mark * 64, buf)[0]


@njit(cache=True)
def step_clearances_kernel(xy: Array, circles: Array, verts: Array, starts: Array,
                           counts: Array, bb_lo: Array, bb_hi: Array, slot: Array, off: Array,
                           grid: Array, start: Array, items: Array) -> Array:
    """metrics.step_clearances: the swept clearance of each step xy[i] -> xy[i + 1].

    ``slot[o]`` (circles first, then polygons) is -1 for an obstacle that never moves, else its
    column in ``off`` (rows x moving obstacles x 2), its offset from its first pose at each row:
    in its frame the robot sweeps (xy[i] - c) - off[i] -> (xy[i + 1] - c) - off[i + 1] (a circle
    of centre c) or xy[i] - off[i] -> xy[i + 1] - off[i + 1] (a polygon), as
    metrics._clearance_matrix computes. Circles: max(distance - r, 0). Static polygons through
    the index: a step's static clearance is at most the previous step's plus the previous
    step's length (a distance is 1-Lipschitz), which bounds the search.
    """
    n = xy.shape[0] - 1
    k = circles.shape[0]
    npoly = counts.shape[0]
    out = np.empty(max(n, 0))
    fixed = np.empty(npoly, dtype=np.bool_)
    any_fixed = False
    for j in range(npoly):
        fixed[j] = slot[k + j] < 0
        any_fixed = any_fixed or fixed[j]
    stamp = np.zeros(npoly, dtype=np.int64)
    buf = np.empty(npoly, dtype=np.int64)
    previous = math.inf  # the static polygons' clearance of the last step
    moved = math.inf  # the last step's length
    for i in range(n):
        ax, ay, bx, by = xy[i, 0], xy[i, 1], xy[i + 1, 0], xy[i + 1, 1]
        best = math.inf
        for c in range(k):
            cx, cy, r = circles[c, 0], circles[c, 1], circles[c, 2]
            pax, pay, pbx, pby = ax - cx, ay - cy, bx - cx, by - cy
            s = slot[c]
            if s >= 0:
                pax, pay = pax - off[i, s, 0], pay - off[i, s, 1]
                pbx, pby = pbx - off[i + 1, s, 0], pby - off[i + 1, s, 1]
            v = _point_segment(0.0, 0.0, pax, pay, pbx, pby) - r
            v = v if v >= 0.0 else 0.0
            best = min(best, v)
        for j in range(npoly):
            s = slot[k + j]
            if s < 0:
                continue
            pax, pay = ax - off[i, s, 0], ay - off[i, s, 1]
            pbx, pby = bx - off[i + 1, s, 0], by - off[i + 1, s, 1]
            best = min(best, _segment_polygon(pax, pay, pbx, pby, verts, starts[j], counts[j]))
        if any_fixed:
            bound = previous + moved
            here = _static_polygons(ax, ay, bx, by, bound, verts, starts, counts, bb_lo, bb_hi,
                                    fixed, grid, start, items, stamp, i + 1, buf)
            previous = here
            best = min(best, here)
        moved = math.hypot(bx - ax, by - ay) * (1.0 + 1e-9)
        out[i] = best
    return out


@njit(cache=True)
def segment_clearance_kernel(ax: float, ay: float, bx: float, by: float, circles: Array,
                             verts: Array, starts: Array, counts: Array, bb_lo: Array,
                             bb_hi: Array, grid: Array, start: Array, items: Array,
                             stamp: Array, mark: int, buf: Array) -> float:
    """ObstacleSet.segment_clearance of one segment: max(least of |c - AB| - r, 0) over the
    circles (geometry.point_segment_distance(c, A, B)), and over the polygons their least edge
    distance, 0 when A lies inside one. ``stamp``, ``mark`` and ``buf``: the index's scratch
    (:func:`_candidates`; a new ``mark`` per call)."""
    out = math.inf
    if circles.shape[0]:
        low = math.inf
        for c in range(circles.shape[0]):
            low = min(low, _point_segment(circles[c, 0], circles[c, 1], ax, ay, bx, by)
                      - circles[c, 2])
        out = low if low >= 0.0 else 0.0
    npoly = counts.shape[0]
    if npoly:
        every = np.zeros(0, dtype=np.bool_)
        out = min(out, _static_polygons(ax, ay, bx, by, math.inf, verts, starts, counts, bb_lo,
                                        bb_hi, every, grid, start, items, stamp, mark, buf))
    return out


# ------------------------------------------------------------------------------------- sensing
@njit(cache=True)
def rays_kernel(ox: float, oy: float, dirs: Array, reach: float, verts: Array, starts: Array,
                counts: Array, bb_lo: Array, bb_hi: Array, grid: Array, start: Array,
                items: Array, stamp: Array, mark: int, buf: Array) -> tuple[Array, bool]:
    """sensors.ray_segment_distance over the polygons' edges, for the polygons whose box comes
    within ``reach`` of the origin (a farther edge can only give a distance beyond the reach,
    which the caller reads as nothing), and whether the origin lies inside any polygon
    (sensors._inside_any_polygon). Same operations as the references, per ray and edge."""
    n = dirs.shape[0]
    t_min = np.full(n, math.inf)
    inside = False
    m = _candidates(ox - reach, oy - reach, ox + reach, oy + reach, grid, start, items, stamp,
                    mark * 64, buf)
    for q in range(m):
        j = buf[q]
        if _box_gap(ox, oy, ox, oy, bb_lo, bb_hi, j) > reach:
            continue
        crossings = 0
        first, last = starts[j], starts[j] + counts[j]
        for k in range(first, last):
            nxt = k + 1 if k + 1 < last else first
            x, y, xn, yn = verts[k, 0], verts[k, 1], verts[nxt, 0], verts[nxt, 1]
            ex = xn - x
            ey = yn - y
            wx = x - ox
            wy = y - oy
            for r in range(n):
                d0, d1 = dirs[r, 0], dirs[r, 1]
                denom = d0 * ey - d1 * ex
                if not abs(denom) > 1e-15:
                    continue
                t = (wx * ey - wy * ex) / denom
                u = (wx * d1 - wy * d0) / denom
                if t >= 0 and u >= 0 and u <= 1 and t < t_min[r]:
                    t_min[r] = t
            if (y > oy) != (yn > oy):
                if ox < x + (oy - y) * (xn - x) / (yn - y):
                    crossings += 1
        if crossings % 2 == 1:
            inside = True
    return t_min, inside


# -------------------------------------------------------------------------- point clearances
@njit(cache=True)
def point_clearances_kernel(points: Array, circles: Array, verts: Array, starts: Array,
                            counts: Array, bb_lo: Array, bb_hi: Array, grid: Array,
                            start: Array, items: Array, stamp: Array, mark: int,
                            buf: Array) -> Array:
    """ObstacleSet.point_clearance of each point: the least of the circles' hypot - r and the
    polygons' signed edge distances (negative inside, even-odd), +inf with no obstacle. The
    polygons are searched as :func:`_static_polygons` does (a reach growing from one cell);
    a polygon whose box is farther than the best value found cannot be the least (its signed
    distance is at least its box gap). Point i marks its polygons with ``mark + i``."""
    out = np.empty(points.shape[0])
    npoly = counts.shape[0]
    for i in range(points.shape[0]):
        px, py = points[i, 0], points[i, 1]
        best = math.inf
        for c in range(circles.shape[0]):
            best = min(best, math.hypot(px - circles[c, 0], py - circles[c, 1]) - circles[c, 2])
        if npoly:
            reach = grid[2]
            for round_ in range(1, 64):
                n = _candidates(px - reach, py - reach, px + reach, py + reach, grid, start,
                                items, stamp, (mark + i) * 64 + round_, buf)
                every = n == npoly
                found = math.inf
                for q in range(n):
                    j = buf[q]
                    gap = _box_gap(px, py, px, py, bb_lo, bb_hi, j)
                    if (not every and gap > reach) or gap > min(best, found) + SLACK:
                        continue
                    found = min(found, _signed_polygon(px, py, verts, starts[j], counts[j]))
                best = min(best, found)
                if best <= reach or every:
                    break
                reach *= 4.0
        out[i] = best
    return out
