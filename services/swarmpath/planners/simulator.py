"""The simulator owns the truth: world motion, robot kinematics, sensors and the trajectory.

It advances in fixed steps of the scenario's ``time_step``. Each step moves the obstacles and the
goal (the world), drives the robot toward the current target through its kinematic model and
records the pose. Collisions are checked against the recorded trajectory and the obstacle positions
at every step (see :func:`swarmpath.metrics.min_clearance`), never taken from the planner.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from swarmpath.planners.base import Observation
from swarmpath.robot.kinematics import (
    ARRIVE,
    DiffDrive,
    Omni,
    Pose,
    aligned_drive_command,
    diff_drive_command,
    omni_command,
)
from swarmpath.robot.sensors import SensorModel, get_sensor_model, read_sensors_in
from swarmpath.world.clearance import segment_clearance
from swarmpath.world.geometry import ObstacleSet, collides
from swarmpath.world.scenario import RobotSpec, Scenario, WorldState

Array = NDArray[np.float64]
GOAL_TOLERANCE = 0.2  # m: the papers' acceptance error
#: Bisection rounds of :meth:`Simulator._guarded` (the kept fraction is exact to 2**-30 of a step).
GUARD_ROUNDS = 30


def robot_model(spec: RobotSpec) -> DiffDrive | Omni:
    if spec.model == "omni":
        return Omni(max_linear=spec.linear_speed, max_angular=spec.angular_speed)
    if spec.wheel_radius is None or spec.wheel_separation is None:
        raise ValueError("a diff-drive robot needs wheel_radius and wheel_separation")
    return DiffDrive(
        wheel_radius=spec.wheel_radius,
        wheel_separation=spec.wheel_separation,
        max_linear=spec.linear_speed,
        max_angular=spec.angular_speed,
    )


class Simulator:
    def __init__(
        self,
        scenario: Scenario,
        rng: np.random.Generator,
        sensors: str | None,
        goal_tolerance: float = GOAL_TOLERANCE,
        guard: bool = False,
    ):
        self.scenario = scenario
        self.world: WorldState = scenario.instantiate(rng)
        self.model = robot_model(scenario.robot)
        self.radius = scenario.robot.radius
        self.dt = scenario.time_step
        self.sensor_model: SensorModel | None = get_sensor_model(sensors) if sensors else None
        self.goal_tolerance = goal_tolerance
        sx, sy = scenario.start
        self.pose = Pose(float(sx), float(sy), 0.0)  # initial orientation 0, as in the ICOOT paper
        self.trajectory: list[tuple[float, float, float]] = [(self.pose.x, self.pose.y, 0.0)]
        static = scenario.static_obstacles() if guard else None
        #: The static obstacles the motion guard keeps the body off (None: no guard).
        self.guard: ObstacleSet | None = None if static is None or static.is_empty else static

    @property
    def time(self) -> float:
        return self.world.time

    def distance_to_goal(self) -> float:
        g = self.world.goal
        return math.hypot(g[0] - self.pose.x, g[1] - self.pose.y)

    @property
    def reached(self) -> bool:
        return self.distance_to_goal() <= self.goal_tolerance

    def observe(self) -> Observation:
        reading = None
        if self.sensor_model is not None:
            reading = read_sensors_in(
                self.sensor_model, self.pose.x, self.pose.y, self.pose.theta, self.radius,
                self.world.obstacles(),
            )
        return Observation(
            time=self.time,
            pose=self.pose,
            goal=self.world.goal.copy(),
            reading=reading,
            robot_radius=self.radius,
            world_size=self.scenario.size,
        )

    def drive(
        self,
        target: Array,
        duration: float | None,
        time_limit: float,
        finish: bool = False,
        align: bool = False,
        arrive: float = ARRIVE,
    ) -> None:
        """Drive toward ``target`` for ``duration`` seconds (the robot waits there if it arrives
        early: the world keeps moving), or until it arrives when ``duration`` is None; stop early
        when the goal is reached (unless ``finish``: the target is the goal, drive onto it) or at
        the episode's ``time_limit``. ``align``: a differential drive turns in place until it
        faces the target and then drives straight (:func:`aligned_drive_command`). The robot has
        arrived within ``arrive`` metres of the target (the episode's final approach asks for
        the goal itself)."""
        end = time_limit if duration is None else min(time_limit, self.time + duration)
        tx, ty = float(target[0]), float(target[1])
        while self.time < end - 1e-12:
            arrived = math.hypot(tx - self.pose.x, ty - self.pose.y) < arrive
            if arrived and duration is None:
                break
            if arrived:
                pass  # wait in place
            elif isinstance(self.model, Omni):
                vx, vy, w = omni_command(self.model, self.pose, (tx, ty), self.dt)
                self.pose = self._guarded(self.model.advance(self.pose, vx, vy, w, self.dt))
            else:
                if align:
                    v, w = aligned_drive_command(self.model, self.pose, (tx, ty), self.dt,
                                                 arrive=arrive)
                else:
                    v, w = diff_drive_command(self.model, self.pose, (tx, ty), self.dt,
                                              arrive=arrive)
                self.pose = self._guarded(self.model.advance(self.pose, v, w, self.dt))
            self.world.advance(self.dt)
            self.trajectory.append((self.pose.x, self.pose.y, self.time))
            if self.reached and not finish:
                break

    def _guarded(self, new: Pose) -> Pose:
        """The motion guard: a step whose swept body (the segment from the current centre to
        ``new``'s, as the collision check sees it) would touch a static obstacle is cut to the
        largest safe fraction of its displacement, found by bisection; the heading still turns
        (the body is a disk, turning sweeps nothing). From a pose already touching (a start
        without clearance), only a step that ends farther from the obstacles is driven. Moving
        obstacles are left to the planner."""
        if self.guard is None:
            return new
        a = np.array([self.pose.x, self.pose.y])
        b = np.array([new.x, new.y])
        if not collides(segment_clearance(self.guard, a, b), self.radius):
            return new
        here, there = self.guard.point_clearance(np.stack([a, b]))
        if collides(here, self.radius):
            return new if there > here else Pose(self.pose.x, self.pose.y, new.theta)
        lo, hi = 0.0, 1.0
        for _ in range(GUARD_ROUNDS):
            mid = 0.5 * (lo + hi)
            if collides(segment_clearance(self.guard, a, a + mid * (b - a)), self.radius):
                hi = mid
            else:
                lo = mid
        kept = a + lo * (b - a)
        return Pose(float(kept[0]), float(kept[1]), new.theta)

    def path(self) -> Array:
        """Executed trajectory rows [x, y, t]."""
        return np.asarray(self.trajectory, dtype=float)
