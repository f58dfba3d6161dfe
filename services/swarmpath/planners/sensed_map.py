"""What a local planner knows of the world: the points its sensors hit, condensed into obstacles.

* :func:`condense` keeps the hits that can matter this step (within ``reach`` of the robot) and
  merges hits closer than ``cell`` (one per grid cell), so the cost of scoring candidates does not
  grow with how long obstacles have been remembered.
* :func:`known_obstacles` groups hits closer than ``link`` (a gap the robot cannot pass) and wraps
  each group in its convex hull: a polygon for three or more non-collinear hits, a thin
  rectangle for collinear ones, a point-circle for a single hit. Unseen space is assumed free
  (the free-space assumption of navigation in unknown terrain).
* :func:`predict` estimates how sensed points move between two scans (nearest-neighbour
  displacement: it captures the motion of a surface toward or away from the robot, the part that
  matters for avoidance, and is ~0 for static surfaces whose hits only slide along them) and
  returns where the moving ones will be a little later.
* :func:`carrot` plans the exact shortest path to the goal in that known map
  (:func:`swarmpath.world.optimum.shortest_path`) and returns the point ``lookahead`` metres along
  it: the local target the swarm steers to when ``heuristic = "visibility"``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import ConvexHull, QhullError, cKDTree

from swarmpath.world.geometry import ObstacleSet
from swarmpath.world.optimum import shortest_path

Array = NDArray[np.float64]


def condense(hits: Array, position: Array, reach: float, cell: float) -> Array:
    """Hits within ``reach`` of ``position``, at most one per ``cell``-sized grid cell."""
    if len(hits) == 0:
        return hits.reshape(0, 2)
    d = np.hypot(hits[:, 0] - position[0], hits[:, 1] - position[1])
    near = hits[d <= reach]
    if len(near) == 0:
        return near
    keys = np.floor(near / cell).astype(np.int64)
    _, first = np.unique(keys, axis=0, return_index=True)
    return near[np.sort(first)]


def predict(
    previous: Array, current: Array, dt: float, horizons: tuple[float, ...],
    max_speed: float = 2.0, min_speed: float = 0.05,
) -> Array:
    """Predicted positions of the moving points of ``current`` after each horizon (s)."""
    if len(previous) == 0 or len(current) == 0 or dt <= 0:
        return np.zeros((0, 2))
    dist, idx = cKDTree(previous).query(current)
    velocity = (current - previous[idx]) / dt
    speed = dist / dt
    moving = (speed >= min_speed) & (speed <= max_speed)
    if not moving.any():
        return np.zeros((0, 2))
    base, v = current[moving], velocity[moving]
    return np.concatenate([base + v * h for h in horizons])


def _hull(points: Array, thickness: float) -> Array | None:
    """Convex hull vertices of a hit group; None for a single point."""
    if len(points) == 1:
        return None
    try:
        if len(points) >= 3:
            hull = ConvexHull(points)
            return points[hull.vertices]
    except QhullError:
        pass  # collinear: fall through to a thin rectangle
    centre = points.mean(axis=0)
    axis_dir = points[np.argmax(np.hypot(*(points - centre).T))] - centre
    n = np.hypot(*axis_dir)
    u = axis_dir / n if n > 1e-12 else np.array([1.0, 0.0])
    proj = (points - centre) @ u
    a, b = centre + proj.min() * u, centre + proj.max() * u
    normal = np.array([-u[1], u[0]]) * thickness
    return np.array([a - normal, b - normal, b + normal, a + normal])


def known_obstacles(hits: Array, link: float, thickness: float = 1e-3) -> ObstacleSet:
    """Hit groups (linked when closer than ``link``) as convex hulls and point circles."""
    if len(hits) == 0:
        return ObstacleSet.empty()
    pairs = cKDTree(hits).query_pairs(link, output_type="ndarray")
    n = len(hits)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    count, labels = connected_components(graph, directed=False)
    circles, polygons = [], []
    for k in range(count):
        group = hits[labels == k]
        poly = _hull(group, thickness)
        if poly is None:
            circles.append([group[0, 0], group[0, 1], 0.0])
        else:
            polygons.append(poly)
    return ObstacleSet(np.array(circles, dtype=float).reshape(-1, 3), tuple(polygons))


def carrot(
    position: Array,
    goal: Array,
    known: ObstacleSet,
    margin: float,
    world: tuple[float, float, float, float],
    lookahead: float,
) -> Array | None:
    """The point ``lookahead`` along the shortest known path to the goal (None if unavailable:
    the robot or the goal inside a known inflated obstacle, or no path in the known map)."""
    if known.is_empty:
        return None
    try:
        best = shortest_path(position, goal, known, margin, world=world)
    except ValueError:
        return None
    if not best.exact or not math.isfinite(best.length) or len(best.points) < 2:
        return None
    pts = best.points
    seg = np.hypot(*np.diff(pts, axis=0).T)
    along = np.concatenate([[0.0], np.cumsum(seg)])
    if along[-1] <= lookahead:
        return np.asarray(pts[-1], dtype=float)
    k = int(np.searchsorted(along, lookahead, side="right")) - 1
    frac = (lookahead - along[k]) / max(seg[k], 1e-12)
    return np.asarray(pts[k] + frac * (pts[k + 1] - pts[k]), dtype=float)
