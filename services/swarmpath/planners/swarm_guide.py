"""The global guide of a swarm local planner that knows the map (``knowledge = "map"``).

The papers' planners are local: each decision optimises a waypoint within reach of the robot,
toward the goal, around what the sensors returned. On a map that is known, the guide gives the
swarm a target that leads somewhere: the shortest way to the goal on the static map, keeping a
clearance, and the swarm optimises locally toward a point of it, as RFO-GWO's general mode follows
its free-space cost-to-go (docs/planners.md, "What the planner knows").

* **The way.** ``guide = "optimum"``: the exact shortest path (:func:`swarmpath.world.optimum.
  shortest_path`) for a disk of the robot radius plus ``clearance``; when that search gives up
  (its ``guide_budget`` or no path) or ``guide = "cost-to-go"``: the descent of the free-space
  cost-to-go (:class:`~swarmpath.planners.cost_to_go.CostToGo`, cells keeping the same
  clearance) from the robot, its cells pulled taut where the straight segment keeps the
  clearance. The first way, from the start, is remembered per scenario in the process (the
  same doubles for every run; only the first run's planning time includes it).
* **Following.** The robot's place on the way only moves forward (the nearest point of the way
  within a few lookaheads ahead); the rest of the way from the robot is what the aim walks
  (``sensed_map.shortcut``: the farthest point within ``lookahead`` reachable in a straight
  line with the planner's margin from the points it knows). When the robot is more than
  ``guide_rejoin`` off the way (it gave way to a moving obstacle) or the goal moved, the way is
  planned again from where it is.
* **What is near.** The static map's surfaces near the robot, sampled like sensor hits
  (``sensed_map.surface_points``' spacing), are added to the sensed points for the candidates'
  feasibility and repairs: only the polygons whose boxes come within reach, only the part of
  each edge within reach, so that a 512 x 512 grid map costs a decision what a room does.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmpath.planners import sensed_map
from swarmpath.planners.cost_to_go import CostToGo
from swarmpath.world import clearance as fast
from swarmpath.world.geometry import ObstacleSet
from swarmpath.world.optimum import shortest_path

Array = NDArray[np.float64]

#: m: the goal moved farther than this from the end of the way: plan again.
GOAL_MOVED = 0.2
#: lookaheads of the way searched, ahead of the robot's place, for its new place.
SEARCH_AHEAD = 4.0
#: m between the static surface points near the robot (the planner's HIT_CELL: one sensed point
#: per cell) and the slack beyond its reaches within which they are given.
SPACING = 0.01
NEAR_SLACK = 0.5
#: ways remembered per process (first ways from the start, per scenario and clearance).
KEPT = 16
_WAYS: OrderedDict[Any, tuple[Array, str | None]] = OrderedDict()


def _surface_near(static: ObstacleSet, p: Array, reach: float, spacing: float) -> Array:
    """The static surfaces within the box of half-width ``reach`` around p, as points at most
    ``spacing`` apart: each edge sampled as :func:`swarmpath.planners.sensed_map.surface_points`
    samples it (the same points every decision), only the samples inside the box."""
    parts: list[Array] = [np.zeros((0, 2))]
    lo, hi = p - reach, p + reach
    for cx, cy, r in static.circles:
        if cx + r < lo[0] or cx - r > hi[0] or cy + r < lo[1] or cy - r > hi[1]:
            continue
        n = max(8, math.ceil(2 * math.pi * r / spacing))
        a = np.arange(n) * (2 * math.pi / n)
        pts = np.stack([cx + r * np.cos(a), cy + r * np.sin(a)], axis=1)
        parts.append(pts[np.all((pts >= lo) & (pts <= hi), axis=1)])
    if static.polygons:
        index = fast.index_of(static)
        near = np.flatnonzero(np.all(index.bb_lo <= hi, axis=1)
                              & np.all(index.bb_hi >= lo, axis=1))
        if len(near):
            starts, counts = index.starts[near], index.counts[near]
            edge = np.repeat(starts - np.cumsum(counts) + counts, counts) + np.arange(
                int(counts.sum()))  # the near polygons' vertex indices, polygon by polygon
            first = np.repeat(starts, counts)
            last = np.repeat(starts + counts - 1, counts)
            a = index.verts[edge]
            b = index.verts[np.where(edge == last, first, edge + 1)]
            keep = ((np.maximum(a, b) >= lo) & (np.minimum(a, b) <= hi)).all(axis=1)
            a, b = a[keep], b[keep]
            n = np.maximum(1, np.ceil(np.hypot(*(b - a).T) / spacing)).astype(np.int64)
            k = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
            s = (k / np.repeat(n, n))[:, None]
            pts = np.repeat(a, n, axis=0) + s * (np.repeat(b, n, axis=0) - np.repeat(a, n, axis=0))
            parts.append(pts[np.all((pts >= lo) & (pts <= hi), axis=1)])
    return np.concatenate(parts)


def taut(cells: Array, static: ObstacleSet, margin: float) -> Array:
    """A polyline through ``cells`` with every vertex dropped whose neighbours see each other
    keeping more than ``margin`` from the static map (greedy from the start)."""
    out = [cells[0]]
    i = 0
    while i < len(cells) - 1:
        j = i + 1
        while (j + 1 < len(cells)
               and fast.segment_clearance(static, cells[i], cells[j + 1]) > margin):
            j += 1
        out.append(cells[j])
        i = j
    return np.asarray(out)


def descend(field: CostToGo, p: Array, goal: Array) -> Array | None:
    """The way down the cost-to-go from p to the goal: cell centres of strictly decreasing value,
    then the goal (None when p has no finite value)."""
    spec = field.spec
    rows, cols = spec.shape
    flat, off = field._neighbours(p[None, :])
    value = field.field.reshape(-1)[flat[0]] + off[0]
    if not np.isfinite(value).any():
        return None
    k = int(flat[0][int(np.argmin(value))])
    r, c = divmod(k, cols)
    cells = [p, spec.cell_to_world(np.array([[r, c]]))[0]]
    steps = [(a, b) for a in (-1, 0, 1) for b in (-1, 0, 1) if a or b]
    here = field.field[r, c]
    while True:
        best, at = here, None
        for a, b in steps:
            rr, cc = r + a, c + b
            if 0 <= rr < rows and 0 <= cc < cols and field.field[rr, cc] < best:
                best, at = field.field[rr, cc], (rr, cc)
        if at is None:  # a seed cell of the goal: no neighbour is lower
            break
        r, c = at
        here = best
        cells.append(spec.cell_to_world(np.array([[r, c]]))[0])
    cells.append(goal)
    return np.asarray(cells, dtype=float)


class Way:
    """A way to the goal and the robot's place on it, followed as the module docstring says
    ("Following"); subclasses say how a way is planned (:meth:`_plan`)."""

    def __init__(self, rejoin: float, backend: str) -> None:
        self.rejoin = float(rejoin)
        self.backend = backend
        self.way: Array | None = None
        self.at = 0  # index of the way's segment the robot is on
        self.plans = 0  # ways planned (for tests and traces)

    def _plan(self, p: Array, goal: Array) -> Array:
        """The way from p to the goal."""
        raise NotImplementedError

    def _first(self, p: Array, goal: Array) -> Array:
        """The first way, from the start."""
        return self._plan(p, goal)

    def ahead(self, p: Array, goal: Array, lookahead: float) -> Array:
        """The rest of the way from the robot at p: p, then the way from its place on it."""
        way = self.way
        if way is None:
            way = self._first(p, goal) if self.plans == 0 else self._plan(p, goal)
            self.way, self.at = way, 0
        elif math.dist(way[-1], goal) > GOAL_MOVED:
            way = self.way = self._plan(p, goal)
            self.at = 0
        place, seg, off = self._place(p, lookahead)
        if off > self.rejoin:
            way = self.way = self._plan(p, goal)
            self.at = 0
            place, seg, off = self._place(p, lookahead)
        self.at = seg
        return np.vstack([p[None, :], place[None, :], way[seg + 1:]])

    def _place(self, p: Array, lookahead: float) -> tuple[Array, int, float]:
        """The nearest point of the way to p on the segments from the robot's place up to
        SEARCH_AHEAD lookaheads ahead: (point, its segment, its distance)."""
        way = self.way
        assert way is not None
        a, b = way[self.at:-1], way[self.at + 1:]
        if not len(a):
            return way[-1], len(way) - 2 if len(way) > 1 else 0, math.dist(p, way[-1])
        length = np.concatenate([[0.0], np.cumsum(np.hypot(*(b - a).T))])
        keep = max(1, int(np.searchsorted(length, SEARCH_AHEAD * lookahead)) + 1)
        foot, dist = sensed_map.feet(a[:keep], b[:keep], p)
        k = int(np.argmin(dist))
        return foot[k], self.at + k, float(dist[k])

    def aim(self, p: Array, goal: Array, hits: Array, margin: float, lookahead: float,
            kind: str) -> Array:
        """What f1 aims at (``aim``): the shortcut point of the rest of the way (the farthest
        point within ``lookahead`` reachable in a straight line keeping ``margin`` from the
        ``hits``), or the carrot ``lookahead`` along it."""
        way = self.ahead(p, goal, lookahead)
        if kind == "carrot":
            return sensed_map.along(way, lookahead)
        return sensed_map.shortcut(way, hits, margin, lookahead, backend=self.backend)


class Guide(Way):
    """The way to the goal on the static map and the robot's place on it (module docstring)."""

    def __init__(self, scenario: Any, static: ObstacleSet, radius: float, clearance: float,
                 source: str, rejoin: float, budget: float | None, backend: str) -> None:
        super().__init__(rejoin, backend)
        self.scenario = scenario
        self.static = static
        self.radius = float(radius)
        w, h = scenario.size
        self.world = (0.0, 0.0, float(w), float(h))
        ends = np.array([scenario.start, scenario.goal], dtype=float)
        room = fast.point_clearances(static, ends) - self.radius if not static.is_empty else [
            np.inf]
        # keep the clearance, unless the start or goal is closer than that to an obstacle
        self.clearance = float(min(clearance, 0.5 * float(np.min(room))))
        self.source = source
        self.budget = budget
        self.planned_by: str | None = None  # "optimum" or "cost-to-go", the last way's source

    # ------------------------------------------------------------------------------ the way
    def _plan(self, p: Array, goal: Array) -> Array:
        """The way from p to the goal (module docstring); the straight line when none exists."""
        self.plans += 1
        margin = self.radius + self.clearance
        if not self.static.is_empty:
            room = float(fast.point_clearances(self.static, p[None, :])[0])
            margin = min(margin, room - 1e-6)  # a robot pushed closer plans with what it has
        if self.source == "optimum" and margin > 0:
            try:
                best = shortest_path(p, goal, self.static, margin, world=self.world,
                                     budget=self.budget, backend=self.backend)
            except ValueError:
                best = None
            if best is not None and best.exact and math.isfinite(best.length):
                self.planned_by = "optimum"
                return np.asarray(best.points, dtype=float)
        field = CostToGo(self.static, self.scenario.size, goal, max(margin, 0.0))
        cells = descend(field, p, goal)
        self.planned_by = "cost-to-go"
        if cells is None:
            return np.array([p, goal], dtype=float)
        return taut(cells, self.static, max(margin, 0.0))

    def _first(self, p: Array, goal: Array) -> Array:
        """The way from the start, remembered per scenario, clearance and source."""
        key = (self.scenario, self.clearance, self.source, self.budget, tuple(p), tuple(goal))
        if key in _WAYS:
            _WAYS.move_to_end(key)
            self.plans += 1
            way, self.planned_by = _WAYS[key]
            return way
        way = self._plan(p, goal)
        _WAYS[key] = (way, self.planned_by)
        while len(_WAYS) > KEPT:
            _WAYS.popitem(last=False)
        return way

    def near(self, p: Array, reach: float) -> Array:
        """The static surfaces within ``reach`` (+ :data:`NEAR_SLACK`) of p, as points
        :data:`SPACING` apart (module docstring)."""
        return _surface_near(self.static, p, reach + NEAR_SLACK, SPACING)
