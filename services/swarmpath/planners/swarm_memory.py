"""The sensors-only fallback of the swarm local planner: a way on the robot's occupancy memory
(``escape_plan = "memory"``; docs/planners.md, "Leaving clutter with sensors only").

The papers' planners decide from what the sensors return now; the swarm's own aim remembers the
points of the last ``memory`` seconds only, so in a maze it walks back into dead ends it has
already seen (maze-32-32-4: 0 of 8 swarm planners at the goal, docs/benchmarks.md). This module
is what the robot remembers for the whole run, and the way it plans on it:

* **Memory.** An occupancy grid of the world at ``cell`` metres (the planner's ``map_cell``;
  coarser when the world would need more than :data:`~swarmpath.planners.cost_to_go.MAX_CELLS`
  cells, so memory and a plan's CPU are bounded). A cell is occupied once a scan's hit falls
  in it (the first hit is kept as the cell's point), for the rest of the run: the world is
  taken as static (a mover leaves its trail in the memory; :meth:`MemoryWay.remember` says why
  motion is not trusted to free cells). Only the robot's own scans feed it: the planner never
  sees the map.
* **The way** (:class:`MemoryWay`): the shortest way on that grid with every cell not known to
  be occupied assumed free (planning with the free-space assumption: Stentz, "Optimal and
  efficient path planning for partially-known environments", ICRA 1994, D*; Koenig & Likhachev,
  "D* Lite", AAAI 2002; Koenig, Tovey & Smirnov, Artificial Intelligence 147, 2003): Dijkstra's
  cost-to-go from the goal over the 8-connected cells whose centre keeps ``clearance`` plus
  half a cell diagonal from every occupied cell's centre (so from every remembered hit, wherever
  in its cell it lies), descended from the robot and pulled taut against the remembered hits
  (:func:`~swarmpath.planners.swarm_guide.descend`, :func:`~swarmpath.planners.swarm_guide.taut`).
  The swarm aims at its shortcut point and follows it as the global guide's way is followed
  (:class:`~swarmpath.planners.swarm_guide.Way`).
* **Replanning only on change.** A new hit within ``clearance`` of the rest of the way, the robot
  more than ``rejoin`` off it, or the goal moved: plan again; otherwise the way is kept. Hits
  only add obstacles, and obstacles off the way cannot make another way shorter, so the kept way
  is the one a full replan (D* Lite's) would return, up to ties.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import distance_transform_edt

from swarmpath.planners import sensed_map
from swarmpath.planners.cost_to_go import MAX_CELLS, CostToGo
from swarmpath.planners.swarm_guide import Way, descend, taut
from swarmpath.world.geometry import ObstacleSet, point_segment_distance
from swarmpath.world.raster import GridSpec

Array = NDArray[np.float64]

#: Cells (beyond the clearance) around the robot searched for a free cell to start the way from
#: when the robot's own cell is too close to a remembered hit (it drove closer than the way's
#: clearance, which the swarm's own margin allows).
START_REACH = 3


class MemoryWay(Way):
    """The occupancy memory and the way on it (see the module docstring)."""

    def __init__(self, world: tuple[float, float], cell: float, clearance: float, rejoin: float,
                 backend: str) -> None:
        super().__init__(rejoin, backend)
        w, h = float(world[0]), float(world[1])
        res = float(cell)
        if math.ceil(w / res) * math.ceil(h / res) > MAX_CELLS:
            res = math.sqrt(w * h / MAX_CELLS) * 1.01
        self.spec = GridSpec.covering((w, h), res)
        self.clearance = float(clearance)
        self.occupied = np.zeros(self.spec.shape, dtype=bool)
        self.point = np.zeros((*self.spec.shape, 2))  # each occupied cell's first hit
        self.leading = False  # the swarm follows this way (set by the planner at a stall)
        self.found = True  # the last plan found a way (False: it aimed along the straight line)

    # --------------------------------------------------------------------------- the memory
    def remember(self, points: Array) -> None:
        """Mark the cells of this scan's hits; the way is dropped (planned again at the next
        aim) when a new hit comes within ``clearance`` of the rest of it. Every hit counts,
        also one the sensing saw move: the ends of the rays that slide along a wall as the robot
        drives by move steadily and are tracked like a mover (maze-32-32-4-cut, MFB seed 1:
        freeing their cells cut 0.6-1.2 m gaps into a wall the robot had driven along, and the
        way led through them)."""
        if not len(points):
            return
        rc = self.spec.world_to_cell(points, clip=True)
        new = ~self.occupied[rc[:, 0], rc[:, 1]]
        if not new.any():
            return
        cells, first = np.unique(rc[new], axis=0, return_index=True)
        self.occupied[cells[:, 0], cells[:, 1]] = True
        self.point[cells[:, 0], cells[:, 1]] = points[new][first]
        if self.way is not None:
            rest = self.way[self.at:]
            if len(rest) < 2 or sensed_map.path_clearance(
                    rest, points[new], math.inf, self.backend) < self.clearance:
                self.way = None

    def points(self) -> Array:
        """One remembered hit per occupied cell."""
        return self.point[self.occupied]

    # ------------------------------------------------------------------------------ the way
    def free(self) -> NDArray[np.bool_]:
        """Cells whose centre keeps ``clearance`` + half a cell diagonal from every occupied
        cell's centre (unknown cells are free)."""
        if not self.occupied.any():
            return np.ones(self.spec.shape, dtype=bool)
        res = self.spec.resolution
        dist = distance_transform_edt(~self.occupied) * res
        return np.asarray(dist > self.clearance + res * math.sqrt(0.5))

    def _plan(self, p: Array, goal: Array) -> Array:
        """The shortest way on the memory from p to the goal, unknown cells free (module
        docstring); the straight line when the memory has none (``found`` False)."""
        self.plans += 1
        free = self.free()
        # the goal is where the robot must go, also when it is nearer a wall than the clearance
        # (thin_wall.json: 1 mm beyond the body): the unoccupied cells around it count as free
        reach = self.clearance + self.spec.resolution
        rr, cc = self._window(goal, math.ceil(reach / self.spec.resolution))
        near = np.hypot(*(self.spec.cell_to_world(np.stack([rr, cc], axis=-1)) - goal).transpose(
            2, 0, 1)) <= reach
        free[rr[near], cc[near]] |= ~self.occupied[rr[near], cc[near]]
        field = CostToGo.on_grid(self.spec, free, goal)
        start = self._start(field, p)
        self.found = start is not None
        if start is None:
            return np.array([p, goal], dtype=float)
        cells = descend(field, start, goal)
        assert cells is not None  # the start cell has a finite value
        cells = np.vstack([p[None, :], cells[1:]])
        points = self.points()
        if not len(points):
            return np.array([p, goal], dtype=float)
        dots = ObstacleSet(circles=np.column_stack([points, np.zeros(len(points))]))
        return taut(cells, dots, self.clearance)

    def _start(self, field: CostToGo, p: Array) -> Array | None:
        """The centre of the free cell the way starts from: the robot's own, or, when that is too
        close to a hit, the best (value + straight distance) free cell within ``clearance`` +
        :data:`START_REACH` cells of the robot that it can reach in a straight line without
        coming closer to a hit; None when none has a way to the goal."""
        spec = field.spec
        r, c = spec.world_to_cell(p, clip=True)
        if np.isfinite(field.field[r, c]):
            return np.asarray(spec.cell_to_world(np.array([r, c])), dtype=float)
        k = START_REACH + math.ceil(self.clearance / spec.resolution)
        rr, cc = self._window(p, k)
        centres = spec.cell_to_world(np.stack([rr, cc], axis=-1)).reshape(-1, 2)
        value = field.field[rr, cc].reshape(-1) + np.hypot(*(centres - p).T)
        ok = np.isfinite(value)
        # ... reached in a straight line that comes no closer to a remembered hit than the
        # robot is now (never through the thin known face of a wall to the unknown behind it)
        points = self.points()
        near = points[np.all(np.abs(points - p) <= (k + 2) * spec.resolution, axis=1)]
        if ok.any() and len(near):
            room = min(self.clearance, float(np.min(np.hypot(*(near - p).T))))
            gap = point_segment_distance(near[None, :, :], p[None, None, :],
                                         centres[ok][:, None, :]).min(axis=1)
            ok[np.flatnonzero(ok)[gap < room - 1e-9]] = False
        if not ok.any():
            return None
        return np.asarray(centres[int(np.argmin(np.where(ok, value, np.inf)))], dtype=float)

    def _window(self, p: Array, k: int) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        """Rows and columns of the cells within ``k`` cells of p's (cut to the grid)."""
        rows, cols = self.spec.shape
        r, c = self.spec.world_to_cell(p, clip=True)
        rr, cc = np.mgrid[max(0, r - k):min(rows, r + k + 1), max(0, c - k):min(cols, c + k + 1)]
        return rr, cc
