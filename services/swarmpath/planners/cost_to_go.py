"""Cost-to-go on a static map: the length of the shortest way to a goal, from any point.

Used by the RFO family as its "closer to the target" measure when the paper's straight-line
distance (eq 17) leaves every fox trapped behind an obstacle that faces the goal (a concave
pocket, a wall between start and goal reaching the border): a measure that decreases along the
shortest way has no such trap, so "closer" always has a way forward.

The field is Dijkstra's distance to the goal over an 8-connected grid (no corner cutting) of the
cells whose centre keeps more than ``clearance`` from every obstacle, at ``cells`` cells along the
longer world side, and never coarser than ``clearance`` itself (as far as ``MAX_CELLS`` allows): on
maze512-32-9 (512 m, 1 m walls, clearance 0.30 m) 300 cells are 1.7 m, coarser than a wall, and the
RFO family's foxes stalled at wall ends (no point of their 3 m box both valid and "closer" on that
grid); at 0.81 m (the cap) RFO-GWO reaches the goal. A point's value is the least, over the free
cells of its 3 x 3 neighbourhood, of the cell's value plus the straight distance to the cell's
centre (+inf when none is free or none reaches the goal). Grid distances are up to 8% above the
true length (octile moves); the planners need only that the value decreases toward the goal. Pure
numpy and scipy, no state beyond the field.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from swarmpath.world.geometry import ObstacleSet
from swarmpath.world.raster import GridSpec, rasterize

Array = NDArray[np.float64]

#: Largest number of grid cells a field may have (memory and Dijkstra time stay bounded).
MAX_CELLS = 400_000


class CostToGo:
    """Distance to ``goal`` along free space of a ``world = (w, h)`` map (see the module)."""

    def __init__(self, obstacles: ObstacleSet, world: tuple[float, float], goal: Array,
                 clearance: float, cells: int = 300):
        w, h = float(world[0]), float(world[1])
        res = max(w, h) / max(int(cells), 1)
        if clearance > 0:
            res = min(res, float(clearance))
        if math.ceil(w / res) * math.ceil(h / res) > MAX_CELLS:
            res = math.sqrt(w * h / MAX_CELLS) * 1.01
        spec = GridSpec.covering((w, h), res)
        self._solve(spec, ~rasterize(obstacles, spec, clearance), goal)

    @classmethod
    def on_grid(cls, spec: GridSpec, free: NDArray[np.bool_], goal: Array) -> CostToGo:
        """The field over a grid whose free cells are given (``free``, shape ``spec.shape``),
        e.g. an occupancy memory's (:mod:`swarmpath.planners.swarm_memory`)."""
        field = cls.__new__(cls)
        field._solve(spec, np.asarray(free, dtype=bool), goal)
        return field

    def _solve(self, spec: GridSpec, free: NDArray[np.bool_], goal: Array) -> None:
        """Dijkstra's distance to ``goal`` over the free cells of ``spec`` (module docstring)."""
        self.spec = spec
        self.free = free
        rows, cols = self.spec.shape
        self.goal = np.asarray(goal, dtype=float)
        res = spec.resolution
        idx = np.arange(rows * cols).reshape(rows, cols)

        def part(dr: int, dc: int) -> tuple[slice, slice]:
            """The cells that have a neighbour at (dr, dc) inside the grid."""
            return (slice(max(0, -dr), rows - max(0, dr)), slice(max(0, -dc), cols - max(0, dc)))

        src, dst, cost = [], [], []
        diag = math.sqrt(2.0) * res
        for dr, dc, c in ((0, 1, res), (1, 0, res), (1, 1, diag), (1, -1, diag)):
            here, there = part(dr, dc), part(-dr, -dc)
            ok = self.free[here] & self.free[there]
            if dr and dc:  # no corner cutting: both orthogonal neighbours free
                ok &= self.free[part(dr, 0)][:, here[1]] & self.free[part(0, dc)][here[0], :]
            src.append(idx[here][ok])
            dst.append(idx[there][ok])
            cost.append(np.full(int(ok.sum()), c))
        # A virtual source (index n) joined to the free cells around the goal by the straight
        # distance: the goal's own cell may be blocked at this resolution though the goal is clear.
        n = rows * cols
        seeds, offsets = self._neighbours(self.goal[None, :])
        keep = np.isfinite(offsets[0])
        src.append(np.full(int(keep.sum()), n))
        dst.append(seeds[0][keep])
        cost.append(offsets[0][keep])
        graph = coo_matrix((np.concatenate(cost), (np.concatenate(src), np.concatenate(dst))),
                           shape=(n + 1, n + 1)).tocsr()
        field = dijkstra(graph, directed=False, indices=n)[:n]
        self.field = field.reshape(rows, cols)

    def _neighbours(self, P: Array) -> tuple[NDArray[np.intp], Array]:
        """Flat indices of the 3 x 3 cells around each point and the straight distance from the
        point to each cell's centre (+inf for cells outside the grid or blocked)."""
        rows, cols = self.spec.shape
        rc = self.spec.world_to_cell(P, clip=True)  # (m, 2)
        d = np.array([(a, b) for a in (-1, 0, 1) for b in (-1, 0, 1)])
        cells = rc[:, None, :] + d[None, :, :]  # (m, 9, 2)
        inside = self.spec.in_bounds(cells)
        cells = np.clip(cells, 0, np.array([rows - 1, cols - 1]))
        flat = cells[..., 0] * cols + cells[..., 1]
        centre = self.spec.cell_to_world(cells)
        dist = np.hypot(*(centre - P[:, None, :]).transpose(2, 0, 1))
        ok = inside & self.free.reshape(-1)[flat]
        return flat, np.where(ok, dist, np.inf)

    def __call__(self, P: Array) -> Array:
        """Cost-to-go of points P (..., 2); exactly 0 at the goal."""
        P = np.asarray(P, dtype=float)
        shape = P.shape[:-1]
        Q = P.reshape(-1, 2)
        flat, off = self._neighbours(Q)
        value = np.min(self.field.reshape(-1)[flat] + off, axis=1)
        value = np.where(np.all(Q == self.goal, axis=1), 0.0, value)
        return value.reshape(shape)
