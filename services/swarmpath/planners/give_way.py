"""Giving way to moving obstacles: where a move takes the robot, and how near the sensed moving
points can come to it meanwhile (the swarm local planner's ``give_way``; docs/planners.md,
"Giving way to moving obstacles").

A tracked moving point x (a steady velocity v over several scans) is predicted at x + v t after
t seconds; any other moving point (an erratic walker: the papers' random walk redraws heading
and speed every step) anywhere within ``spread`` |v| t of x. A move is rolled out with the
robot's own drive (a differential drive turns in place at its top angular speed, then drives
straight at its top speed; an omnidirectional robot drives straight at once) at every control
step over the horizon, and scored by its least body gap to those points and to the sensed
static points. Pure functions, no state.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def rollout(
    position: Array, heading: float, targets: Array, speed: float, turn_rate: float | None,
    dt: float, steps: int,
) -> Array:
    """Centres (k, steps, 2) after each of ``steps`` control steps of ``dt`` s driving from
    ``position`` toward each of ``targets`` (k, 2): turn in place at ``turn_rate`` rad/s until
    facing the target (``None``: an omnidirectional robot, no turn), then straight at ``speed``
    m/s, stopping on the target (what the simulator's aligned drive does)."""
    p = np.asarray(position, dtype=float)
    rel = np.asarray(targets, dtype=float) - p
    dist = np.hypot(rel[:, 0], rel[:, 1])
    unit = rel / np.maximum(dist, 1e-12)[:, None]
    if turn_rate is None:
        turns = np.zeros(len(rel))
    else:
        err = np.abs((np.arctan2(rel[:, 1], rel[:, 0]) - heading + math.pi) % (2 * math.pi)
                     - math.pi)
        turns = np.ceil(err / (turn_rate * dt) - 1e-12)
        turns = np.where(dist > 1e-12, np.maximum(turns, 0.0), 0.0)
    j = np.arange(1, steps + 1, dtype=float)
    driven = np.clip(j[None, :] - turns[:, None], 0.0, None) * speed * dt  # (k, steps)
    driven = np.minimum(driven, dist[:, None])
    return p[None, None, :] + driven[:, :, None] * unit[:, None, :]


def moving_gaps(centres: Array, dt: float, points: Array, velocities: Array, steady: Array,
                spread: float, radius: float) -> Array:
    """Least body gap (k,) of each rollout ``centres`` (k, steps, 2) to the moving ``points``
    (m, 2) with sensed ``velocities`` (m, 2) at times t = j dt (step j): a ``steady`` point
    (a tracked obstacle, constant velocity) is at x + v t; any other moving point (a random
    walk: its last velocity does not say where it goes next, its speed says how far) anywhere
    within ``spread`` |v| t of x. +inf without points."""
    if len(points) == 0:
        return np.full(len(centres), np.inf)
    t = dt * np.arange(1, centres.shape[1] + 1, dtype=float)
    follow = np.where(steady, 1.0, 0.0)[:, None] * velocities
    ahead = points[None, :, :] + t[:, None, None] * follow[None, :, :]  # (steps, m, 2)
    speed = np.where(steady, 0.0, spread * np.hypot(velocities[:, 0], velocities[:, 1]))
    grow = speed[None, :] * t[:, None]
    d = np.hypot(*(centres[:, :, None, :] - ahead[None]).transpose(3, 0, 1, 2))
    return np.asarray((d - grow[None]).min(axis=(1, 2)) - radius)


def static_gaps(centres: Array, points: Array, radius: float) -> Array:
    """Least body gap (k,) of each rollout ``centres`` (k, steps, 2) to the static ``points``."""
    if len(points) == 0:
        return np.full(len(centres), np.inf)
    d = np.hypot(*(centres[:, :, None, :] - points[None, None]).transpose(3, 0, 1, 2))
    return np.asarray(d.min(axis=(1, 2)) - radius)


def choose(moving: Array, still: Array, still_now: float, need: float, ends: Array,
           wanted: Array, prefer: int | None = None) -> int:
    """Index of the move to drive, given each move's least gap to the moving points
    (``moving``) and to the static ones (``still``; ``still_now`` where the robot stands) and
    where its rollout ends (``ends``). 0 (the planner's own move) when it keeps ``need`` from
    the moving points. Otherwise a *safe* move, one that keeps ``need`` from them and comes no
    closer to a static point than ``need`` or than the robot is now: ``prefer`` (the way the
    robot gave way last time) if it is safe, else the safe move ending nearest to ``wanted``
    (the planner's target). With no safe move, the one with the largest gap to the moving
    points among those that respect the static points (among all, if none does), or
    ``prefer`` if its gap is within ``need`` of that one's."""
    if moving[0] >= need:
        return 0
    static_ok = still >= min(need, still_now) - 1e-9
    safe = static_ok & (moving >= need)
    safe[0] = False
    if prefer is not None and safe[prefer]:
        return prefer
    if safe.any():
        miss = np.hypot(*(ends - wanted).T)
        return int(np.argmin(np.where(safe, miss, np.inf)))
    pool = static_ok if static_ok.any() else np.ones(len(moving), dtype=bool)
    best = int(np.argmax(np.where(pool, moving, -np.inf)))
    if prefer is not None and pool[prefer] and moving[prefer] >= moving[best] - need:
        return prefer  # nearly as good: keep going that way rather than turn about
    return best
