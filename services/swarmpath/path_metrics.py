"""The field's path-quality metrics of an executed trajectory (pure functions; the clearances
through :mod:`swarmpath.world.clearance`, compiled when numba is installed, the same doubles).

Beside :mod:`swarmpath.metrics` (length, smoothness, the exact swept clearance and collisions):
what Bench-MR, OMPL, MRPB and nav2's planner benchmark report, each computed on the executed
trajectory (rows ``[x, y, t]``, straight at constant velocity between rows, as everywhere in
swarmpath). Definitions, sources and the decisions where a source is silent: docs/metrics.md,
"The field's metrics".

* :func:`clearance_profile` - body gap (clearance - robot radius) along the path, sampled every
  :data:`CLEARANCE_SPACING` metres of arc length (Bench-MR's and OMPL's clearance is over the
  states of an interpolated path), each sample against the obstacles at its own time.
* :func:`curvature` - Bench-MR's curvature: the circle through three points of the path
  :data:`CURVATURE_SPACING` apart (arc length); its maximum and mean.
* :func:`cusps` - Bench-MR's cusps: vertices between consecutive moving steps that turn by more
  than :data:`CUSP_ANGLE` (a turn in place is one vertex; a smooth arc has none).
* :func:`danger_share` - MRPB's safety: the share of the travel time spent within
  :data:`DANGER_DISTANCE` of an obstacle (body gap), over runs of consecutive rows in danger.
* :func:`motion_smoothness` - MRPB's velocity smoothness (mean |dv| / dt, m/s^2), its angular
  counterpart on the direction of travel (mean |d omega| / dt, rad/s^2) and the mean jerk
  magnitude (|d a / dt|, m/s^3).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmpath.world import clearance
from swarmpath.world.geometry import ObstacleSet

Array = NDArray[np.float64]

#: m of arc length between the clearance samples (about two simulator steps at 0.5 m/s).
CLEARANCE_SPACING = 0.05
#: m between the three points of Bench-MR's curvature.
CURVATURE_SPACING = 0.3
#: rad: a vertex turning by more counts as a cusp (Bench-MR: 60 degrees).
CUSP_ANGLE = math.pi / 3.0
#: m of body gap (clearance - radius) under which the robot is "in danger" (MRPB's safety).
DANGER_DISTANCE = 0.1
MOVING = 1e-9  # m: a shorter step is a stop (turning in place, waiting), with no direction
#: The per-run fields these metrics (and nav2's costs, :mod:`swarmpath.costmap`) fill
#: (RunOutcome); summaries average them over the successful runs under the same names.
PATH_METRICS = ("clearance_mean", "curvature_max", "curvature_mean", "cusps", "danger_share",
                "velocity_smoothness", "angular_smoothness", "jerk", "costmap_cost_mean",
                "costmap_cost_max")

__all__ = [
    "CLEARANCE_SPACING",
    "CURVATURE_SPACING",
    "CUSP_ANGLE",
    "DANGER_DISTANCE",
    "PATH_METRICS",
    "Curvature",
    "PathQuality",
    "Smoothness",
    "clearance_profile",
    "curvature",
    "cusps",
    "danger_share",
    "motion_smoothness",
    "path_quality",
    "resample",
    "row_gaps",
]


def _rows(path: ArrayLike) -> Array:
    P = np.asarray(path, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != 3:
        raise ValueError(f"trajectory must be an (n, 3) array of [x, y, t], got shape {P.shape}")
    return P


def resample(path: ArrayLike, spacing: float) -> Array:
    """Rows ``[x, y, t]`` every ``spacing`` metres of arc length from the first row, plus the
    last row (linear interpolation within a step; stops add no length and no sample)."""
    P = _rows(path)
    if len(P) < 2:
        return P.copy()
    seg = np.hypot(*np.diff(P[:, :2], axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    total = float(s[-1])
    if total <= 0.0:
        return P[[0, -1]].copy()
    at = np.arange(0.0, total, spacing)
    at = np.append(at, total) if total - at[-1] > 1e-12 else at
    keep = np.concatenate([[True], seg > 0.0])  # arc length strictly increasing
    return np.stack([np.interp(at, s[keep], P[keep, k]) for k in range(3)], axis=1)


def _gaps(points: Array, obstacles_at: Callable[[float], ObstacleSet] | ObstacleSet,
          radius: float) -> Array:
    """Body gap of each row ``[x, y, t]`` against the obstacles at its time (inf: none)."""
    if isinstance(obstacles_at, ObstacleSet):
        if obstacles_at.is_empty:
            return np.full(len(points), np.inf)
        return clearance.point_clearances(obstacles_at, points[:, :2]) - radius
    out = np.empty(len(points))
    times, inverse = np.unique(points[:, 2], return_inverse=True)
    # rows grouped by their snapshot: a static world hands out one for every time (one call)
    snapshots: dict[int, tuple[ObstacleSet, list[int]]] = {}
    for k, t in enumerate(times):
        obs = obstacles_at(float(t))
        snapshots.setdefault(id(obs), (obs, []))[1].append(k)
    for obs, ks in snapshots.values():
        rows = np.isin(inverse, ks)
        out[rows] = (np.inf if obs.is_empty
                     else clearance.point_clearances(obs, points[rows, :2]) - radius)
    return out


def clearance_profile(path: ArrayLike,
                      obstacles_at: Callable[[float], ObstacleSet] | ObstacleSet,
                      radius: float, spacing: float = CLEARANCE_SPACING) -> Array:
    """Body gap (clearance - radius, m; negative inside an obstacle) at samples every
    ``spacing`` metres along the path, each against the obstacles at the sample's time."""
    return _gaps(resample(path, spacing), obstacles_at, radius)


def row_gaps(path: ArrayLike, obstacles_at: Callable[[float], ObstacleSet] | ObstacleSet,
             radius: float) -> Array:
    """Body gap at every row of the trajectory (the simulator's poses), at the row's time."""
    return _gaps(_rows(path), obstacles_at, radius)


class Curvature(NamedTuple):
    """Bench-MR's curvature (1/m) of the circles through three points CURVATURE_SPACING apart:
    the largest and the mean over the triples (0 for a path shorter than two spacings)."""

    max: float
    mean: float


def curvature(path: ArrayLike, spacing: float = CURVATURE_SPACING) -> Curvature:
    """Menger curvature 4 A / (a b c) of consecutive triples of :func:`resample` points; a
    reversal (the outer points coincide) counts as the tightest turn the spacing can show,
    2 / spacing."""
    Q = resample(path, spacing)[:, :2]
    if len(Q) < 3:
        return Curvature(0.0, 0.0)
    a = np.hypot(*(Q[1:-1] - Q[:-2]).T)
    b = np.hypot(*(Q[2:] - Q[1:-1]).T)
    c = np.hypot(*(Q[2:] - Q[:-2]).T)
    u, v = Q[1:-1] - Q[:-2], Q[2:] - Q[:-2]
    twice_area = np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        k = 2.0 * twice_area / (a * b * c)
    k = np.where(c <= 1e-12 * spacing, 2.0 / spacing, k)
    k = k[np.isfinite(k)]
    if k.size == 0:
        return Curvature(0.0, 0.0)
    return Curvature(float(k.max()), float(k.mean()))


def _moving_steps(P: Array) -> tuple[Array, Array]:
    """The steps that move (> MOVING m) and their end-row indices."""
    d = np.diff(P[:, :2], axis=0)
    moving = np.hypot(d[:, 0], d[:, 1]) > MOVING
    return d[moving], np.flatnonzero(moving) + 1


def cusps(path: ArrayLike, angle: float = CUSP_ANGLE) -> int:
    """Vertices between consecutive moving steps (stops skipped: a turn in place is one vertex)
    whose direction changes by more than ``angle`` (Bench-MR: 60 degrees)."""
    d, _ = _moving_steps(_rows(path))
    if len(d) < 2:
        return 0
    h = np.arctan2(d[:, 1], d[:, 0])
    turn = np.abs(np.mod(np.diff(h) + math.pi, 2.0 * math.pi) - math.pi)
    return int(np.count_nonzero(turn > angle))


def danger_share(gaps: ArrayLike, times: ArrayLike, danger: float = DANGER_DISTANCE) -> float:
    """MRPB's safety: the time of every run of consecutive rows whose body gap is below
    ``danger`` (from the run's first row to its last), over the whole travel time; 0 for a
    trajectory that takes no time."""
    g = np.asarray(gaps, dtype=float)
    t = np.asarray(times, dtype=float)
    total = float(t[-1] - t[0]) if len(t) else 0.0
    if total <= 0.0:
        return 0.0
    inside = g < danger
    both = inside[:-1] & inside[1:]  # a step inside a run: both of its rows in danger
    return float(np.sum(np.diff(t)[both]) / total)


class Smoothness(NamedTuple):
    """MRPB's velocity smoothness (mean |dv/dt| of the speed, m/s^2), the same for the rate of
    turn of the direction of travel (rad/s^2), and the mean jerk magnitude (m/s^3)."""

    velocity: float
    angular: float
    jerk: float


def motion_smoothness(path: ArrayLike) -> Smoothness:
    """Finite differences over the trajectory's steps (velocity of a step = its displacement
    over its duration, at the step's mid-time); the turn rate is taken between consecutive
    moving steps (a turn in place is a change of direction at the stop's length of time).
    Steps of zero duration are skipped. 0 where there are too few steps."""
    P = _rows(path)
    dt = np.diff(P[:, 2])
    keep = dt > 0.0
    if np.count_nonzero(keep) < 2:
        return Smoothness(0.0, 0.0, 0.0)
    vel = np.diff(P[:, :2], axis=0)[keep] / dt[keep, None]
    mid = 0.5 * (P[:-1, 2] + P[1:, 2])[keep]
    speed = np.hypot(vel[:, 0], vel[:, 1])
    tau = np.diff(mid)
    velocity = float(np.mean(np.abs(np.diff(speed)) / tau))
    acc = np.diff(vel, axis=0) / tau[:, None]
    if len(acc) >= 2:
        jerk_vec = np.diff(acc, axis=0) / (0.5 * (tau[1:] + tau[:-1]))[:, None]
        jerk = float(np.mean(np.hypot(jerk_vec[:, 0], jerk_vec[:, 1])))
    else:
        jerk = 0.0
    moving = speed > MOVING / np.max(dt)
    h = np.arctan2(vel[moving, 1], vel[moving, 0])
    tm = mid[moving]
    angular = 0.0
    if len(h) >= 3:
        omega = (np.mod(np.diff(h) + math.pi, 2.0 * math.pi) - math.pi) / np.diff(tm)
        t_omega = 0.5 * (tm[1:] + tm[:-1])
        angular = float(np.mean(np.abs(np.diff(omega)) / np.diff(t_omega)))
    return Smoothness(velocity, angular, jerk)


class PathQuality(NamedTuple):
    """Every metric of this module for one run (see the module docstring)."""

    clearance_mean: float  # m, mean body gap along the path (inf without obstacles)
    curvature_max: float  # 1/m
    curvature_mean: float  # 1/m
    cusps: int
    danger_share: float  # share of the travel time within DANGER_DISTANCE
    velocity_smoothness: float  # m/s^2
    angular_smoothness: float  # rad/s^2
    jerk: float  # m/s^3


def path_quality(path: ArrayLike,
                 obstacles_at: Callable[[float], ObstacleSet] | ObstacleSet,
                 radius: float, danger: float = DANGER_DISTANCE) -> PathQuality:
    """All of the module's metrics for one executed trajectory."""
    P = _rows(path)
    along = clearance_profile(P, obstacles_at, radius)
    rows = row_gaps(P, obstacles_at, radius)
    k = curvature(P)
    s = motion_smoothness(P)
    return PathQuality(
        clearance_mean=float(np.mean(along)) if along.size else math.inf,
        curvature_max=k.max, curvature_mean=k.mean, cusps=cusps(P),
        danger_share=danger_share(rows, P[:, 2], danger),
        velocity_smoothness=s.velocity, angular_smoothness=s.angular, jerk=s.jerk,
    )
