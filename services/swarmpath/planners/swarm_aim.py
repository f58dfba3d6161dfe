"""The aim of the swarm local planner: what f1 and f2 measure against (step 2).

:class:`SwarmAim` is a base of :class:`~swarmpath.planners.swarm_local.SwarmLocalPlanner` (its
module docstring describes ``heuristic``, ``aim`` and the known path); the planner's
``__init__`` sets the state declared below.
"""

from __future__ import annotations

import math

import numpy as np

from swarmpath.planners import local, sensed_map
from swarmpath.planners.swarm_sensing import Array, SwarmSensing
from swarmpath.world.geometry import ObstacleSet


def _line_clearance(p: Array, goal: Array, hits: Array, backend: str) -> float:
    """Distance from the segment p -> goal to its nearest hit (``local.segment_hit_distance``;
    ``backend = "numba"``: :func:`swarmpath.planners.compiled_aim.line_clearance_kernel`)."""
    if backend == "numba":
        from swarmpath.planners.compiled_aim import line_clearance_kernel

        return float(line_clearance_kernel(float(p[0]), float(p[1]), float(goal[0]),
                                           float(goal[1]), np.ascontiguousarray(hits, dtype=float)))
    return float(local.segment_hit_distance(p, goal[None, :], hits)[0][0])


def nearest_hit(p: Array, hits: Array, backend: str) -> float:
    """Distance from p to its nearest hit (``local.point_hit_distance``; ``backend = "numba"``:
    :func:`swarmpath.planners.compiled._point_nearest`, the same)."""
    if backend == "numba":
        from swarmpath.planners.compiled import _point_nearest

        return math.sqrt(_point_nearest(float(p[0]), float(p[1]),
                                        np.ascontiguousarray(hits, dtype=float))[0])
    return float(local.point_hit_distance(p[None, :], hits)[0][0])


def clear(x: Array, ctx: local.StepContext) -> bool:
    """Whether the move to x keeps the margin (``local.violation`` is 0; ``backend = "numba"``:
    its distances by :func:`swarmpath.planners.compiled.distances_kernel`, the same)."""
    if ctx.backend == "numba" and len(ctx.hits):
        from swarmpath.planners.compiled import distances_kernel

        f = np.ascontiguousarray
        d_pt, _, d_seg, _ = distances_kernel(f(x, dtype=float).reshape(1, 2),
                                             np.asarray(ctx.position, dtype=float),
                                             f(ctx.hits, dtype=float))
        return bool(max(ctx.margin - min(d_pt[0], d_seg[0]), 0.0) == 0)
    return bool(local.violation(x[None, :], ctx)[0] == 0)


def _room(p: Array, known: ObstacleSet, backend: str) -> float:
    """Signed clearance of p in the known map (``ObstacleSet.point_clearance``; ``backend =
    "numba"``: :func:`swarmpath.planners.compiled_aim.point_clearance_kernel`)."""
    if backend == "numba":
        from swarmpath.planners.compiled_aim import point_clearance_kernel

        polys = known.polygons
        verts = np.concatenate(polys) if polys else np.zeros((0, 2))
        counts = np.array([len(q) for q in polys], dtype=np.int64)
        return float(point_clearance_kernel(float(p[0]), float(p[1]), known.circles, verts,
                                            counts))
    return float(known.point_clearance(p[None, :])[0])


def free_space_path(p: Array, goal: Array, points: Array, clearance: float,
                    world: tuple[float, float, float, float], backend: str) -> Array | None:
    """The way to the goal on a grid of the sensed points themselves, unseen space free (the
    free-space assumption of planning in unknown terrain: Koenig, Tovey & Smirnov, Artificial
    Intelligence 147, 2003), for when the hulls leave no path: a concave pocket's faces make a
    hull that covers the robot (MFB on random-32-32-20 oscillated there, aiming at the straight
    line). The cost-to-go (:class:`~swarmpath.planners.cost_to_go.CostToGo`) of cells keeping
    ``clearance`` (less when the robot is closer) from every point, descended from the robot and
    pulled taut (:mod:`swarmpath.planners.swarm_guide`); None when no cell near the robot has a
    way to the goal."""
    from swarmpath.planners.cost_to_go import CostToGo
    from swarmpath.planners.swarm_guide import descend, taut

    if not len(points):
        return None
    c = min(clearance, nearest_hit(p, points, backend) - 1e-6)
    if c <= 0:
        return None
    dots = ObstacleSet(circles=np.column_stack([points, np.zeros(len(points))]))
    cells = descend(CostToGo(dots, (world[2], world[3]), goal, c), p, goal)
    return None if cells is None else taut(cells, dots, c)


def load_kernels() -> None:
    """Compile, or load from numba's cache, the sensing's and the aim's kernels (one call each
    on a tiny problem), so that no decision pays for it."""
    from swarmpath.world.optimum import shortest_path

    hit = np.array([[1.0, 0.0]])
    path = np.array([[0.0, 0.0], [2.0, 0.0]])
    sensed_map.shortcut(path, hit, 0.5, 1.0, backend="numba")
    sensed_map.path_clearance(path, hit, 1.0, "numba")
    scan = np.array([[1.0, 0.0], [1.0, 0.1], [1.0, 0.2]])
    sensed_map.motion(scan, scan + 0.01, 0.1, surface=0.2, backend="numba")
    sensed_map.condense(scan, np.zeros(2), 2.0, 0.1, "numba")
    sensed_map.has_corner(scan, 0.2, 30.0, "numba")
    sensed_map.rejoin(path, np.zeros(2), 0.1, "numba")
    square = sensed_map.known_obstacles(np.array([[1.0, -0.1], [1.1, -0.1], [1.1, 0.1],
                                                  [1.0, 0.1]]), 0.25, backend="numba")
    # (not sensed_map.known_path: scripts/bench/sensed_path_time.py records its calls)
    shortest_path(np.zeros(2), path[1], square, 0.05, (-1, -1, 3, 1), backend="numba")
    _room(np.zeros(2), square, "numba")
    _line_clearance(np.zeros(2), path[1], scan, "numba")
    nearest_hit(np.zeros(2), scan, "numba")
    clear(path[1], local.StepContext(position=np.zeros(2), goal=path[1], hits=scan, margin=0.1,
                                     backend="numba"))


class SwarmAim(SwarmSensing):
    """The point f1 aims at: the goal, or a point of the shortest path in the sensed map."""

    _path: Array | None


    def _aim(self, p: Array, goal: Array, hits: Array, margin: float,
             world: tuple[float, float, float, float], known: Array | None = None) -> Array:
        """What f1 and f2 measure against (module docstring, step 2): ``known`` are the points
        the known path avoids (default ``hits``), ``hits`` the nearby ones the shortcut must keep
        ``margin`` from."""
        if self.p["heuristic"] == "euclidean":
            return goal
        if known is None:
            known = hits
        lookahead = float(self.p["lookahead"])
        clearance = margin + float(self.p["carrot_clearance"])
        path = np.array([p, goal])
        # Nothing known near the straight line to the goal: that line is the known shortest path
        # (the convex hulls are not needed to see it).
        if len(known) and _line_clearance(p, goal, known, str(self.p["backend"])) < clearance:
            path = self._known_path(p, goal, known, margin, clearance, world)
        if self.p["aim"] == "carrot":
            return sensed_map.along(path, lookahead)
        return sensed_map.shortcut(path, hits, margin, lookahead,
                                   backend=str(self.p["backend"]))

    def _known_path(self, p: Array, goal: Array, hits: Array, margin: float, clearance: float,
                    world: tuple[float, float, float, float]) -> Array:
        """Shortest path to the goal in the sensed map (straight line if there is none).

        Planned again only when needed: while the robot is within ``rejoin`` of the last known
        path, the goal has not moved, and that path still keeps ``margin`` from every sensed
        point within the sensing reach, the rest of it is still the shortest known path (static
        obstacles only add to the known map), so it is reused.
        """
        cached = self._path
        backend = str(self.p["backend"])
        if cached is not None and np.allclose(cached[-1], goal):
            rest = sensed_map.rejoin(cached, p, float(self.p["rejoin"]), backend)
            reach = 2 * (float(self.p["step"]) + 2 * margin)
            if rest is not None and sensed_map.path_clearance(
                    rest, hits, reach, backend) >= margin:
                return rest
        coarse = sensed_map.condense(hits, p, np.inf, float(self.p["map_cell"]), backend)
        known = sensed_map.known_obstacles(coarse, link=2 * margin, backend=backend)
        # The hulls grow as more of an obstacle is seen, so the robot may already be closer to
        # one than ``clearance``: plan with what it has (the candidates still need margin).
        room = _room(p, known, backend)
        path = sensed_map.known_path(p, goal, known, min(clearance, room - 1e-6), world,
                                     backend)
        if path is None and self.p["no_path"] == "grid":
            path = free_space_path(p, goal, coarse, clearance, world, backend)
        if path is None:
            self._path = None
            return np.array([p, goal])
        self._path = path if float(self.p["rejoin"]) > 0 else None
        return path
