"""Sensing of the swarm local planner: what the robot remembers of its scans and their motion.

:class:`SwarmSensing` is the base of :class:`~swarmpath.planners.swarm_local.SwarmLocalPlanner`
(whose module docstring describes the sensing: step 1 and the moving obstacles); the planner's
``__init__`` sets the state declared below.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from swarmpath.planners import sensed_map
from swarmpath.planners.base import Observation, Planner
from swarmpath.world.geometry import point_segment_distance

Array = np.ndarray
#: Share of a scan's points within ``track_gap`` of a moving point that must move for it to be
#: given way to (``_give_way``): icoot-map1's static polygons showed 1-6 moving points among
#: tens; a random walker shows most of its visible surface moving.
MOVING_SHARE = 0.5
MOVING_POINTS = 3


class SwarmSensing(Planner):
    """Scan memory, motion tracking and the clearance kept; the planner decides with them."""

    _prior: Array
    _memory: list[tuple[float, Array, np.ndarray]]
    _last_scan: tuple[float, Array] | None
    _scan: tuple[Array, NDArray[np.bool_]]
    _moving_until: float
    _moving: tuple[Array, Array]
    _settled: Array
    _threats: tuple[Array, Array, NDArray[np.bool_]]
    _last_moving: Array
    _tracks: tuple[Array, Array, NDArray[np.int64]]
    _speed: float
    _diff_drive: bool
    _corner_until: float
    _coarse: bool


    def _known_hits(self, obs: Observation) -> Array:
        current = np.zeros((0, 2))
        if obs.reading is not None and len(obs.reading.hit_points):
            current = obs.reading.hit_points
        moving = np.zeros(len(current), dtype=bool)
        velocity = np.zeros((len(current), 2))
        if self._last_scan is not None:
            t0, previous = self._last_scan
            moving, velocity = sensed_map.motion(previous, current, obs.time - t0,
                                                 surface=float(self.p["surface"]),
                                                 backend=str(self.p["backend"]))
        self._scan = (current, moving)  # for ``_keep_off``
        whole = velocity.copy()
        tracked = self._track(current, moving, whole)
        self._moving = (current[tracked], whole[tracked])
        # for ``_give_way``: this scan's moving points with their velocities (whole-obstacle
        # when tracked), if a moving point of the last scan lies within ``track_gap`` (a
        # single scan's motion is also what a static surface shows when a new part of it
        # comes into view: mfb-static, MFB seed 5)
        seen = current[moving]
        again = np.zeros(len(seen), dtype=bool)
        gap = float(self.p["track_gap"])
        if len(seen) > 1 and len(self._last_moving):
            again = cKDTree(self._last_moving).query(seen)[0] <= gap
            # ... and most of the scan's distinct points around it moved, at least
            # MOVING_POINTS of them (a moving obstacle's visible surface moves; on a static one
            # a few rays at a newly seen edge do; rays of several layers hit the same point)
            every = np.unique(np.round(current, 4), axis=0)
            distinct = np.unique(np.round(seen, 4), axis=0)
            around = cKDTree(every).query_ball_point(seen, gap, return_length=True)
            close = cKDTree(distinct).query_ball_point(seen, gap, return_length=True)
            again &= (close >= MOVING_POINTS) & (close >= MOVING_SHARE * around)
        self._last_moving = seen
        self._threats = (seen[again], whole[moving][again], tracked[moving][again])
        if moving.any():
            self._moving_until = obs.time + float(self.p["memory"])
        if tracked.any():
            self._erase_trail(obs.time, current[tracked], whole[tracked])
        if len(current):
            self._memory.append((obs.time, current, tracked))
        horizon = obs.time - float(self.p["memory"])
        fade = obs.time - float(self.p["moving_memory"])
        kept = []
        for t, h, m in self._memory:
            if t < horizon - 1e-9:
                continue
            if t < fade - 1e-9 and m.any():
                h, m = h[~m], m[~m]  # a moving point is remembered ``moving_memory`` s only
            if len(h):
                kept.append((t, h, m))
        self._memory = kept
        parts = [h for _, h, _ in self._memory]
        if len(self._prior):
            parts.append(self._prior)
        # everything but this scan's tracked points and their predictions (see ``lead``)
        settled = [h[~m] if t == obs.time else h for t, h, m in self._memory]
        if len(self._prior):
            settled.append(self._prior)
        self._settled = np.concatenate(settled) if settled else np.zeros((0, 2))
        ahead = float(self.p["predict"])
        if ahead > 0 and moving.any():
            horizons = [ahead * k / 4 for k in range(1, 5)]
            parts.append(sensed_map.extrapolate(current[moving], velocity[moving], horizons))
            # tracked points: also along their whole-obstacle velocity (the measured surface
            # velocity is the approach component, the one that matters most for contact)
            parts.append(sensed_map.extrapolate(current[tracked], whole[tracked], horizons))
        self._last_scan = (obs.time, current)
        if sensed_map.has_corner(current, float(self.p["surface"]) or 0.2,
                                 float(self.p["corner_angle"]), str(self.p["backend"])):
            self._corner_until = obs.time + float(self.p["memory"])
        if not parts:
            return np.zeros((0, 2))
        return np.concatenate(parts)

    def _track(self, current: Array, moving: NDArray[np.bool_], velocity: Array) -> NDArray[
        np.bool_
    ]:
        """Which moving points of this scan move steadily (updates ``velocity`` in place).

        Each moving obstacle's velocity is estimated as a whole (:func:`sensed_map.
        group_velocity`); a point is *tracked* when the previous scan had a moving point within
        ``track_gap`` whose estimate differs by at most ``consistency`` (m/s). Tracked points get
        the whole-obstacle velocity (for the ``predict`` extrapolation and the ``lead`` plan) and
        are remembered only ``moving_memory`` seconds; other moving points (an obstacle on a
        random walk, whose next step its last one does not tell) keep their measured surface
        velocity and are remembered like static ones, so their recent positions stay a buffer.
        """
        tracked = np.zeros(len(current), dtype=bool)
        if float(self.p["lead"]) <= 0 or not moving.any():
            self._tracks = (np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0, dtype=np.int64))
            return tracked
        idx = np.flatnonzero(moving)
        whole = sensed_map.group_velocity(current[idx], velocity[idx],
                                          1.5 * (float(self.p["surface"]) or 0.2))
        previous, before, streak = self._tracks
        runs = np.zeros(len(idx), dtype=np.int64)
        self._tracks = (current[idx], whole, runs)
        if not len(previous):
            return tracked
        d, j = cKDTree(previous).query(current[idx])
        steady = (d <= float(self.p["track_gap"])) & (
            np.hypot(*(whole - before[j]).T) <= float(self.p["consistency"]))
        runs[steady] = streak[j[steady]] + 1
        steady = runs >= int(self.p["track_scans"])
        tracked[idx[steady]] = True
        velocity[idx[steady]] = whole[steady]
        return tracked

    def _plan_hits(self, p: Array) -> Array:
        """The sensed points the aim plans around (``lead``): each point x of this scan that
        moves at v is put where it will be when the robot, driving at full speed S, could reach
        it: x + v tau, |x + v tau - p| = S tau (tau at most ``lead``), instead of where it is and
        its short prediction. An obstacle crossing the robot's way is then planned around where
        it will be: behind it rather than ahead of it. The candidates' feasibility keeps every
        sensed and predicted point."""
        points, v = self._moving
        rel = points - p
        a = np.einsum("ij,ij->i", v, v) - self._speed**2
        b = np.einsum("ij,ij->i", rel, v)
        c = np.einsum("ij,ij->i", rel, rel)
        lead = float(self.p["lead"])
        slow = a < -1e-9  # slower than the robot: one positive root
        root = np.sqrt(np.maximum(b * b - a * c, 0.0))
        tau = np.where(slow, (-b - root) / np.where(slow, a, -1.0), lead)
        tau = np.clip(tau, 0.0, lead)
        return np.concatenate([self._settled, points + v * tau[:, None]])

    def _erase_trail(self, time: float, points: Array, velocity: Array) -> None:
        """Forget remembered points where a moving surface has been (``moving_memory``): a point
        sensed ``a`` seconds ago within ``trail`` of the segment from a moving point x back to
        x - v (a + 0.25 s). Such a point is where the obstacle was, not where it is; kept, the
        trail of its surface (0.6 m for 0.3 m/s over the 2 s memory) blocks the way behind it."""
        tol = float(self.p["trail"])
        if tol <= 0 or float(self.p["moving_memory"]) >= float(self.p["memory"]):
            return
        kept = []
        for t, h, m in self._memory:
            back = velocity * (time - t + float(self.p["replan"]))
            d = point_segment_distance(h[:, None, :], (points - back)[None], points[None])
            trail = d.min(axis=1) < tol
            kept.append((t, h[~trail], m[~trail]))
        self._memory = [(t, h, m) for t, h, m in kept if len(h)]

    def _safety(self, time: float) -> float:
        """ds: the clearance kept beyond the robot radius. Sensed points sample a surface every
        few centimetres: a circle's polyline stays within millimetres of it, a corner's tip can
        lie between two rays, so 1 cm is kept only while no corner was sensed recently, and
        only when the robot moves at most 5 cm per simulated step."""
        if self._diff_drive:
            return float(self.p["diff_drive_safety"])
        coarse = self._coarse or time <= self._corner_until
        return float(self.p["corner_safety" if coarse else "safety"])
