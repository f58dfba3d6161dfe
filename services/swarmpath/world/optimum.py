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
an imported grid map), is dropped
(:func:`swarmpath.world.optimum_tangents._covered_vertices`). Disk pairs are processed in chunks
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
from numpy.typing import ArrayLike
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from swarmpath.world.geometry import ObstacleSet
from swarmpath.world.optimum_base import (
    DEFAULT_BUDGET,
    TOL,
    TWO_PI,
    Array,
    IntArray,
    World,
    _norm,
)
from swarmpath.world.optimum_index import EdgeIndex
from swarmpath.world.optimum_scene import _Scene
from swarmpath.world.optimum_tangents import (
    _arc_points,
    _disks,
    _locally_free,
    _pair_rows,
    _tangents,
)

__all__ = ["DEFAULT_BUDGET", "MAX_DISKS", "TOL", "OptimalPath", "shortest_path"]

MAX_DISKS = 20_000
INDEX_ABOVE = 600  # disks above which the spatial index decides pairs, segments and arcs
_PAIRS = 1 << 17  # disk pairs per chunk
_TINY_WEIGHT = 1e-300  # zero-length edges must stay edges in the sparse graph


def _sorted_csr(rows: IntArray, cols: IntArray, weights: Array, n: int) -> csr_matrix:
    """The n x n sparse matrix with ``weights`` at (``rows``, ``cols``), given sorted by (row,
    column) without repeats: these arrays already are its canonical CSR form (the same matrix
    as ``coo_matrix(...).tocsr()``, without the conversion and duplicate summing)."""
    indptr = np.zeros(n + 1, dtype=np.intp)
    np.cumsum(np.bincount(rows, minlength=n), out=indptr[1:])
    return csr_matrix((weights, cols, indptr), shape=(n, n))


def _compiled(scene: _Scene) -> tuple[np.ndarray, ...]:
    """The scene's arrays as :mod:`swarmpath.world.optimum_compiled` takes them (box, circles,
    polygon edges and their grown boxes)."""
    box = np.zeros(0)
    if scene.lo is not None and scene.hi is not None:
        box = np.concatenate([scene.lo - TOL, scene.hi + TOL])
    f = np.ascontiguousarray
    return (box, f(scene.circles, dtype=np.float64), f(scene.e0, dtype=np.float64),
            f(scene.e1, dtype=np.float64), scene.starts, scene.counts,
            f(scene.bb_lo, dtype=np.float64), f(scene.bb_hi, dtype=np.float64))


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
    backend: str = "numpy",
) -> OptimalPath:
    """Exact shortest path from start to goal for a disk robot of radius ``margin``.

    See the module docstring for the method, the tolerance, the world-box handling and the
    limits. ``budget``: seconds of wall time after which the search gives up (``None``: no
    limit); ``progress(fraction)`` is called as the tangent pairs are processed; ``index``: use
    the spatial index of :mod:`swarmpath.world.optimum_index` (``None``: when there are more than
    ``INDEX_ABOVE`` disks; only with margin > 0 and polygons); ``backend = "numba"``: the
    tangents and segment checks of small scenes compiled
    (:mod:`swarmpath.world.optimum_compiled`, the same path to the last bit). Raises ValueError
    if start or goal is outside ``world`` or inside an inflated obstacle.
    """
    started = time.perf_counter()
    s = np.asarray(start, dtype=np.float64).reshape(2)
    g = np.asarray(goal, dtype=np.float64).reshape(2)
    if not (math.isfinite(margin) and margin >= 0.0):
        raise ValueError(f"margin must be finite and >= 0, got {margin}")
    if backend not in ("numpy", "numba"):
        raise ValueError(f"backend must be 'numpy' or 'numba', got {backend!r}")
    scene = _Scene(obstacles, margin, world)
    for name, p in (("start", s), ("goal", g)):
        if not bool(scene.in_box(p)):
            raise ValueError(f"{name} {p.tolist()} is outside the world box {world}")
        who = scene.blocker(p)
        if who is not None:
            raise ValueError(f"{name} {p.tolist()} is inside the inflated {who}")

    compiled = _compiled(scene) if backend == "numba" and margin > 0.0 else None
    if compiled is not None:
        scene.backend = "numba"
        from swarmpath.world.optimum_compiled import segments_blocked_kernel

        direct = not segments_blocked_kernel(s[None], g[None], margin, *compiled)[0]
    else:
        direct = not scene.segments_blocked(s[None], g[None])[0]
    if direct:
        return OptimalPath(float(_norm(g - s)), np.stack([s, g]), True, None)

    if compiled is not None:
        from swarmpath.world.optimum_compiled import disks_kernel

        centres, radii, na, nb = disks_kernel(s, g, compiled[1], compiled[2], compiled[5],
                                              float(margin))
    else:
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
    if compiled is not None and edge_index is None and n_disks * (n_disks - 1) <= _PAIRS:
        from swarmpath.world.optimum_compiled import tangents_kernel

        # one chunk (the loop below would take every pair at once), compiled
        found.append(tangents_kernel(centres, radii, na, nb, margin, *compiled))
        i0 = n_disks  # skips the loop
        if progress is not None:
            progress(1.0)
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
    graph = _sorted_csr(lo_[sel], hi_[sel], np.maximum(ew[sel], _TINY_WEIGHT), n_nodes)
    dist, pred = dijkstra(graph, directed=False, indices=0, return_predecessors=True)
    length = float(dist[1])
    if not math.isfinite(length):
        return OptimalPath(math.inf, np.zeros((0, 2)), True, "no collision-free path exists")

    # Polyline: walk the predecessors back from the goal, expanding arcs.
    chain = [1]
    while chain[-1] != 0:
        chain.append(int(pred[chain[-1]]))
    chain.reverse()
    pts = [node_xy[:1]]  # pieces (k, 2) of the polyline, joined once at the end
    n_tan = len(node_u)
    for a, b in itertools.pairwise(chain):
        cand = np.flatnonzero((lo_ == min(a, b)) & (hi_ == max(a, b)))
        e = int(cand[np.argmin(ew[cand])])
        if e < n_tan:
            pts.append(node_xy[b : b + 1])
            continue
        k = e - n_tan
        dk, th0, dth = int(adisk[k]), float(ath0[k]), float(adth[k])
        if au[k] == a:
            arc = _arc_points(centres[dk], float(radii[dk]), th0, dth, arc_tol)
        else:
            arc = _arc_points(centres[dk], float(radii[dk]), th0 + dth, -dth, arc_tol)
        arc[-1] = node_xy[b]
        pts.append(arc)
    poly = np.concatenate(pts)
    dup = np.zeros(len(poly), dtype=bool)
    dup[1:] = np.all(poly[1:] == poly[:-1], axis=1)
    return OptimalPath(length, poly[~dup], True, None)
