"""The seeds' step-wise local planner, as pure functions over arrays.

Each planning step a swarm searches candidate next waypoints c around the robot p, minimising the
weighted sum of eqs 3-6 of Ajeil et al. (2020) / eqs 1-6 of Abdulsaheb & Kadhim (2022):

    f1(c) = |g - c|                                  distance still to go (eq 3)
    f2(c) = |angle(c - p) - angle(g - p)|            heading deviation (eq 5, wrapped to [0, pi])
    f(c)  = w1 f1(c) + w2 f2(c),  w1 + w2 = 1        (eqs 6-7)

and the MFB paper's fitness 1 / (f + eps) (eq 8) when ``objective = "inverse"`` (maximised, so the
optimizer minimises -1 / (f + eps): same argmin as f, different landscape).

The planner knows obstacles only as the points its sensors hit (``hits``, world coordinates). A
candidate is infeasible when it lies within ``margin`` (robot radius + safety distance) of a hit
(case 1, inside an inflated obstacle) or when the segment p -> c passes within ``margin`` of one
(case 2). Infeasible candidates are repaired before they are scored:

* ``repair = "mfb"``: eqs 18-22 of Ajeil et al. Case 1 pushes c radially out of the obstacle to
  ``margin + ds`` from it (eqs 19-20; the obstacle centre is the nearest hit point); case 2 moves c
  by delta * D away from the obstacle, D = |c - p|, delta = 0.6 (eqs 21-22), sideways: the
  direction is from the obstacle to the segment's closest point (see ``_lateral``).
* ``repair = "grid"``: the ICOOT paper's section 4.1 on a grid of ``resolution``: case 1 moves c to
  the nearest free grid offset; case 2 slides c sideways across the line's dominant axis
  (horizontally for a mostly vertical line and vice versa) to the nearest offset whose segment is
  free.
* ``repair = "none"``: infeasible candidates are only penalised.

A candidate still infeasible after repair costs ``PENALTY`` plus its violation, so any feasible
candidate beats every infeasible one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
PENALTY = 1e6


@dataclass(frozen=True)
class StepContext:
    position: Array  # (2,) robot p
    goal: Array  # (2,) g
    hits: Array  # (h, 2) sensed obstacle surface points
    margin: float  # robot radius + safety distance: required clearance from any hit
    w1: float = 0.9
    w2: float = 0.1
    objective: str = "cost"  # or "inverse"
    eps: float = 1e-4
    repair: str = "mfb"  # or "grid" or "none"
    delta: float = 0.6
    safety: float = 0.05  # ds of eqs 19-20
    resolution: float = 0.05  # grid repair step
    lower: Array | None = None  # (2,) box the waypoint must stay in
    upper: Array | None = None
    backend: str = "numpy"  # or "numba": the repairs compiled (the same numbers)


def wrapped_abs(a: Array) -> Array:
    return np.abs(np.arctan2(np.sin(a), np.cos(a)))


def raw_cost(C: Array, ctx: StepContext) -> Array:
    """w1 f1 + w2 f2 for candidates C (..., 2)."""
    g, p = ctx.goal, ctx.position
    f1 = np.hypot(g[0] - C[..., 0], g[1] - C[..., 1])
    heading = np.arctan2(C[..., 1] - p[1], C[..., 0] - p[0])
    to_goal = np.arctan2(g[1] - p[1], g[0] - p[0])
    f2 = wrapped_abs(heading - to_goal)
    return ctx.w1 * f1 + ctx.w2 * f2


def point_hit_distance(C: Array, hits: Array) -> tuple[Array, NDArray[np.int64]]:
    """Distance from each candidate (..., 2) to its nearest hit, and that hit's index."""
    if len(hits) == 0:
        return np.full(C.shape[:-1], np.inf), np.zeros(C.shape[:-1], dtype=np.int64)
    flat = C.reshape(-1, 2)
    d2 = _point_d2(flat, hits)
    idx = np.argmin(d2, axis=1)
    best = np.sqrt(d2[np.arange(len(flat)), idx])
    return best.reshape(C.shape[:-1]), idx.reshape(C.shape[:-1])


def _point_d2(flat: Array, hits: Array) -> Array:
    """(n, h) squared distances (c_x - q_x)^2 + (c_y - q_y)^2, in place (same roundings as
    the plain expression)."""
    d2 = np.subtract.outer(flat[:, 0], hits[:, 0])
    d2 *= d2
    dy = np.subtract.outer(flat[:, 1], hits[:, 1])
    dy *= dy
    d2 += dy
    return d2


def segment_hit_distance(p: Array, C: Array, hits: Array) -> tuple[Array, NDArray[np.int64]]:
    """Distance from each segment p -> c to its nearest hit, and that hit's index.

    The same as :func:`swarmpath.world.geometry.point_segment_distance` against every hit,
    written for one shared start point (the robot): this runs for every swarm evaluation.
    """
    if len(hits) == 0:
        return np.full(C.shape[:-1], np.inf), np.zeros(C.shape[:-1], dtype=np.int64)
    flat = C.reshape(-1, 2)
    d2 = _segment_d2(p, flat, hits[:, 0] - p[0], hits[:, 1] - p[1])
    idx = np.argmin(d2, axis=1)
    best = np.sqrt(d2[np.arange(len(flat)), idx])
    return best.reshape(C.shape[:-1]), idx.reshape(C.shape[:-1])


def _segment_d2(p: Array, flat: Array, wx: Array, wy: Array) -> Array:
    """(n, h) squared distances from the hits (``wx``, ``wy``: relative to p, shaped (h,) or
    (n, h)) to the segments p -> c, in place with the roundings of

        t = clip((u . w) / (u . u + 1e-300), 0, 1);  d = w - t u;  d2 = d_x^2 + d_y^2
    """
    ux = (flat[:, 0] - p[0])[:, None]
    uy = (flat[:, 1] - p[1])[:, None]
    t = ux * wx
    t += uy * wy
    t /= ux * ux + uy * uy + 1e-300  # a zero-length segment has t = 0 / tiny = 0
    np.clip(t, 0.0, 1.0, out=t)
    dy = t * uy
    t *= ux
    np.subtract(wx, t, out=t)
    t *= t
    np.subtract(wy, dy, out=dy)
    dy *= dy
    t += dy
    return t


def _clip(C: Array, ctx: StepContext) -> Array:
    if ctx.lower is None or ctx.upper is None:
        return C
    return np.clip(C, ctx.lower, ctx.upper)


def _unit(v: Array) -> Array:
    n = np.hypot(v[..., 0], v[..., 1])[..., None]
    return np.where(n > 1e-12, v / np.where(n > 1e-12, n, 1.0), np.array([1.0, 0.0]))


def _lateral(p: Array, C: Array, Q: Array) -> Array:
    """Unit direction from obstacle points Q to the closest points of the segments p -> C.

    Eqs 21-22 move the candidate along the angle between obstacle and candidate; for a candidate
    straight behind the obstacle that angle points along the blocked line and never frees it, so
    the angle is taken toward the side the segment already passes on (the left normal of p -> c
    when the segment runs through the obstacle point itself).
    """
    u = C - p
    L2 = np.maximum(u[..., 0] ** 2 + u[..., 1] ** 2, 1e-24)
    s = np.clip(((Q[..., 0] - p[0]) * u[..., 0] + (Q[..., 1] - p[1]) * u[..., 1]) / L2, 0.0, 1.0)
    closest = p + s[..., None] * u
    side = closest - Q
    norm = np.hypot(side[..., 0], side[..., 1])[..., None]
    left = np.stack([-u[..., 1], u[..., 0]], axis=-1)
    left = left / np.sqrt(L2)[..., None]
    return np.where(norm > 1e-9, side / np.where(norm > 1e-9, norm, 1.0), left)


def repair_mfb(C: Array, ctx: StepContext, rounds: int = 3) -> Array:
    """Eqs 18-22 of Ajeil et al., applied up to ``rounds`` times (each case re-checked)."""
    return _repair_mfb(C, ctx, rounds)[0]


def _distances(C: Array, ctx: StepContext) -> tuple[Array, NDArray[np.int64], Array, NDArray[
    np.int64
]]:
    if ctx.backend == "numba" and len(ctx.hits):
        from swarmpath.planners.compiled import distances_kernel

        shape = C.shape[:-1]
        d_pt, i_pt, d_seg, i_seg = distances_kernel(
            np.ascontiguousarray(C.reshape(-1, 2), dtype=float),
            np.asarray(ctx.position, dtype=float), np.ascontiguousarray(ctx.hits, dtype=float))
        return d_pt.reshape(shape), i_pt.reshape(shape), d_seg.reshape(shape), i_seg.reshape(shape)
    d_pt, i_pt = point_hit_distance(C, ctx.hits)
    d_seg, i_seg = segment_hit_distance(ctx.position, C, ctx.hits)
    return d_pt, i_pt, d_seg, i_seg


def _box(ctx: StepContext) -> tuple[Array, Array, bool]:
    """(lower, upper, bounded) of the waypoint box for a compiled kernel."""
    bounded = ctx.lower is not None and ctx.upper is not None
    lower = np.asarray(ctx.lower if bounded else np.zeros(2), dtype=float)
    upper = np.asarray(ctx.upper if bounded else np.zeros(2), dtype=float)
    return lower, upper, bounded


def _repair_mfb(C: Array, ctx: StepContext, rounds: int) -> tuple[Array, Array]:
    """(repaired candidates, their remaining violation)."""
    hits = ctx.hits
    if len(hits) == 0:
        return C, np.zeros(C.shape[:-1])
    if ctx.backend == "numba":
        from swarmpath.planners.compiled import repair_mfb_kernel

        lower, upper, bounded = _box(ctx)
        out, short = repair_mfb_kernel(
            np.ascontiguousarray(C.reshape(-1, 2), dtype=float),
            np.asarray(ctx.position, dtype=float), np.ascontiguousarray(hits, dtype=float),
            float(ctx.margin), float(ctx.safety), float(ctx.delta), lower, upper, bounded,
            int(rounds))
        return out.reshape(C.shape), short.reshape(C.shape[:-1])
    for _ in range(rounds):
        d_pt, i_pt, d_seg, i_seg = _distances(C, ctx)
        inside = d_pt < ctx.margin  # case 1 (eq 18)
        crossing = ~inside & (d_seg < ctx.margin)  # case 2
        if not np.any(inside) and not np.any(crossing):
            return C, np.zeros(C.shape[:-1])
        if np.any(inside):
            away = _unit(C - hits[i_pt])
            push = (ctx.margin + ctx.safety - d_pt)[..., None]
            C = np.where(inside[..., None], C + push * away, C)  # eqs 19-20
        if np.any(crossing):
            away = _lateral(ctx.position, C, hits[i_seg])
            D = np.hypot(C[..., 0] - ctx.position[0], C[..., 1] - ctx.position[1])[..., None]
            C = np.where(crossing[..., None], C + ctx.delta * D * away, C)  # eqs 21-22
        C = _clip(C, ctx)
    d_pt, _, d_seg, _ = _distances(C, ctx)
    return C, np.maximum(ctx.margin - np.minimum(d_pt, d_seg), 0.0)


def repair_grid(C: Array, ctx: StepContext, reach: int = 24, chunk: int = 8) -> Array:
    """ICOOT section 4.1 on a grid: nearest free offset (case 1), sideways slide (case 2).

    Offsets 0, +1, -1, +2, -2, ... (times ``resolution``) across the line's dominant axis are
    tried nearest first, ``chunk`` sizes at a time, and only for candidates not yet resolved.
    """
    return _repair_grid(C, ctx, reach, chunk)[0]


def _repair_grid(C: Array, ctx: StepContext, reach: int = 24, chunk: int = 8) -> tuple[
    Array, Array
]:
    """(repaired candidates, their remaining violation)."""
    hits = ctx.hits
    if len(hits) == 0:
        return C, np.zeros(C.shape[:-1])
    p = ctx.position
    flat = C.reshape(-1, 2)
    if ctx.backend == "numba":
        from swarmpath.planners.compiled import repair_grid_kernel

        lower, upper, bounded = _box(ctx)
        out, short = repair_grid_kernel(
            np.ascontiguousarray(flat, dtype=float), np.asarray(p, dtype=float),
            np.ascontiguousarray(hits, dtype=float), float(ctx.margin), float(ctx.resolution),
            lower, upper, bounded, int(reach))
        return out.reshape(C.shape), short.reshape(C.shape[:-1])
    out = flat.copy()
    d_pt, _, d_seg, _ = _distances(flat, ctx)
    short = np.maximum(ctx.margin - np.minimum(d_pt, d_seg), 0.0)
    bad = np.flatnonzero(short > 0)
    if bad.size == 0:
        return C, short.reshape(C.shape[:-1])
    direction = flat[bad] - p
    # slide across the line's dominant axis: x for a mostly vertical line, y otherwise
    axis = np.where(np.abs(direction[:, 1]) > np.abs(direction[:, 0]), 0, 1)
    pending = np.ones(bad.size, dtype=bool)
    for first in range(1, reach + 1, chunk):
        k = np.arange(first, min(first + chunk, reach + 1)) * ctx.resolution
        steps = np.stack([k, -k], axis=1).ravel()  # +k, -k, nearest first
        idx = np.flatnonzero(pending)
        B = flat[bad[idx]]
        offsets = np.zeros((idx.size, steps.size, 2))
        offsets[np.arange(idx.size), :, axis[idx]] = steps
        trial = _clip(B[:, None, :] + offsets, ctx)
        tp, _ = point_hit_distance(trial, hits)
        free = tp >= ctx.margin
        # segments only for the offsets whose point is free (the costlier test)
        ts, _ = segment_hit_distance(p, trial[free], hits)
        free[free] = ts >= ctx.margin
        found = free.any(axis=1)
        pick = np.argmax(free, axis=1)
        out[bad[idx[found]]] = trial[found, pick[found]]
        short[bad[idx[found]]] = 0.0
        pending[idx[found]] = False
        if not pending.any():
            break
    return out.reshape(C.shape), short.reshape(C.shape[:-1])


def repair(C: Array, ctx: StepContext) -> Array:
    if ctx.repair == "mfb":
        return repair_mfb(C, ctx)
    if ctx.repair == "grid":
        return repair_grid(C, ctx)
    if ctx.repair == "none":
        return C
    raise ValueError(f"unknown repair {ctx.repair!r}; valid: mfb, grid, none")


def violation(C: Array, ctx: StepContext) -> Array:
    """How far (m) candidates fall short of the required clearance (0 when feasible)."""
    d_pt, _ = point_hit_distance(C, ctx.hits)
    d_seg, _ = segment_hit_distance(ctx.position, C, ctx.hits)
    return np.maximum(ctx.margin - np.minimum(d_pt, d_seg), 0.0)


def score(C: Array, ctx: StepContext) -> tuple[Array, Array]:
    """(objective to minimise, repaired candidates) for candidates C (..., 2)."""
    if ctx.backend == "numba":  # the same numbers, compiled (planners.compiled_score)
        from swarmpath.planners.compiled_score import score_into, setup

        geo, k = setup(ctx)
        flat = np.ascontiguousarray(C, dtype=float).reshape(-1, 2)
        F = np.empty(flat.shape[0])
        fixed = score_into(flat, geo, np.ascontiguousarray(ctx.hits, dtype=float).reshape(-1, 2),
                           k, F)
        return F.reshape(C.shape[:-1]), fixed.reshape(C.shape)
    if ctx.repair == "mfb":
        fixed, v = _repair_mfb(C, ctx, 3)
    elif ctx.repair == "grid":
        fixed, v = _repair_grid(C, ctx)
    else:
        fixed = repair(C, ctx)
        v = violation(fixed, ctx)
    cost = raw_cost(fixed, ctx)
    if ctx.objective == "inverse":
        cost = -1.0 / (cost + ctx.eps)  # eq 8's fitness, maximised
    elif ctx.objective != "cost":
        raise ValueError(f"unknown objective {ctx.objective!r}; valid: cost, inverse")
    return np.where(v > 0, PENALTY + v, cost), fixed


def keep_off(position: Array, move: Array, points: Array, reach: float | Array) -> Array:
    """``move`` (2,) changed as little as possible so that it closes on no point within ``reach``.

    Every point q of ``points`` (h, 2) within ``reach`` (a distance, or one per point) of
    ``position`` p gives the constraint ``move . n >= 0``, n the unit direction from q to p: the
    robot may move away from q or along the tangent, never toward it. For a convex obstacle whose
    nearest point to p is q, no such move brings p closer to it (the obstacle lies behind the
    tangent line through q). The constraints form a cone; the nearest move in it is ``move``
    itself, its projection on one of the cone's edges (a tangent), or zero (stop), whichever is
    allowed and nearest.
    """
    p = np.asarray(position, dtype=float)
    m = np.asarray(move, dtype=float)
    if len(points) == 0:
        return m
    rel = p - np.asarray(points, dtype=float)
    dist = np.hypot(rel[:, 0], rel[:, 1])
    close = dist <= np.asarray(reach, dtype=float)
    if not close.any():
        return m
    n = rel[close] / np.maximum(dist[close], 1e-12)[:, None]
    # a point at the robot's centre gives no direction: only stopping is safe
    if np.any(dist[close] <= 1e-12):
        return np.zeros(2)
    options = np.vstack([m[None, :], m - (n @ m)[:, None] * n, np.zeros((1, 2))])
    allowed = np.all(options @ n.T >= -1e-12, axis=1)
    options = options[allowed]  # zero is always allowed
    shift = np.hypot(*(options - m).T)
    return options[int(np.argmin(shift))]
