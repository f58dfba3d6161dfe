"""How far one decision of the swarm local planner may move the robot, and toward what not.

:class:`SwarmMoveLimits` is a base of :class:`~swarmpath.planners.swarm_local.SwarmLocalPlanner`:
a move is cut to what the sensors covered (:meth:`_cut`, :meth:`_commit`) and never closes on
what the robot touches (:meth:`_keep_off`); the planner's ``__init__`` sets the state below.
"""

from __future__ import annotations

import numpy as np

from swarmpath.planners import local
from swarmpath.planners.base import Decision, Observation
from swarmpath.planners.swarm_aim import SwarmAim
from swarmpath.planners.swarm_sensing import Array

#: m beyond the body: a sensed point this near is touching (rays hit the surface exactly; the
#: planner keeps at least 1 cm from every hit, so a run without contact never comes this near).
CONTACT = 0.002


class SwarmMoveLimits(SwarmAim):
    """The guards applied to every decision (see ``SwarmLocalPlanner.decide``)."""

    _held: Array | None
    _travel: float
    _range: float
    _ray_gap: float


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
        points, moving = self._scan
        if decision.target is None or not len(points):
            return decision
        p = np.array([obs.pose.x, obs.pose.y])
        move = np.asarray(decision.target, dtype=float) - p
        reach = obs.robot_radius + CONTACT + float(self.p["contact_band"]) * moving.astype(float)
        kept = local.keep_off(p, move, points, reach)
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

