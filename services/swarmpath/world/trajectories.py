"""Stated trajectories that run into static obstacles.

A constant-velocity goal or obstacle (:class:`~swarmpath.world.scenario.Motion`) has a path known
in advance. :func:`trajectory_warnings` samples it over the episode's default time limit and
reports, naming the field, a moving goal that enters a static obstacle inflated by the robot
radius (the robot could not be on it then) and a moving obstacle that overlaps a static one
(it would pass through a wall). Random walks state no trajectory and are not checked. These are
warnings, not errors: the simulation stays well defined (movers only reflect at the world
border).
"""

from __future__ import annotations

import math

import numpy as np

from swarmpath.world.geometry import collides
from swarmpath.world.scenario import Motion, Scenario

__all__ = ["trajectory_warnings"]

MAX_SAMPLES = 4000
TIME_FACTOR = 6.0  # as the episode's default time limit: 6 x straight-line time + 60 s


def _first(mask: np.ndarray) -> int | None:
    hit = np.flatnonzero(mask)
    return int(hit[0]) if len(hit) else None


def trajectory_warnings(s: Scenario, horizon: float | None = None) -> list[tuple[str, str]]:
    """``(field, message)`` for each constant-velocity mover whose path over ``horizon`` seconds
    (default: the episode's time limit) meets a static obstacle; at most one per mover."""
    static = s.static_obstacles()
    const = [k for k, o in enumerate(s.obstacles) if isinstance(o.motion, Motion)]
    goal_moves = isinstance(s.goal_motion, Motion)
    if static.is_empty or not (const or goal_moves):
        return []
    if horizon is None:
        straight = math.dist(s.start, s.goal)
        horizon = TIME_FACTOR * straight / s.robot.linear_speed + 60.0
    speeds = [s.obstacles[k].motion.max_speed for k in const]  # type: ignore[union-attr]
    if goal_moves:
        speeds.append(s.goal_motion.max_speed)  # type: ignore[union-attr]
    fastest = max(max(speeds), 1e-9)
    n = int(min(MAX_SAMPLES, max(2, math.ceil(horizon * fastest / 0.05))))
    times = np.linspace(0.0, horizon, n)
    world = s.instantiate(np.random.default_rng(0))  # constant motion draws nothing
    out: list[tuple[str, str]] = []
    if goal_moves:
        pts = np.array([world.goal_at(float(t)) for t in times])
        k = _first(collides(static.point_clearance(pts), s.robot.radius))
        if k is not None:
            x, y = pts[k]
            out.append(("goal_motion", f"the goal's stated path enters a static obstacle "
                        f"(inflated by the robot radius {s.robot.radius:g} m) at t = "
                        f"{times[k]:.1f} s, at ({x:.3g}, {y:.3g})"))
    if const:
        ref = np.array([world.obstacle_positions_at(float(t)) for t in times])  # (n, m, 2)
        column = {k: j for j, k in enumerate(world.set_order)}
        for k in const:
            o = s.obstacles[k]
            moved = ref[:, column[k]] - ref[0, column[k]]  # translation at each time
            if o.shape == "circle":
                assert o.center is not None and o.radius is not None
                c = np.asarray(o.center) + moved
                bad = np.asarray(static.point_clearance(c) < o.radius, dtype=bool)
            else:
                pts = np.asarray(o.points)
                a = (pts[None, :, :] + moved[:, None, :]).reshape(-1, 2)
                b = (np.roll(pts, -1, axis=0)[None, :, :] + moved[:, None, :]).reshape(-1, 2)
                bad = np.asarray(static.segment_clearance(a, b) <= 0.0).reshape(n, -1)
                bad = np.asarray(bad.any(axis=1), dtype=bool)
            i = _first(bad)
            if i is not None:
                out.append((f"obstacles[{k}]", f"its stated path runs into a static obstacle at "
                            f"t = {times[i]:.1f} s"))
    return out
