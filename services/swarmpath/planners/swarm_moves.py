"""How far one decision of the swarm local planner may move the robot, and toward what not.

:class:`SwarmMoveLimits` is a base of :class:`~swarmpath.planners.swarm_local.SwarmLocalPlanner`:
a move is cut to what the sensors covered (:meth:`_cut`, :meth:`_commit`) and never closes on
what the robot touches (:meth:`_keep_off`); the planner's ``__init__`` sets the state below.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from swarmpath.planners import give_way, local, sensed_map
from swarmpath.planners.base import Decision, Observation
from swarmpath.planners.swarm_aim import SwarmAim
from swarmpath.planners.swarm_sensing import Array

#: m beyond the body: a sensed point this near is touching (rays hit the surface exactly; the
#: planner keeps at least 1 cm from every hit, so a run without contact never comes this near).
CONTACT = 0.002
#: m beyond the body: untracked moving points farther away are not given way to (``_give_way``).
ERRATIC_NEAR = 0.5


class SwarmMoveLimits(SwarmAim):
    """The guards applied to every decision (see ``SwarmLocalPlanner.decide``)."""

    _held: Array | None
    _travel: float
    _range: float
    _ray_gap: float
    _threats: tuple[Array, Array, NDArray[np.bool_]]
    _gave: Array | None
    _way_out: Array | None
    _scan: tuple[Array, NDArray[np.bool_]]
    _threat_until: float
    _prior: Array

    def _give_way(self, obs: Observation, decision: Decision) -> Decision:
        """Give way to moving obstacles (``give_way`` seconds ahead; 0: off). The decision's
        move, rolled out with the robot's own drive, is scored against this scan's moving points
        predicted along their sensed velocities (:mod:`swarmpath.planners.give_way`), and, while
        such points were sensed in the last ``memory`` seconds, the points the robot touches (a
        walker that reached the robot is no longer seen moving: its surface is at the body's).
        If it keeps the safety distance from them it is driven unchanged; otherwise the robot
        moves out of their way: of staying and 16 straight moves as far as it can drive within
        the horizon (each as ``_keep_off`` lets it through), the one that keeps the safety
        distance and ends nearest to the decision's target, or, with none, the one that keeps
        the largest gap; never closer to a static point of this scan than the safety distance
        or than the robot is now. Without such a point in reach nothing changes."""
        horizon = float(self.p["give_way"])
        if horizon <= 0 or decision.target is None:
            self._gave = None
            return decision
        points, velocity, steady = self._threats
        scan, moving_now = self._scan
        p = np.array([obs.pose.x, obs.pose.y])
        # an untracked moving point counts within ERRATIC_NEAR of the body only (farther, the
        # robot senses again before a walker gets there; and the static polygons of icoot-map1
        # showed a few such points 0.7-1.5 m away)
        keep = steady | (np.hypot(*(points - p).T) <= obs.robot_radius + ERRATIC_NEAR)
        points, velocity, steady = points[keep], velocity[keep], steady[keep]
        if len(points):
            self._threat_until = obs.time + float(self.p["memory"])
        if obs.time <= self._threat_until and len(scan):
            touch = np.hypot(*(scan - p).T) <= obs.robot_radius + float(self.p["contact_band"])
            away = p - scan[touch].mean(axis=0) if touch.any() else np.zeros(2)
            if np.hypot(*away) > 1e-9:  # the way out should the walker run over the robot
                self._way_out = away / np.hypot(*away)
            points = np.vstack([points, scan[touch]])
            velocity = np.vstack([velocity, np.zeros((int(touch.sum()), 2))])
            steady = np.concatenate([steady, np.ones(int(touch.sum()), dtype=bool)])
        if not len(points):
            self._gave = None
            return decision
        scenario = self.scenario
        dt, speed = scenario.time_step, float(scenario.robot.linear_speed)
        spread = float(self.p["give_way_spread"])
        drive = speed * horizon
        # only points that can come within the safety distance of any move matter
        fast = np.hypot(velocity[:, 0], velocity[:, 1]) * (1.0 + spread) * horizon
        safety = self._safety(obs.time)
        reach = drive + obs.robot_radius + safety
        near = np.hypot(*(points - p).T) <= reach + fast
        if not near.any():
            self._gave = None
            return decision
        steps = max(1, int(np.ceil(horizon / dt - 1e-9)))
        angles = obs.pose.theta + np.arange(16) * (np.pi / 8)
        w, h = obs.world_size
        ends = np.clip(p + drive * np.stack([np.cos(angles), np.sin(angles)], axis=1),
                       [0.0, 0.0], [w, h])
        wanted = np.asarray(decision.target, dtype=float)
        # the way the robot gave way last decision, if it did: kept while it stays safe (a
        # new choice each decision made a diff drive turn back and forth on the spot)
        last = [] if self._gave is None else [np.clip(p + drive * self._gave, 0.0, [w, h]) - p]
        moves = np.vstack([wanted - p, np.zeros(2), *last, ends - p])
        targets = p + (moves if self._engulfed(p) else self._kept(p, moves, obs.robot_radius))
        turn = None if scenario.robot.model == "omni" else float(scenario.robot.angular_speed)
        centres = give_way.rollout(p, obs.pose.theta, targets, speed, turn, dt, steps)
        # an untracked point may move as fast as the fastest one of them sensed this scan (a
        # walker's points show 0.1-0.8 m/s in one scan: its own speed is the largest, and the
        # slowest points' small discs let the robot drive at it: ihpo-map3 ICOOT seed 2)
        velocity = velocity.copy()
        erratic = ~steady
        if erratic.any():
            speeds = np.hypot(velocity[:, 0], velocity[:, 1])
            top = float(speeds[erratic].max())
            scale = top / np.maximum(speeds[erratic], 1e-12)
            velocity[erratic] = np.where(speeds[erratic, None] > 1e-12,
                                         velocity[erratic] * scale[:, None], [top, 0.0])
        gaps = give_way.moving_gaps(centres, dt, points[near], velocity[near], steady[near],
                                    spread, obs.robot_radius)
        still = sensed_map.condense(np.vstack([scan[~moving_now], self._prior]), p, reach,
                                    CONTACT)
        clear = give_way.static_gaps(centres, still, obs.robot_radius)
        now = give_way.static_gaps(p[None, None, :], still, obs.robot_radius)[0]
        pick = give_way.choose(gaps, clear, float(now), safety, centres[:, -1], wanted,
                               prefer=2 if last else None)
        self._gave = None
        if pick == 0:
            return decision
        move = targets[pick] - p
        if np.hypot(*move) > 1e-9:
            self._gave = move / np.hypot(*move)
        self._held = None
        return Decision(targets[pick], decision.iterations, decision.duration, align=True)

    def _kept(self, p: Array, moves: Array, radius: float) -> Array:
        """The parts of ``moves`` (n, 2) that ``_keep_off`` lets through when the robot is not
        engulfed (see there; the callers check :meth:`_engulfed` once per decision)."""
        points, moving = self._scan
        if not len(points):
            return moves
        reach = radius + CONTACT + float(self.p["contact_band"]) * moving.astype(float)
        return np.array([local.keep_off(p, m, points, reach) for m in moves])

    def _engulfed(self, p: Array) -> bool:
        """With ``give_way`` on: the robot's centre is inside an obstacle (a walker ran over it):
        every ray reports the centre, so there is no direction to keep off, and stopping (what
        ``keep_off`` does then) kept the robot under the walker for 20 s (icoot-map4, IHPO seed
        2). The robot drives away from where the points near it were last seen (the walker's
        side), one control step at a time (it is blind)."""
        points = self._scan[0]
        return (float(self.p["give_way"]) > 0 and len(points) > 0
                and bool(np.all(np.hypot(*(points - p).T) <= 1e-9)))

    def _cut(self, obs: Observation, decision: Decision) -> Decision:
        if decision.target is None:
            return decision
        commit = self._commit(obs.time, obs.robot_radius)
        if self._travel <= commit:
            return decision
        p = np.array([obs.pose.x, obs.pose.y])
        move = np.asarray(decision.target, dtype=float) - p
        length = float(np.hypot(*move))
        if length <= commit:
            return decision
        target = p + move * (max(commit, 0.0) / length)
        return Decision(target, decision.iterations, decision.duration, decision.reason,
                        decision.finish)

    def _keep_off(self, obs: Observation, decision: Decision) -> Decision:
        """Never drive toward what the robot touches (:func:`local.keep_off`), whatever the
        swarm, the hold or the fallback chose. The points of this scan within ``CONTACT`` of the
        body (touching) and the points it saw moving within ``contact_band`` more (a moving
        obstacle can close that much while the decision is driven) keep the part of the move
        toward them from being driven: the robot slides along the tangent, moves away or stops,
        and a differential drive turns in place before it drives, so that its path follows the
        kept direction instead of bulging into the obstacle. Without such a point the decision is
        unchanged (runs that come no nearer than that are the same as without the rule)."""
        points, _ = self._scan
        if decision.target is None or not len(points):
            return decision
        p = np.array([obs.pose.x, obs.pose.y])
        if self._engulfed(p):
            out = p if self._way_out is None else p + self._way_out
            return Decision(out, decision.iterations, self.scenario.time_step, align=True)
        move = np.asarray(decision.target, dtype=float) - p
        kept = self._kept(p, move[None, :], obs.robot_radius)[0]
        if np.array_equal(kept, move):
            return decision
        self._held = None
        return Decision(p + kept, decision.iterations, decision.duration, decision.reason,
                        align=True)

    def _commit(self, time: float, radius: float) -> float:
        """How far one decision may move the robot (see ``_travel``): within the sensing range,
        and with coarse steps also where a corner between two rays sticks out by less than the
        safety distance (with fine steps the robot senses again long before that)."""
        safety = self._safety(time)
        commit = self._range - safety
        if self._coarse and self._ray_gap > 0:
            commit = min(commit, 2 * safety / self._ray_gap - radius - safety)
        return max(commit, safety)

