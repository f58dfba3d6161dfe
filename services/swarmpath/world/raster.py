"""Occupancy grids: rasterize a scenario's obstacles at any time, and convert world <-> cell.

Pure numpy, no I/O. Grid convention (used by the importers too):

* ``data[row, col]``; row 0 is the *bottom* of the map (lowest y) and rows grow with y, cols with x
  (like ROS ``nav_msgs/OccupancyGrid``; *not* image order, where row 0 is the top).
* Cell ``(row, col)`` covers ``[ox + col*res, ox + (col+1)*res) x [oy + row*res, oy + (row+1)*res)``
  with ``(ox, oy) = origin``; its centre is at ``+ res/2``.
* Values follow ROS: 0 free, 100 occupied, -1 unknown, 1..99 a graded occupancy (``scale`` maps).

Rasterization rule: a cell is occupied iff the clearance of its *centre* (signed distance to the
nearest obstacle surface, negative inside) is ``<= inflation``. With ``inflation = 0`` that is "the
centre is inside or on an obstacle"; with the robot radius it is the configuration-space obstacle
under the product's collision rule (touching counts, see :mod:`swarmpath.world.geometry`).
Obstacles are processed one at a time over the cells of their inflated bounding box, so the cost
grows with the obstacles' area, not with grid size times obstacle count.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmpath.world.geometry import ObstacleSet, point_polygon_distance
from swarmpath.world.scenario import Scenario, WorldState

Array = NDArray[np.float64]
IndexArray = NDArray[np.intp]
BoolArray = NDArray[np.bool_]

__all__ = [
    "FREE",
    "OCCUPIED",
    "UNKNOWN",
    "GridSpec",
    "OccupancyGrid",
    "rasterize",
    "rasterize_scenario",
]

FREE = 0
OCCUPIED = 100
UNKNOWN = -1


@dataclass(frozen=True)
class GridSpec:
    """Geometry of a grid: ``origin`` (lower-left corner of cell (0, 0)), ``resolution`` (m/cell),
    ``shape = (rows, cols)``."""

    origin: tuple[float, float]
    resolution: float
    shape: tuple[int, int]

    def __post_init__(self) -> None:
        object.__setattr__(self, "origin", (float(self.origin[0]), float(self.origin[1])))
        object.__setattr__(self, "resolution", float(self.resolution))
        object.__setattr__(self, "shape", (int(self.shape[0]), int(self.shape[1])))
        if not (math.isfinite(self.resolution) and self.resolution > 0):
            raise ValueError(f"resolution must be > 0, got {self.resolution}")
        if self.shape[0] < 1 or self.shape[1] < 1:
            raise ValueError(f"grid shape must be at least (1, 1), got {self.shape}")

    @classmethod
    def covering(
        cls, size: tuple[float, float], resolution: float, origin: tuple[float, float] = (0.0, 0.0)
    ) -> GridSpec:
        """The smallest grid from ``origin`` covering a ``(w, h)`` world (cells may overhang)."""
        w, h = size
        eps = 1e-9
        cols = max(1, math.ceil(w / resolution - eps))
        rows = max(1, math.ceil(h / resolution - eps))
        return cls(origin, resolution, (rows, cols))

    @property
    def rows(self) -> int:
        return self.shape[0]

    @property
    def cols(self) -> int:
        return self.shape[1]

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) covered by the grid."""
        ox, oy = self.origin
        return (ox, oy, ox + self.cols * self.resolution, oy + self.rows * self.resolution)

    def world_to_cell(self, points: ArrayLike, clip: bool = False) -> IndexArray:
        """(..., 2) world ``(x, y)`` -> (..., 2) integer ``(row, col)``.

        Out-of-grid points give out-of-range indices unless ``clip`` (then the nearest cell, so a
        point on the far edge of the world, e.g. a goal at (w, h), maps to the last cell).
        """
        P = np.asarray(points, dtype=np.float64)
        ox, oy = self.origin
        col = np.floor((P[..., 0] - ox) / self.resolution)
        row = np.floor((P[..., 1] - oy) / self.resolution)
        rc = np.stack([row, col], axis=-1)
        if clip:
            rc = np.clip(rc, 0, np.array([self.rows - 1, self.cols - 1]))
        return rc.astype(np.intp)

    def cell_to_world(self, cells: ArrayLike) -> Array:
        """(..., 2) integer ``(row, col)`` -> (..., 2) world ``(x, y)`` of the cell centres."""
        rc = np.asarray(cells, dtype=np.float64)
        ox, oy = self.origin
        x = ox + (rc[..., 1] + 0.5) * self.resolution
        y = oy + (rc[..., 0] + 0.5) * self.resolution
        return np.stack([x, y], axis=-1)

    def in_bounds(self, cells: ArrayLike) -> BoolArray:
        """(..., 2) ``(row, col)`` -> (...) True where the cell is inside the grid."""
        rc = np.asarray(cells)
        return np.asarray(
            (rc[..., 0] >= 0) & (rc[..., 0] < self.rows) & (rc[..., 1] >= 0)
            & (rc[..., 1] < self.cols)
        )

    def centres(self) -> Array:
        """(rows, cols, 2) world coordinates of every cell centre."""
        ox, oy = self.origin
        xs = ox + (np.arange(self.cols) + 0.5) * self.resolution
        ys = oy + (np.arange(self.rows) + 0.5) * self.resolution
        X, Y = np.meshgrid(xs, ys)
        return np.stack([X, Y], axis=-1)


@dataclass(frozen=True, eq=False)
class OccupancyGrid:
    """A grid with ROS occupancy values (int8: 0 free, 100 occupied, -1 unknown, 1..99 graded)."""

    spec: GridSpec
    data: NDArray[np.int8]

    def __post_init__(self) -> None:
        data = np.asarray(self.data, dtype=np.int8)
        if data.shape != self.spec.shape:
            raise ValueError(f"data shape {data.shape} != grid shape {self.spec.shape}")
        object.__setattr__(self, "data", data)

    @classmethod
    def from_bool(cls, spec: GridSpec, occupied: ArrayLike) -> OccupancyGrid:
        occ = np.asarray(occupied, dtype=bool)
        return cls(spec, np.where(occ, OCCUPIED, FREE).astype(np.int8))

    @property
    def resolution(self) -> float:
        return self.spec.resolution

    @property
    def origin(self) -> tuple[float, float]:
        return self.spec.origin

    @property
    def shape(self) -> tuple[int, int]:
        return self.spec.shape

    def blocked(self, unknown_as_occupied: bool = True) -> BoolArray:
        """Boolean obstacle mask: occupied (100) cells, plus unknown (-1) and graded (1..99) cells
        when ``unknown_as_occupied``."""
        d = self.data
        if unknown_as_occupied:
            return np.asarray(d != FREE)
        return np.asarray(d == OCCUPIED)

    def world_to_cell(self, points: ArrayLike, clip: bool = False) -> IndexArray:
        return self.spec.world_to_cell(points, clip)

    def cell_to_world(self, cells: ArrayLike) -> Array:
        return self.spec.cell_to_world(cells)

    def is_blocked(self, points: ArrayLike, unknown_as_occupied: bool = True) -> BoolArray:
        """(..., 2) world points -> (...) True where the containing cell is blocked or off-grid."""
        rc = self.spec.world_to_cell(points)
        inside = self.spec.in_bounds(rc)
        rcc = np.clip(rc, 0, np.array([self.spec.rows - 1, self.spec.cols - 1]))
        b = self.blocked(unknown_as_occupied)[rcc[..., 0], rcc[..., 1]]
        return np.asarray(~inside | b)


def _box_cells(
    spec: GridSpec, x0: float, y0: float, x1: float, y1: float
) -> tuple[slice, slice] | None:
    """Row/col slices of the cells whose centres may lie in [x0, x1] x [y0, y1]."""
    ox, oy = spec.origin
    res = spec.resolution
    c0 = max(math.floor((x0 - ox) / res - 0.5), 0)
    c1 = min(math.ceil((x1 - ox) / res - 0.5), spec.cols - 1)
    r0 = max(math.floor((y0 - oy) / res - 0.5), 0)
    r1 = min(math.ceil((y1 - oy) / res - 0.5), spec.rows - 1)
    if c0 > c1 or r0 > r1:
        return None
    return slice(r0, r1 + 1), slice(c0, c1 + 1)


def _circles_into(out: BoolArray, circles: Array, xs: NDArray[np.floating[Any]],
                  ys: NDArray[np.floating[Any]], spec: GridSpec, inflation: float) -> None:
    """Mark in ``out`` the cells whose centre is within ``inflation`` of a circle: each circle's
    window of cells (as wide as the widest circle's) at once, the same test cell by cell
    (thousands of sensed points as circles of radius 0: swarm_aim.free_space_path)."""
    reach = circles[:, 2] + inflation
    circles = circles[reach >= 0]
    if not len(circles):
        return
    res, (ox, oy) = spec.resolution, spec.origin
    half = math.ceil(float(np.max(circles[:, 2] + inflation)) / res) + 1
    k = np.arange(-half, half + 1)
    chunk = max(1, 2_000_000 // len(k) ** 2)  # bounded memory: 2 million cells at a time
    for lo in range(0, len(circles), chunk):
        cx, cy, r = circles[lo:lo + chunk].T
        col = np.floor((cx - ox) / res).astype(np.int64)[:, None] + k  # (n, w)
        row = np.floor((cy - oy) / res).astype(np.int64)[:, None] + k
        cin = (col >= 0) & (col < spec.cols)
        rin = (row >= 0) & (row < spec.rows)
        colc, rowc = np.clip(col, 0, spec.cols - 1), np.clip(row, 0, spec.rows - 1)
        d = np.hypot(xs[colc][:, None, :] - cx[:, None, None],
                     ys[rowc][:, :, None] - cy[:, None, None]) - r[:, None, None]
        hit = (d <= inflation) & rin[:, :, None] & cin[:, None, :]
        n, i, j = np.nonzero(hit)
        out[rowc[n, i], colc[n, j]] = True


def rasterize(obstacles: ObstacleSet, spec: GridSpec, inflation: float = 0.0) -> BoolArray:
    """(rows, cols) mask: True where a cell centre's clearance to ``obstacles`` <= ``inflation``."""
    inflation = float(inflation)
    if not math.isfinite(inflation):
        raise ValueError(f"inflation must be finite, got {inflation}")
    out = np.zeros(spec.shape, dtype=bool)
    ox, oy = spec.origin
    res = spec.resolution
    xs = ox + (np.arange(spec.cols) + 0.5) * res
    ys = oy + (np.arange(spec.rows) + 0.5) * res
    _circles_into(out, obstacles.circles, xs, ys, spec, inflation)
    for poly in obstacles.polygons:
        lo = poly.min(axis=0) - max(inflation, 0.0)
        hi = poly.max(axis=0) + max(inflation, 0.0)
        box = _box_cells(spec, lo[0], lo[1], hi[0], hi[1])
        if box is None:
            continue
        rs, cs = box
        X, Y = np.meshgrid(xs[cs], ys[rs])
        d = point_polygon_distance(np.stack([X, Y], axis=-1), poly)
        out[rs, cs] |= d <= inflation
    return out


def rasterize_scenario(
    source: Scenario | WorldState,
    resolution: float,
    t: float | None = None,
    *,
    inflate: bool | float = False,
    static_only: bool = False,
) -> OccupancyGrid:
    """Occupancy grid covering the scenario's world ``[0, w] x [0, h]`` at time ``t``.

    ``source``: a :class:`Scenario` (obstacles at t = 0, or at ``t`` when nothing moves at random -
    random motion needs a :class:`WorldState`, which is where its random stream lives) or a
    :class:`WorldState` (default ``t``: its current time). ``inflate``: False (0), True (the
    robot radius) or a distance in metres. ``static_only``: only the never-moving obstacles.
    """
    if isinstance(source, WorldState):
        world = source
        scenario = source.scenario
        obs = world.static_obstacles() if static_only else world.obstacles_at(
            world.time if t is None else t
        )
    else:
        scenario = source
        if static_only:
            obs = scenario.static_obstacles()
        elif t is None or t == 0 or not any(o.is_moving for o in scenario.obstacles):
            obs = scenario.initial_obstacles()
        elif scenario.has_random_motion:
            raise ValueError(
                "obstacles move at random: pass a WorldState (scenario.instantiate(rng)) "
                "to rasterize them at t > 0"
            )
        else:
            obs = scenario.instantiate(np.random.default_rng(0)).obstacles_at(t)  # no draws
    if isinstance(inflate, bool):
        inflation = scenario.robot.radius if inflate else 0.0
    else:
        inflation = float(inflate)
    spec = GridSpec.covering(scenario.size, resolution)
    return OccupancyGrid.from_bool(spec, rasterize(obs, spec, inflation))
