"""Following the RFO family's path among moving obstacles, and a moving goal.

:class:`RfoFollow` is the base of :class:`~swarmpath.planners.rfo_gwo.RfoFamilyPlanner`; the
planner sets the state declared below and plans (:meth:`_begin`, :meth:`_plan`).

Following the path among moving obstacles
-----------------------------------------
The planner gets only the static map. A moving goal: when the path is used up and the goal is more
than ``goal_snap`` from where it was planned to, the planner plans again from the robot to the
goal's new place. When the observation carries a sensor reading and the
scenario declares moving obstacles (that fact only), :meth:`RfoFollow._follow` hands out
decisions of ``replan`` (0.25 s) so that the robot re-senses. Hits farther than ``STATIC_HIT``
from the static map and the border, with their positions predicted ``predict`` (1 s) ahead
(:func:`sensed_map.predict`) and condensed within ``watch`` (3 m) (:func:`sensed_map.condense`),
must stay farther than r + ``dynamic_margin`` (0.3 m) from the segment to the current waypoint;
otherwise the robot waits or steps ``side_step`` (0.3 m) to the candidate (12 directions) that
keeps that margin and is nearest the waypoint, or, with none, to the one with the most room. A
waypoint no longer reachable on the static map after a step aside triggers a new plan from the
current position. Without sensors or moving obstacles the waypoints are handed out as
:mod:`swarmpath.planners.rfo_gwo` describes.
"""

from __future__ import annotations

import math
from abc import abstractmethod

import numpy as np

from swarmpath.planners import sensed_map
from swarmpath.planners.base import Decision, Observation
from swarmpath.planners.rfo_geometry import _hit_clearance
from swarmpath.planners.rfo_refine import RfoRefine
from swarmpath.planners.rfo_search import Array
from swarmpath.robot.kinematics import ARRIVE
from swarmpath.world.geometry import ObstacleSet, collides

STATIC_HIT = 0.05  # m: a sensed hit this close to the static map or the border is explained by it
HIT_CELL = 0.05  # m: sensed hits are condensed to one per cell of this size


class RfoFollow(RfoRefine):
    """Waypoints handed out while the sensors watch moving obstacles; plans again if needed."""

    _waypoints: Array | None
    _next: int
    _cost: int
    _static: ObstacleSet
    _last_scan: tuple[float, Array] | None
    _moving: bool

    @abstractmethod
    def _begin(self, obs: Observation) -> Decision:
        """Plan from the robot to the goal as observed and hand out the first waypoint."""

    @abstractmethod
    def _plan(self, start: Array, goal: Array, radius: float) -> None:
        """Plan from ``start`` to ``goal``: sets the waypoints, the cost or the failure."""

    def _goal_moved(self, obs: Observation) -> bool:
        """The path is used up and the goal is more than ``goal_snap`` from where it was planned
        to (a moving goal): the planner plans again from the robot to the goal's new place."""
        return math.dist(np.asarray(obs.goal, dtype=float), self._goal) > float(
            self.p["goal_snap"])

    # ------------------------------------------------------------- sensed moving obstacles
    def _sensed(self, obs: Observation, position: Array) -> Array:
        """Sensed hits not explained by the static map or the world border, plus their predicted
        positions (:func:`sensed_map.predict`), condensed within ``watch`` of ``position``."""
        assert obs.reading is not None
        hits = np.asarray(obs.reading.hit_points, dtype=float).reshape(-1, 2)
        if len(hits):
            w, h = obs.world_size
            border = np.minimum(np.minimum(hits[:, 0], w - hits[:, 0]),
                                np.minimum(hits[:, 1], h - hits[:, 1]))
            static = self._static.point_clearance(hits) <= STATIC_HIT
            hits = hits[~static & (border > STATIC_HIT)]
        parts = [hits]
        if self._last_scan is not None:
            t0, previous = self._last_scan
            ahead = float(self.p["predict"])
            if ahead > 0:
                steps = tuple(ahead * k / 4 for k in range(1, 5))
                parts.append(sensed_map.predict(previous, hits, obs.time - t0, steps))
        self._last_scan = (obs.time, hits)
        return sensed_map.condense(np.concatenate(parts), position, float(self.p["watch"]),
                                   HIT_CELL)

    def _watching(self, obs: Observation) -> bool:
        """Watch the sensors when there are some and the scenario says obstacles move (where and
        how they move is not used; without moving obstacles the static map is the whole world)."""
        return obs.reading is not None and self._moving

    def _follow(self, obs: Observation) -> Decision:
        """Follow the path while watching the sensors (scenarios with sensors only).

        Decisions last ``replan`` seconds so that the robot re-senses: drive
        to the current waypoint while the sensed and predicted points stay farther than
        ``radius + dynamic_margin`` from the segment, else step aside (or wait) to the free
        candidate nearest the waypoint; a waypoint no longer reachable on the static map
        triggers a new plan from the current position.
        """
        assert self._waypoints is not None
        r = float(obs.robot_radius)
        pos = np.array([obs.pose.x, obs.pose.y])
        hits = self._sensed(obs, pos)
        k = self._next - 1  # the waypoint handed out last
        if k >= 0 and math.dist(pos, self._waypoints[k]) <= 10 * ARRIVE:
            k = self._next
            if k >= len(self._waypoints):
                if self._goal_moved(obs):
                    return self._begin(obs)
                return Decision(None, 0, None, "path exhausted before the goal was reached")
            self._next = k + 1
        target = self._waypoints[k].copy()
        finish = k == len(self._waypoints) - 1
        duration = float(self.p["replan"])
        if len(hits) == 0:
            return Decision(target, 0, duration, finish=finish, align=True)
        margin = r + float(self.p["dynamic_margin"])
        iterations = 0
        if collides(self._static.segment_clearance(pos[None, :], target[None, :]), r)[0]:
            # a step aside left the path: plan again from here on the static map
            goal = np.asarray(obs.goal, dtype=float)
            self._plan(pos, goal, r)
            iterations = self._cost
            if self._failure is not None:
                return Decision(None, iterations, None, self._failure)
            assert self._waypoints is not None
            self._next = 1
            target = self._waypoints[0].copy()
            finish = len(self._waypoints) == 1
        if _hit_clearance(pos, target, hits) > margin:
            return Decision(target, iterations, duration, finish=finish, align=True)
        # blocked: the candidate (waiting included) nearest the waypoint that stays clear
        step = float(self.p["side_step"])
        angles = np.arange(12) * (2 * math.pi / 12)
        cands = np.vstack([pos, pos + step * np.column_stack([np.cos(angles), np.sin(angles)])])
        w, h = obs.world_size
        cands = np.clip(cands, [r, r], [w - r, h - r])
        starts = np.broadcast_to(pos, cands.shape)
        free = ~collides(self._static.segment_clearance(starts, cands), r)
        room = np.array([_hit_clearance(pos, c, hits) for c in cands])
        ok = free & (room > margin)
        if ok.any():
            cost = np.where(ok, np.hypot(*(cands - target).T), np.inf)
            return Decision(cands[int(np.argmin(cost))], iterations, duration, align=True)
        room = np.where(free, room, -np.inf)
        return Decision(cands[int(np.argmax(room))], iterations, duration, align=True)

