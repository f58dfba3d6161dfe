"""The simulator's geometry on large maps, by numpy or compiled: the same numbers either way.

* :func:`step_clearances` - the swept clearance of every step of a trajectory
  (:func:`swarmpath.metrics.step_clearances` calls it);
* :func:`segment_clearance` - one segment against a static map
  (:meth:`~swarmpath.world.geometry.ObstacleSet.segment_clearance`: the motion guard);
* :func:`point_clearances` - points against a map (:meth:`~swarmpath.world.geometry.ObstacleSet.
  point_clearance`: the clearance along a path of :mod:`swarmpath.path_metrics`);
* :func:`polygon_rays` - range rays against the polygons (:func:`swarmpath.robot.sensors.
  read_sensors_in`).

``backend``: ``"numpy"`` (the reference), ``"numba"`` (:mod:`swarmpath.world.clearance_compiled`:
only the polygons a query can reach are visited, each distance with the reference's operations,
so every result is the same double) or ``"auto"`` (numba when it is installed and its kernels
are compiled, else numpy: a cold cache compiles them in the background meanwhile,
:mod:`swarmpath.optimizers.compiled.ready`). The results do not depend on the choice, so
``"auto"`` keeps a run the same on any worker; numba only saves time (docs/benchmarks.md,
"Large maps").
"""

from __future__ import annotations

import itertools
import math
import time
import weakref
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from swarmpath.world.geometry import ObstacleSet

Array = NDArray[np.float64]
BACKENDS = ("auto", "numpy", "numba")


@lru_cache(maxsize=1)
def compiled_available() -> bool:
    """Whether numba can be imported (the ``fast`` extra)."""
    try:
        import numba  # noqa: F401
    except ImportError:
        return False
    return True


def resolve(backend: str) -> str:
    """``"numpy"`` or ``"numba"`` for a ``backend`` of :data:`BACKENDS`."""
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
    if backend == "auto":
        return "numba" if compiled_available() and _kernels_ready() else "numpy"
    if backend == "numba" and not compiled_available():
        raise ValueError("backend 'numba' needs numba installed (pip install 'swarmpath[fast]')")
    return backend


_READY = [False, 0.0]  # the kernels are compiled; when to look again if not


def _kernels_ready() -> bool:
    """Whether the clearance and sensing kernels are compiled (the piece ``("map",
    "clearance")`` of :mod:`swarmpath.optimizers.compiled.ready`): asked at most once every two
    seconds while they are not (every query resolves its backend), then remembered."""
    if _READY[0]:
        return True
    now = time.monotonic()
    if now >= _READY[1]:
        from swarmpath.optimizers.compiled.ready import MAP_PIECE, ready_for_auto

        _READY[0], _READY[1] = ready_for_auto([MAP_PIECE]), now + 2.0
    return bool(_READY[0])


@dataclass(eq=False)
class PolygonIndex:
    """An obstacle set's polygons as the kernels read them, with a uniform grid over their
    bounding boxes (cells about as many as four per polygon, never smaller than the mean box)."""

    circles: Array
    verts: Array
    starts: NDArray[np.int64]
    counts: NDArray[np.int64]
    bb_lo: Array
    bb_hi: Array
    grid: Array  # x0, y0, cell, nx, ny
    start: NDArray[np.int64]
    items: NDArray[np.int64]
    stamp: NDArray[np.int64] = field(repr=False)
    buf: NDArray[np.int64] = field(repr=False)
    marks: itertools.count = field(default_factory=lambda: itertools.count(1), repr=False)

    @classmethod
    def build(cls, obstacles: ObstacleSet) -> PolygonIndex:
        from swarmpath.world.clearance_compiled import build_index

        polys = obstacles.polygons
        counts = np.array([len(p) for p in polys], dtype=np.int64)
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
        verts = np.ascontiguousarray(np.concatenate(polys) if polys else np.zeros((0, 2)))
        if polys:
            bb_lo = np.array([p.min(axis=0) for p in polys])
            bb_hi = np.array([p.max(axis=0) for p in polys])
            lo, hi = bb_lo.min(axis=0), bb_hi.max(axis=0)
            span = np.maximum(hi - lo, 1e-9)
            mean_box = float(np.mean(bb_hi - bb_lo))
            cell = max(math.sqrt(float(span[0] * span[1]) / (4 * len(polys))), mean_box, 1e-6)
            nx, ny = (int(min(max(math.ceil(float(s) / cell), 1), 4096)) for s in span)
        else:
            bb_lo = bb_hi = np.zeros((0, 2))
            lo, cell, nx, ny = np.zeros(2), 1.0, 1, 1
        grid = np.array([lo[0], lo[1], cell, nx, ny], dtype=np.float64)
        start, items = build_index(bb_lo, bb_hi, float(lo[0]), float(lo[1]), cell, nx, ny)
        n = len(polys)
        return cls(np.ascontiguousarray(obstacles.circles), verts, starts, counts, bb_lo, bb_hi,
                   grid, start, items, np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64))

    def mark(self, queries: int = 1) -> int:
        """The first of ``queries`` fresh marks (one per query) for the visited polygons."""
        first = next(self.marks)
        for _ in range(queries - 1):
            next(self.marks)
        return first


_INDEXES: weakref.WeakKeyDictionary[ObstacleSet, PolygonIndex] = weakref.WeakKeyDictionary()


def index_of(obstacles: ObstacleSet) -> PolygonIndex:
    """The (remembered) index of an obstacle set; a static world hands out one set for the run."""
    index = _INDEXES.get(obstacles)
    if index is None:
        index = PolygonIndex.build(obstacles)
        _INDEXES[obstacles] = index
    return index


def step_clearances(xy: Array, ref: ObstacleSet, offsets: Array | None) -> Array:
    """Compiled :func:`swarmpath.metrics.step_clearances` (rows >= 2): ``offsets`` (rows x
    obstacles x 2, circles first) each obstacle's offset from its pose in ``ref`` at every row,
    or None when nothing moves."""
    from swarmpath.world.clearance_compiled import step_clearances_kernel

    index = index_of(ref)
    total = ref.circles.shape[0] + len(ref.polygons)
    slot = np.full(total, -1, dtype=np.int64)
    off = np.zeros((len(xy), 0, 2))
    if offsets is not None and offsets.size:
        moving = np.flatnonzero(np.any(offsets != 0.0, axis=(0, 2)))
        slot[moving] = np.arange(len(moving))
        off = np.ascontiguousarray(offsets[:, moving])
    return np.asarray(step_clearances_kernel(
        np.ascontiguousarray(xy, dtype=np.float64), index.circles, index.verts, index.starts,
        index.counts, index.bb_lo, index.bb_hi, slot, off, index.grid, index.start, index.items))


def segment_clearance(obstacles: ObstacleSet, a: Array, b: Array, backend: str = "auto") -> float:
    """``obstacles.segment_clearance(a, b)`` of one segment, as a float."""
    if resolve(backend) == "numpy" or obstacles.is_empty:
        return float(obstacles.segment_clearance(a, b))
    from swarmpath.world.clearance_compiled import segment_clearance_kernel

    i = index_of(obstacles)
    return float(segment_clearance_kernel(
        float(a[0]), float(a[1]), float(b[0]), float(b[1]), i.circles, i.verts, i.starts,
        i.counts, i.bb_lo, i.bb_hi, i.grid, i.start, i.items, i.stamp, i.mark(), i.buf))


def point_clearances(obstacles: ObstacleSet, points: Array, backend: str = "auto") -> Array:
    """``obstacles.point_clearance(points)`` of (n, 2) points (the same doubles)."""
    P = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 2)
    if resolve(backend) == "numpy" or obstacles.is_empty or not obstacles.polygons:
        return np.asarray(obstacles.point_clearance(P), dtype=np.float64)
    from swarmpath.world.clearance_compiled import point_clearances_kernel

    i = index_of(obstacles)
    return np.asarray(point_clearances_kernel(
        P, i.circles, i.verts, i.starts, i.counts, i.bb_lo, i.bb_hi, i.grid, i.start, i.items,
        i.stamp, i.mark(len(P)), i.buf))


def polygon_rays(obstacles: ObstacleSet, origin: Array, dirs: Array,
                 reach: float) -> tuple[Array, bool]:
    """Compiled distances along unit rays ``dirs`` from ``origin`` to the polygons' edges where
    they come within ``reach`` (inf otherwise), and whether ``origin`` lies inside a polygon."""
    from swarmpath.world.clearance_compiled import rays_kernel

    i = index_of(obstacles)
    # rounding of a distance is far below this for coordinates up to MAX_METRES
    slack = 1e-6 * (1.0 + max(abs(float(origin[0])), abs(float(origin[1])), reach))
    t, inside = rays_kernel(float(origin[0]), float(origin[1]), np.ascontiguousarray(dirs),
                            reach + slack, i.verts, i.starts, i.counts, i.bb_lo, i.bb_hi,
                            i.grid, i.start, i.items, i.stamp, i.mark(), i.buf)
    return np.asarray(t), bool(inside)


def warm() -> None:
    """Compile (or load from numba's cache) every clearance and sensing kernel by one tiny call
    each (a kernel has one signature whatever the sizes): every map run calls them, so a
    worker that warms before it leases compiles none inside a map lease (about 10 s of CPU
    cold)."""
    box = np.array([[2.0, 2.0], [3.0, 2.0], [3.0, 3.0], [2.0, 3.0]])
    obstacles = ObstacleSet(circles=np.array([[0.0, 0.0, 0.5]]), polygons=(box,))
    xy = np.array([[1.0, 0.0], [1.5, 1.0], [4.0, 4.0]])
    step_clearances(xy, obstacles, None)
    segment_clearance(obstacles, xy[0], xy[2], backend="numba")
    point_clearances(obstacles, xy, backend="numba")
    polygon_rays(obstacles, xy[0], np.array([[1.0, 0.0], [0.0, 1.0]]), 5.0)
