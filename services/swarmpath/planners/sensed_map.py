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
from collections.abc import Sequence
from types import ModuleType

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import ConvexHull, QhullError, cKDTree

from swarmpath.world.geometry import ObstacleSet, point_segment_distance
from swarmpath.world.optimum import shortest_path

Array = NDArray[np.float64]


def condense(hits: Array, position: Array, reach: float, cell: float,
             backend: str = "numpy") -> Array:
    """Hits within ``reach`` of ``position``, at most one per ``cell``-sized grid cell (``backend
    = "numba"``: :func:`swarmpath.planners.compiled_aim.condense_kernel`, the same points)."""
    if len(hits) == 0:
        return hits.reshape(0, 2)
    if backend == "numba":
        return _fast().condense(hits, position, reach, cell)
    d = np.hypot(hits[:, 0] - position[0], hits[:, 1] - position[1])
    near = hits[d <= reach]
    if len(near) == 0:
        return near
    keys = np.floor(near / cell).astype(np.int64)
    # one integer per cell (row-major over the cells spanned): unique on it finds the same
    # first hits as on the pairs, several times faster
    keys -= keys.min(axis=0)
    rows, cols = int(keys[:, 0].max()) + 1, int(keys[:, 1].max()) + 1
    if rows * cols < 2**62:
        _, first = np.unique(keys[:, 0] * cols + keys[:, 1], return_index=True)
    else:  # pragma: no cover - a span of over 2e9 cells per axis
        _, first = np.unique(keys, axis=0, return_index=True)
    return near[np.sort(first)]


def _fast() -> ModuleType:
    """:mod:`swarmpath.planners.compiled_aim` (numba), imported by the first ``backend =
    "numba"`` call: its functions give this module's numbers (its docstring says how)."""
    from swarmpath.planners import compiled_aim

    return compiled_aim


def surface_points(obstacles: ObstacleSet, spacing: float) -> Array:
    """Points on every obstacle surface, at most ``spacing`` apart along it (a known map seen
    as sensor hits): polygon vertices and edge points, and points around each circle."""
    parts = [np.zeros((0, 2))]
    for cx, cy, r in obstacles.circles:
        n = max(8, math.ceil(2 * math.pi * r / spacing))
        a = np.arange(n) * (2 * math.pi / n)
        parts.append(np.stack([cx + r * np.cos(a), cy + r * np.sin(a)], axis=1))
    for poly in obstacles.polygons:
        ends = np.roll(poly, -1, axis=0)
        for a, b in zip(poly, ends, strict=True):
            n = max(1, math.ceil(math.dist(a, b) / spacing))
            s = np.arange(n)[:, None] / n
            parts.append(a + s * (b - a))
    return np.concatenate(parts)


def _to_surface(points: Array, scan: Array, surface: float,
                backend: str = "numpy") -> tuple[Array, Array]:
    """Distance from each point to the sensed surface of ``scan`` and the nearest point of it.

    The surface is the polyline through consecutive hits of the scan (adjacent rays, in the
    sensor's order) closer than ``surface``, plus every hit as a point.
    """
    dist, idx = _nearest(scan, points, backend)
    return _to_surface_from(points, scan, surface, dist, idx, backend)[:2]


def _nearest(ref: Array, points: Array, backend: str) -> tuple[Array, NDArray[np.intp]]:
    """``cKDTree(ref).query(points)`` (``backend = "numba"``: the same by brute force,
    :func:`swarmpath.planners.compiled_aim.nearest_kernel`)."""
    if backend == "numba":
        return _fast().nearest(ref, points)
    return cKDTree(ref).query(points)


def _to_surface_from(points: Array, scan: Array, surface: float, dist: Array,
                     idx: NDArray[np.intp], backend: str = "numpy") -> tuple[
                         Array, Array, NDArray[np.intp]]:
    """:func:`_to_surface` given the nearest hit of ``scan`` to each point (distance and index,
    as ``cKDTree(scan).query(points)`` returns them), which it also returns. ``backend =
    "numba"``: :func:`swarmpath.planners.compiled.surface_kernel` (the same numbers)."""
    nearest = scan[idx]
    if backend == "numba":
        return (*_fast().surface(points, scan, surface, dist, nearest), idx)
    a, b = scan[:-1], scan[1:]
    gap = np.hypot(*(b - a).T)
    joined = (gap < surface) & (gap > 1e-9)
    a, b = a[joined], b[joined]
    if len(a) == 0:
        return dist, nearest, idx
    u = b - a
    t = np.clip(np.einsum("ij,kij->ki", u, points[:, None, :] - a[None])
                / np.einsum("ij,ij->i", u, u), 0.0, 1.0)
    foot = a[None] + t[..., None] * u[None]  # (n_points, n_segments, 2)
    d = np.hypot(*np.moveaxis(points[:, None, :] - foot, -1, 0))
    k = np.argmin(d, axis=1)
    rows = np.arange(len(points))
    closer = d[rows, k] < dist
    return (np.where(closer, d[rows, k], dist),
            np.where(closer[:, None], foot[rows, k], nearest), idx)


def motion(
    previous: Array, current: Array, dt: float,
    max_speed: float = 2.0, min_speed: float = 0.05, surface: float = 0.0,
    backend: str = "numpy",
) -> tuple[NDArray[np.bool_], Array]:
    """Which points of ``current`` moved since ``previous`` (``dt`` seconds earlier), and their
    measured velocities (n, 2) (rule: :func:`predict`; ``backend`` as in
    :func:`_to_surface_from`)."""
    none = (np.zeros(len(current), dtype=bool), np.zeros((len(current), 2)))
    if len(previous) == 0 or len(current) == 0 or dt <= 0:
        return none
    if surface > 0 and backend == "numba":
        return _fast().motion(previous, current, dt, max_speed, min_speed, surface)
    if surface > 0:
        # the nearest previous hit of each current one serves both the surface distance and
        # the check back (one k-d tree query)
        d0, i0 = _nearest(previous, current, backend)
        dist, nearest, idx = _to_surface_from(current, previous, surface, d0, i0, backend)
        back, _ = _to_surface(previous, current, surface, backend)
        dist = np.where(back[idx] >= min_speed * dt, dist, 0.0)
    else:
        dist, idx = cKDTree(previous).query(current)
        nearest = previous[idx]
    velocity = (current - nearest) / dt
    speed = dist / dt
    moving = (speed >= min_speed) & (speed <= max_speed)
    return moving, velocity


def predict(
    previous: Array, current: Array, dt: float, horizons: tuple[float, ...],
    max_speed: float = 2.0, min_speed: float = 0.05, surface: float = 0.0,
) -> Array:
    """Predicted positions of the moving points of ``current`` after each horizon (s).

    ``surface = 0``: each point moves by its displacement from the nearest point of the previous
    scan. ``surface > 0``: each scan's consecutive hits closer than ``surface`` are joined into
    a polyline, the sensed surface (:func:`_to_surface`); a point moves by its displacement from
    the previous surface, and only if the previous scan's nearest hit is as far from the current
    surface (the surface moved, both ways). A static surface then does not move however its hits
    slide along it as the robot drives. With the point rule, a hit that landed between two
    previous hits (5 cm apart on an obstacle 1 m away) "moves" at 0.1-0.2 m/s, above
    ``min_speed``, and its extrapolation puts phantom points in front of a convex obstacle; a
    surface seen further than before, or a polygon corner cut by the previous polyline, would
    move one way only.
    """
    moving, velocity = motion(previous, current, dt, max_speed, min_speed, surface)
    return extrapolate(current[moving], velocity[moving], horizons)


def extrapolate(points: Array, velocity: Array, horizons: Sequence[float]) -> Array:
    """``points`` moved at ``velocity`` for each horizon (s), horizon after horizon."""
    if len(points) == 0:
        return np.zeros((0, 2))
    return np.concatenate([points + velocity * h for h in horizons])


def group_velocity(points: Array, velocity: Array, link: float, max_speed: float = 2.0,
                   conditioning: float = 0.1) -> Array:
    """Whole-obstacle velocities of moving points from their measured surface motion.

    :func:`motion` measures each point's displacement from the previous surface: the component
    of the obstacle's velocity along the surface normal n_i only (a circle crossing the robot's
    way at 0.3 m/s showed 0.12 m/s). Points closer than ``link`` are one rigid obstacle moving by
    one velocity V with n_i . V = s_i (s_i the measured normal speed, n_i its direction); the
    least-squares V is taken when the normals span enough directions (the smaller eigenvalue of
    the mean n n^T at least ``conditioning``), else the points keep their measured velocities.
    """
    out = velocity.copy()
    if len(points) < 2:
        return out
    pairs = cKDTree(points).query_pairs(link, output_type="ndarray")
    n_pts = len(points)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n_pts, n_pts))
    count, labels = connected_components(graph, directed=False)
    speed = np.hypot(*velocity.T)
    for k in range(count):
        idx = np.flatnonzero(labels == k)
        if len(idx) < 2:
            continue
        s = speed[idx]
        n = velocity[idx] / np.where(s > 1e-12, s, 1.0)[:, None]
        A = n.T @ n / len(idx)
        if float(np.linalg.eigvalsh(A)[0]) < conditioning:
            continue
        V = np.linalg.solve(A, n.T @ s / len(idx))
        norm = float(np.hypot(*V))
        if norm > max_speed:
            V = V * (max_speed / norm)
        out[idx] = V
    return out


def has_corner(scan: Array, surface: float, angle_deg: float, backend: str = "numpy") -> bool:
    """Whether the sensed surface of one scan (consecutive hits closer than ``surface`` joined)
    turns by more than ``angle_deg`` between two successive pieces: a corner, whose tip may lie
    between two rays and stick out of the sensed points by centimetres (on a circle the
    polyline turns by ~10 degrees per piece and stays within millimetres of the surface)."""
    if len(scan) < 3:
        return False
    if backend == "numba":
        return _fast().has_corner(scan, surface, angle_deg)
    d = np.diff(scan, axis=0)
    n = np.hypot(*d.T)
    ok = (n < surface) & (n > 1e-9)
    both = ok[:-1] & ok[1:]
    if not both.any():
        return False
    a, b = d[:-1][both], d[1:][both]
    cos = np.einsum("ij,ij->i", a, b) / (n[:-1][both] * n[1:][both])
    return bool(np.any(cos < math.cos(math.radians(angle_deg))))


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


def known_obstacles(hits: Array, link: float, thickness: float = 1e-3,
                    backend: str = "numpy") -> ObstacleSet:
    """Hit groups (linked when closer than ``link``) as convex hulls and point circles
    (``backend = "numba"``: the groups by :func:`swarmpath.planners.compiled_aim.groups_kernel`,
    the same)."""
    if len(hits) == 0:
        return ObstacleSet.empty()
    if backend == "numba" and len(hits) <= 1000:  # all pairs compiled: O(n^2), same groups
        count, labels = _fast().groups(hits, link)
    else:
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


def known_path(
    position: Array,
    goal: Array,
    known: ObstacleSet,
    margin: float,
    world: tuple[float, float, float, float],
    backend: str = "numpy",
) -> Array | None:
    """The shortest path (polyline, arcs sampled) to the goal in the known map; None if there is
    none (the robot or the goal inside a known inflated obstacle, or no path in the known map;
    ``backend`` as in :func:`swarmpath.world.optimum.shortest_path`)."""
    if known.is_empty:
        return np.array([position, goal], dtype=float)
    try:
        best = shortest_path(position, goal, known, margin, world=world, backend=backend)
    except ValueError:
        return None
    if not best.exact or not math.isfinite(best.length) or len(best.points) < 2:
        return None
    return np.asarray(best.points, dtype=float)


def along(pts: Array, distance: float | Array) -> Array:
    """The point(s) ``distance`` along the polyline ``pts`` (its end beyond its length)."""
    seg = np.hypot(*np.diff(pts, axis=0).T)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    s = np.clip(np.asarray(distance, dtype=float), 0.0, cum[-1])
    return np.stack([np.interp(s, cum, pts[:, 0]), np.interp(s, cum, pts[:, 1])], axis=-1)


def feet(a: Array, b: Array, position: Array) -> tuple[Array, Array]:
    """The nearest point of each segment a -> b (m, 2) to ``position`` and its distance."""
    u = b - a
    uu = np.einsum("ij,ij->i", u, u)
    t = np.clip(np.einsum("ij,ij->i", position - a, u) / np.where(uu > 0, uu, 1.0), 0.0, 1.0)
    foot = a + t[:, None] * u
    return foot, np.hypot(*(position - foot).T)


def rejoin(pts: Array, position: Array, tolerance: float,
           backend: str = "numpy") -> Array | None:
    """The rest of the polyline ``pts`` from the robot, starting at ``position``, when the robot
    is within ``tolerance`` of it (None otherwise; ``backend = "numba"``:
    :func:`swarmpath.planners.compiled_aim.rejoin_kernel`, the same)."""
    if backend == "numba":
        return _fast().rejoin(pts, position, tolerance)
    _, d = feet(pts[:-1], pts[1:], position)
    k = int(np.argmin(d))
    if d[k] > tolerance:
        return None
    return np.vstack([position[None, :], pts[k + 1:]])


def _segments_clearance(points: Array, a: Array, b: Array) -> Array:
    """Least distance from ``points`` (h, 2) to each segment a -> b (m, 2), (m,)."""
    return np.asarray(point_segment_distance(points[None, :, :], a[:, None, :],
                                             b[:, None, :]).min(axis=1))


def path_clearance(pts: Array, hits: Array, reach: float, backend: str = "numpy") -> float:
    """Least distance from the hits to the part of the polyline ``pts`` within ``reach`` (along
    it) of its start."""
    if len(hits) == 0 or len(pts) < 2:
        return math.inf
    if backend == "numba":
        return _fast().path_clearance(pts, hits, reach)
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
    n = int(np.searchsorted(cum, reach, side="right")) + 1
    a, b = pts[: min(n, len(pts) - 1)], pts[1 : min(n, len(pts) - 1) + 1]
    return float(_segments_clearance(hits, a, b).min())


def shortcut(
    pts: Array, hits: Array, margin: float, lookahead: float, samples: int = 16,
    backend: str = "numpy",
) -> Array:
    """The farthest point within ``lookahead`` along the polyline ``pts`` (from the robot at
    ``pts[0]``) that the robot can reach in a straight line keeping ``margin`` from every hit.

    A known path bends around obstacles along arcs; aiming at a point past the bend would make
    the robot cut the corner, aiming at the next sample would make it crawl along the arc. The
    straight shortcut (checked against the raw sensed points, not the hulls) is the longest
    feasible chord of the path: the robot drives the path's tangents and cuts its arcs only as
    far as the clearance allows. The first sample (1/``samples`` of the lookahead) is returned
    when no sample is reachable (``backend = "numba"``:
    :func:`swarmpath.planners.compiled_aim.shortcut_kernel`, the same point).
    """
    if backend == "numba":
        return _fast().shortcut(pts, hits, margin, lookahead, samples)
    candidates = along(pts, lookahead * np.arange(1, samples + 1) / samples)
    if len(hits) == 0:
        return np.asarray(candidates[-1], dtype=float)
    start = np.broadcast_to(np.asarray(pts[0], dtype=float), candidates.shape)
    clear = _segments_clearance(hits, start, candidates)
    ok = np.flatnonzero(clear >= margin)
    return np.asarray(candidates[ok[-1] if ok.size else 0], dtype=float)


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
    pts = known_path(position, goal, known, margin, world)
    if pts is None:
        return None
    return along(pts, lookahead)
