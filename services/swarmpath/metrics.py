"""Per-run metrics of an executed trajectory (pure functions, numpy only).

A trajectory is an (n, 3) array of rows [x, y, t] (metres, seconds) with t non-decreasing; the
geometric metrics also accept (n, 2) rows [x, y]. The robot moves in a straight line at constant
velocity between consecutive rows (a "step").

Definitions (p_i = (x_i, y_i), s_i = p_{i+1} - p_i):

* path_length = sum_i |s_i|.
* heading_smoothness = sum over consecutive non-degenerate steps (|s| > 1e-9 m) of
  |wrap(heading_{i+1} - heading_i)|, wrapped to [-pi, pi); radians, 0 for a straight path, pi
  per reversal. Degenerate (zero-length) steps are skipped, so stopping does not count as turning.
* ompl_smoothness: OMPL's ``PathGeometric::smoothness()`` (src/ompl/geometric/src/
  PathGeometric.cpp), on the positions: for each vertex with incoming length a, outgoing length b
  and chord c between its neighbours, cos = (a^2 + b^2 - c^2) / (2ab); if -1 < cos < 1 it adds
  (2 (pi - acos(cos)) / (a + b))^2. As in OMPL, vertices with a zero-length neighbour step or an
  exact 0 / 180 degree turn add nothing (so an exact reversal adds 0, unlike heading_smoothness).
* final_error = |p_last - goal|.
* gap = length / optimum - 1 (nan when the optimum is not a positive finite number).
* min_clearance: see :func:`min_clearance`; collisions follow the product rule of
  swarmpath.world.geometry: the body touches an obstacle when clearance <= radius.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmpath.world import clearance
from swarmpath.world.geometry import (
    ObstacleSet,
    collides,
    point_segment_distance,
    segment_polygon_distance,
)

Array = NDArray[np.float64]

__all__ = [
    "ClearanceResult",
    "ContactCauses",
    "contact_causes",
    "final_error",
    "gap",
    "heading_smoothness",
    "min_clearance",
    "ompl_smoothness",
    "path_length",
    "step_clearances",
]

DEGENERATE_STEP = 1e-9  # m: shorter steps have no heading
_SHAPE_TOL = 1e-9  # m: allowed drift of an obstacle's shape between snapshots


def _xy(path: ArrayLike) -> Array:
    P = np.asarray(path, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] < 2:
        raise ValueError(f"path must be an (n, 2) or (n, 3) array, got shape {P.shape}")
    return P[:, :2]


def path_length(path: ArrayLike) -> float:
    """Sum of the step lengths (0 for fewer than two rows)."""
    P = _xy(path)
    return float(np.sum(np.hypot(*np.diff(P, axis=0).T))) if len(P) > 1 else 0.0


def heading_smoothness(path: ArrayLike) -> float:
    """Sum of absolute heading changes between consecutive non-degenerate steps (radians)."""
    d = np.diff(_xy(path), axis=0)
    d = d[np.hypot(d[:, 0], d[:, 1]) > DEGENERATE_STEP]
    if len(d) < 2:
        return 0.0
    h = np.arctan2(d[:, 1], d[:, 0])
    turn = np.diff(h)
    turn = np.mod(turn + math.pi, 2 * math.pi) - math.pi  # [-pi, pi)
    return float(np.sum(np.abs(turn)))


def ompl_smoothness(path: ArrayLike) -> float:
    """OMPL's PathGeometric::smoothness() on the positions (see the module docstring)."""
    P = _xy(path)
    if len(P) < 3:
        return 0.0
    a = np.hypot(*(P[1:-1] - P[:-2]).T)
    b = np.hypot(*(P[2:] - P[1:-1]).T)
    c = np.hypot(*(P[2:] - P[:-2]).T)
    with np.errstate(divide="ignore", invalid="ignore"):
        cos = (a * a + b * b - c * c) / (2.0 * a * b)
        ok = (cos > -1.0) & (cos < 1.0)  # NaN / inf (zero-length steps) fail both
        k = 2.0 * (math.pi - np.arccos(np.where(ok, cos, 0.0))) / (a + b)
    return float(np.sum(np.where(ok, k * k, 0.0)))


def final_error(path: ArrayLike, goal: ArrayLike) -> float:
    """Distance from the last position to the goal."""
    P = _xy(path)
    g = np.asarray(goal, dtype=np.float64).reshape(2)
    return float(np.hypot(*(P[-1] - g)))


#: Relative gaps below this in magnitude are round-off, reported as 0: a path summed segment by
#: segment along the optimum may come out a few ulps shorter than the optimum itself, which
#: printed "Gap -0.00 %". A larger negative gap is kept: it would be a bug to see, not to hide.
GAP_ROUNDOFF = 1e-9


def gap(length: float, optimum: float) -> float:
    """Relative excess over the optimum, length / optimum - 1 (nan if the optimum is unusable;
    0 within :data:`GAP_ROUNDOFF`)."""
    if not (math.isfinite(optimum) and optimum > 0.0) or math.isnan(length):
        return math.nan
    g = length / optimum - 1.0
    return 0.0 if abs(g) < GAP_ROUNDOFF else g


class ClearanceResult(NamedTuple):
    """min_gap: smallest body gap (clearance - radius) over all steps, m (inf if no obstacles);
    collisions: number of steps whose gap is <= 0 (clearance <= radius, touching counts)."""

    min_gap: float
    collisions: int


def _snapshots(
    obstacles_at: Callable[[float], ObstacleSet] | ObstacleSet, times: Array
) -> list[ObstacleSet]:
    if isinstance(obstacles_at, ObstacleSet):
        return [obstacles_at] * len(times)
    return [obstacles_at(float(t)) for t in times]


def _obstacle_frames(
    path: ArrayLike, obstacles_at: Callable[[float], ObstacleSet] | ObstacleSet
) -> tuple[Array, ObstacleSet, Array | None]:
    """Trajectory rows (at least two), the obstacles at t_0 and each obstacle's offset from its
    t_0 pose at every row, shape (n, k + n_poly, 2) (circles first, then polygons); None when
    every snapshot is the t_0 one (a static world: all offsets 0)."""
    P = np.asarray(path, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != 3:
        raise ValueError(f"trajectory must be an (n, 3) array of [x, y, t], got {P.shape}")
    if len(P) == 0:
        raise ValueError("empty trajectory")
    if len(P) == 1:
        P = np.vstack([P, P])
    t = P[:, 2]
    if np.any(np.diff(t) < 0):
        raise ValueError("trajectory times must be non-decreasing")
    snaps = _snapshots(obstacles_at, t)
    ref = snaps[0]
    if all(s is ref for s in snaps):
        return P, ref, None
    k, n_poly = len(ref.circles), len(ref.polygons)
    for s in snaps:
        if len(s.circles) != k or len(s.polygons) != n_poly:
            raise ValueError("obstacles_at must return the same obstacles at every time")
    offsets = np.zeros((len(P), k + n_poly, 2))
    if k:
        circ = np.stack([s.circles for s in snaps])  # (n, k, 3)
        if np.any(np.abs(circ[:, :, 2] - ref.circles[:, 2]) > _SHAPE_TOL):
            raise ValueError("circle radii must not change over time")
        offsets[:, :k] = circ[:, :, :2] - ref.circles[:, :2]
    for j, shape in enumerate(ref.polygons):
        verts = np.stack([s.polygons[j] for s in snaps])  # (n, m, 2)
        if verts.shape[1:] != shape.shape:
            raise ValueError(f"polygon {j} changes its vertex count over time")
        offset = verts[:, 0, :] - shape[0]  # (n, 2)
        if np.any(np.abs(verts - offset[:, None, :] - shape) > _SHAPE_TOL):
            raise ValueError(f"polygon {j} changes shape over time (only translation allowed)")
        offsets[:, k + j] = offset
    return P, ref, offsets


def _clearance_columns(xy_a: Array, xy_b: Array, ref: ObstacleSet, off_a: Array | None,
                       off_b: Array | None) -> Iterator[Array]:
    """Clearance of the robot moving xy_a -> xy_b while each obstacle translates off_a -> off_b
    (None: no obstacle moves), one column per obstacle (circles, then polygons; exact, as in
    :func:`step_clearances`)."""
    k = len(ref.circles)
    if k:
        a = xy_a[:, None, :] - ref.circles[:, :2]
        b = xy_b[:, None, :] - ref.circles[:, :2]
        if off_a is not None and off_b is not None:
            a, b = a - off_a[:, :k], b - off_b[:, :k]
        circles = np.maximum(point_segment_distance(np.zeros(2), a, b) - ref.circles[:, 2], 0.0)
        yield from circles.T
    for j, shape in enumerate(ref.polygons):
        if off_a is None or off_b is None:
            yield segment_polygon_distance(xy_a, xy_b, shape)
        else:
            yield segment_polygon_distance(xy_a - off_a[:, k + j], xy_b - off_b[:, k + j], shape)


def _clearance_matrix(xy_a: Array, xy_b: Array, ref: ObstacleSet, off_a: Array | None,
                      off_b: Array | None) -> Array:
    """:func:`_clearance_columns` as a matrix (rows: steps, columns: obstacles)."""
    out = np.empty((len(xy_a), len(ref.circles) + len(ref.polygons)))
    for j, column in enumerate(_clearance_columns(xy_a, xy_b, ref, off_a, off_b)):
        out[:, j] = column
    return out


def step_clearances(
    path: ArrayLike, obstacles_at: Callable[[float], ObstacleSet] | ObstacleSet,
    backend: str = "auto",
) -> Array:
    """Exact clearance of the robot centre during each step, shape (max(n - 1, 1),).

    Between rows i and i+1 every obstacle is assumed to translate at constant velocity from its
    pose in ``obstacles_at(t_i)`` to its pose in ``obstacles_at(t_{i+1})`` (shapes and radii must
    not change; obstacle order must be stable). In an obstacle's own frame the robot then moves
    along the straight segment from p_i - o(t_i) to p_{i+1} - o(t_{i+1}) (o the obstacle's
    offset), so the step's clearance to that obstacle is an exact segment-to-static-obstacle
    distance (0 when touching, crossing or inside). The step clearance is the minimum over
    obstacles (+inf if there are none). A single-row path is one zero-length step.

    ``backend`` (:mod:`swarmpath.world.clearance`): ``"numba"`` visits only the obstacles a step
    can reach and gives the same doubles; ``"auto"`` uses it when numba is installed.
    """
    return _step_clearances(*_obstacle_frames(path, obstacles_at), backend)


def _step_clearances(P: Array, ref: ObstacleSet, off: Array | None, backend: str) -> Array:
    if ref.is_empty:
        return np.full(len(P) - 1, np.inf)
    xy = P[:, :2]
    if clearance.resolve(backend) == "numba":
        return clearance.step_clearances(xy, ref, off)
    out = np.full(len(P) - 1, np.inf)
    off_a, off_b = (None, None) if off is None else (off[:-1], off[1:])
    for column in _clearance_columns(xy[:-1], xy[1:], ref, off_a, off_b):
        out = np.minimum(out, column)  # the least over obstacles, one column at a time
    return out


class ContactCauses(NamedTuple):
    """Colliding steps by cause; ``robot_driven + obstacle_driven`` = the collisions.

    robot_driven: in the step the robot moved closer to an obstacle it touches (its own motion
    with that obstacle held where it was at the start of the step), or the obstacle is static;
    obstacle_driven: the robot was still or moved tangentially or away from every obstacle it
    touches, and each of them moved during the step (a moving obstacle reached it)."""

    robot_driven: int
    obstacle_driven: int


#: m: a robot displacement that changes its distance to an obstacle by less is not an approach.
APPROACH_TOL = 1e-9


def contact_causes(
    path: ArrayLike,
    obstacles_at: Callable[[float], ObstacleSet] | ObstacleSet,
    radius: float,
    backend: str = "auto",
) -> ContactCauses:
    """Classify every colliding step (see :class:`ContactCauses`); touching counts, as in
    :func:`min_clearance`. Only the colliding steps (:func:`step_clearances`, ``backend``) are
    looked at obstacle by obstacle."""
    P, ref, off = _obstacle_frames(path, obstacles_at)
    if ref.is_empty:
        return ContactCauses(0, 0)
    xy = P[:, :2]
    rows = np.flatnonzero(collides(_step_clearances(P, ref, off, backend), radius))
    if rows.size == 0:
        return ContactCauses(0, 0)
    a, b = xy[rows], xy[rows + 1]
    if off is None:
        off = np.zeros((len(P), ref.circles.shape[0] + len(ref.polygons), 2))
    swept = _clearance_matrix(a, b, ref, off[rows], off[rows + 1])
    touching = collides(swept, radius)
    frozen = off[rows]  # every obstacle held at its pose at the start of the step
    before = _clearance_matrix(a, a, ref, frozen, frozen)
    after = _clearance_matrix(b, b, ref, frozen, frozen)
    approached = after < before - APPROACH_TOL
    moved = np.hypot(*(off[rows + 1] - off[rows]).transpose(2, 0, 1)) > 0.0
    robot = touching & (approached | ~moved)
    n_robot = int(np.count_nonzero(robot.any(axis=1)))
    return ContactCauses(n_robot, int(rows.size) - n_robot)


def min_clearance(
    path: ArrayLike,
    obstacles_at: Callable[[float], ObstacleSet] | ObstacleSet,
    radius: float,
    backend: str = "auto",
) -> ClearanceResult:
    """Smallest body gap along a trajectory and the number of colliding steps.

    Uses :func:`step_clearances` (exact per step for obstacles translating at constant velocity
    within each step). ``obstacles_at`` maps a time to the obstacle snapshot (an ObstacleSet is
    accepted for static maps). The body gap of a step is clearance - radius; a step collides when
    ``collides(clearance, radius)``, i.e. gap <= 0.
    """
    c = step_clearances(path, obstacles_at, backend)
    return ClearanceResult(float(np.min(c) - radius), int(np.count_nonzero(collides(c, radius))))
