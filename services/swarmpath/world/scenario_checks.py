"""Validation of scenarios: every problem of a :class:`swarmpath.world.scenario.Scenario` as
``(field path, message)`` pairs, and the simple-polygon checks. Pure numpy."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from swarmpath.world.geometry import (
    collides,
    point_segment_distance,
    segment_segment_distance,
)
from swarmpath.world.scenario_parts import Motion, MotionSpec, Obstacle, RandomMotion, obstacle_set

if TYPE_CHECKING:
    from swarmpath.world.scenario import Scenario


#: Largest magnitude of a length, coordinate or speed in a scenario (metres, m/s): beyond it the
#: geometry's products overflow or lose its absolute tolerances (1e-9 m) in float64 rounding.
MAX_METRES = 1e7


def polygon_problems(points: ArrayLike) -> list[str]:
    """Why ``points`` is not a valid simple polygon (empty list: valid).

    Checks: at least 3 vertices, finite, no repeated consecutive vertex, non-zero area, and no two
    edges meeting anywhere except adjacent edges at their shared vertex (self-intersection).
    """
    P = np.asarray(points, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != 2:
        return ["must be a list of [x, y] points"]
    m = P.shape[0]
    if m < 3:
        return [f"needs at least 3 points, got {m}"]
    if not np.all(np.isfinite(P)):
        return ["coordinates must be finite"]
    if np.abs(P).max() > MAX_METRES:
        return [f"coordinates must be within +-{MAX_METRES:g} m"]
    A, B = P, np.roll(P, -1, axis=0)
    span = float(np.ptp(P, axis=0).max())
    tol = 1e-12 * max(span, 1.0)
    lengths = np.hypot(*(B - A).T)
    if np.any(lengths <= tol):
        q = int(np.argmax(lengths <= tol))
        return [f"points {q} and {(q + 1) % m} coincide"]
    # Non-adjacent edges must stay apart.
    i, j = np.triu_indices(m, k=2)
    keep = ~((i == 0) & (j == m - 1))
    i, j = i[keep], j[keep]
    if i.size:
        d = segment_segment_distance(A[i], B[i], A[j], B[j])
        bad = np.flatnonzero(d <= tol)
        if bad.size:
            k = int(bad[0])
            return [f"is self-intersecting (edges {int(i[k])} and {int(j[k])} meet)"]
    # Adjacent edges must not fold back onto each other (a vertex of one lying on the other).
    prev = np.roll(A, 1, axis=0)
    fold = (point_segment_distance(prev, A, B) <= tol) | (point_segment_distance(B, prev, A) <= tol)
    if np.any(fold):
        k = int(np.argmax(fold))
        return [f"is self-intersecting (edges {(k - 1) % m} and {k} overlap)"]
    area2 = float(np.sum(A[:, 0] * B[:, 1] - B[:, 0] * A[:, 1]))
    if abs(area2) <= tol * span:
        return ["has zero area"]
    return []


def scenario_problems(s: Scenario) -> list[tuple[str, str]]:
    """Everything wrong with ``s`` as ``(field path, message)`` pairs; empty when valid.

    Paths use the JSON spelling, e.g. ``("obstacles[2].radius", "must be > 0")``. Checks: positive
    finite size/time_step/robot numbers, radii > 0, simple polygons, non-negative motion speeds,
    start and goal inside the world and - at t = 0 - not in collision with any obstacle
    (clearance <= robot radius counts as a collision, :func:`~swarmpath.world.geometry.collides`).
    """
    out: list[tuple[str, str]] = []

    def positive(path: str, v: float | None) -> bool:
        if v is None or not math.isfinite(v) or v <= 0:
            out.append((path, "must be > 0"))
            return False
        if v > MAX_METRES:
            out.append((path, f"must be <= {MAX_METRES:g}"))
            return False
        return True

    if not s.name:
        out.append(("name", "must not be empty"))
    w, h = s.size
    size_ok = positive("size[0]", w) & positive("size[1]", h)
    positive("time_step", s.time_step)
    r = s.robot
    robot_ok = positive("robot.radius", r.radius)
    positive("robot.linear_speed", r.linear_speed)
    positive("robot.angular_speed", r.angular_speed)
    if r.model == "diff-drive":
        positive("robot.wheel_radius", r.wheel_radius)
        positive("robot.wheel_separation", r.wheel_separation)

    def motion(path: str, m: MotionSpec | None) -> None:
        if isinstance(m, Motion):
            if not (math.isfinite(m.speed) and m.speed >= 0):
                out.append((f"{path}speed", "must be >= 0"))
            elif m.speed > MAX_METRES:
                out.append((f"{path}speed", f"must be <= {MAX_METRES:g}"))
            if not math.isfinite(m.heading_deg):
                out.append((f"{path}heading_deg", "must be finite"))
        elif isinstance(m, RandomMotion):
            positive(f"{path}max_speed", m.max_speed)

    motion("goal_motion.", s.goal_motion)
    valid: list[Obstacle] = []  # obstacles well-formed enough for the collision checks
    for k, o in enumerate(s.obstacles):
        p = f"obstacles[{k}]"
        if o.shape == "circle":
            assert o.center is not None
            ok = all(math.isfinite(c) for c in o.center)
            if not ok:
                out.append((f"{p}.center", "coordinates must be finite"))
            elif max(abs(c) for c in o.center) > MAX_METRES:
                ok = False
                out.append((f"{p}.center", f"coordinates must be within +-{MAX_METRES:g} m"))
            if positive(f"{p}.radius", o.radius) and ok:
                valid.append(o)
        else:
            msgs = polygon_problems(o.points or ())
            out.extend((f"{p}.points", msg) for msg in msgs)
            if not msgs:
                valid.append(o)
        motion(f"{p}.", o.motion)
    obs = obstacle_set(valid)

    for label, pt in (("start", s.start), ("goal", s.goal)):
        x, y = pt
        if not (math.isfinite(x) and math.isfinite(y)):
            out.append((label, "coordinates must be finite"))
        elif size_ok and not (0.0 <= x <= w and 0.0 <= y <= h):
            out.append((label, f"({x:g}, {y:g}) is outside the world [0, {w:g}] x [0, {h:g}]"))
        elif robot_ok and not obs.is_empty:
            c = float(obs.point_clearance(np.array(pt)))
            if collides(c, r.radius):
                where = (f"lies inside an obstacle ({-c:.3g} m deep)" if c < 0 else
                         "lies on an obstacle's edge" if c == 0 else
                         f"is {c:.3g} m from an obstacle, within the robot radius {r.radius:g}")
                out.append((label, f"({x:g}, {y:g}) {where}: the robot collides there"))
    return out

