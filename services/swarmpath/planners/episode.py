"""One run of one planner on one scenario: the unit a worker hosts.

``Episode(scenario, planner, seed, run)`` pairs a planner with its own simulator. Run r of seed s
draws the planner's randomness from stream (s, r, OPTIMIZER) and the world's (moving obstacles and
goal) from (s, r, SIMULATION), so the same (scenario, planner, params, seed, run) gives the same
path exactly, on any worker, in any order.

``step()`` asks the planner for one decision and lets the simulator execute it; ``run()`` steps
until the goal is reached or a limit is hit; ``outcome()`` computes the metrics from the executed
trajectory, with collisions checked against the true obstacle positions at every simulated step.
"""

from __future__ import annotations

import math
import time
from collections import OrderedDict
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from swarmpath import metrics, path_metrics
from swarmpath.optimizers.streams import OPTIMIZER, SIMULATION, run_generator
from swarmpath.planners import failures
from swarmpath.planners.base import Planner, get_planner
from swarmpath.planners.cost_to_go import CostToGo
from swarmpath.planners.simulator import Simulator
from swarmpath.world.geometry import collides
from swarmpath.world.optimum import DEFAULT_BUDGET, MAX_DISKS, shortest_path
from swarmpath.world.scenario import Scenario

#: Decisions a run may take at least (:class:`Episode`'s default ``step_limit`` grows with the
#: time limit: one decision per simulated step).
DEFAULT_STEP_LIMIT = 2000
#: A static goal is reached when the robot's centre is this close to it (m): the exact
#: optimum's own tolerance, so no successful path can end short of the goal and be shorter than
#: the optimum (a path ending d from the goal can be up to d shorter).
FINISH_TOLERANCE = 1e-9
#: RunOutcome fields measured on the host (wall and CPU time): the only ones that may differ
#: between two executions of the same run.
TIMING_FIELDS = ("seconds", "cpu_seconds")
#: Time limit: this many times the travel time of the exact optimum (the straight line when the
#: map has none), plus 60 s.
DEFAULT_TIME_FACTOR = 6.0


@dataclass
class RunOutcome:
    planner: str
    map: str
    run: int
    seed: int
    success: bool
    reason: str  # "goal reached", or why the run failed
    collisions: int
    length: float
    error: float
    smoothness: float
    ompl_smoothness: float
    min_clearance: float
    steps: int
    iterations: int
    seconds: float  # planning wall time
    travel_time: float  # simulated seconds
    optimum: float | None
    gap: float | None
    #: Length of the path a global planner planned (None for local planners); ``length`` is
    #: what the robot executed.
    planned_length: float | None = None
    #: ``collisions`` by cause (:func:`swarmpath.metrics.contact_causes`): the robot moved into
    #: the obstacle, or it was still / moving away and a moving obstacle reached it.
    robot_driven_contacts: int = 0
    obstacle_driven_contacts: int = 0
    #: CPU time of the planner's decisions (s; this thread's, :func:`time.thread_time`): beside
    #: the wall time ``seconds``, which other processes' load inflates.
    cpu_seconds: float = 0.0
    #: The field's path metrics (:mod:`swarmpath.path_metrics`, docs/metrics.md): mean body gap
    #: along the path (m), Bench-MR's curvature (1/m) and cusps, MRPB's share of the travel time
    #: within DANGER_DISTANCE of an obstacle, MRPB's velocity smoothness (m/s^2), its angular
    #: counterpart (rad/s^2) and the mean jerk (m/s^3).
    clearance_mean: float | None = None
    curvature_max: float | None = None
    curvature_mean: float | None = None
    cusps: int = 0
    danger_share: float | None = None
    velocity_smoothness: float | None = None
    angular_smoothness: float | None = None
    jerk: float | None = None
    #: nav2's planner-benchmark costs along the path (0-254, nav2's inflation layer; maps
    #: imported from a grid only, else None): mean and largest (:mod:`swarmpath.costmap`).
    costmap_cost_mean: float | None = None
    costmap_cost_max: float | None = None
    #: ``path`` is in the scenario frame (0, 0 = the map's lower-left corner); a map imported
    #: with a frame of its own (nav2: "map") puts the scenario's (0, 0) here in that frame, so
    #: ``map_xy = path_xy + frame_origin`` (None: no other frame).
    frame_origin: list[float] | None = None
    #: Why a failed run failed (:mod:`swarmpath.planners.failures`: a class of
    #: ``FAILURE_CLASSES`` and where / for how long); None for a success.
    failure_class: str | None = None
    failure_detail: str | None = None
    path: list[list[float]] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


_OPTIMA: OrderedDict[tuple[Scenario, float | None], tuple[float | None, str | None]] = (
    OrderedDict()
)
_OPTIMA_KEPT = 16  # scenarios whose optimum this process remembers (equal scenarios share it)


def optimum_of(
    scenario: Scenario,
    budget: float | None = DEFAULT_BUDGET,
    progress: Callable[[float], None] | None = None,
) -> tuple[float | None, str | None]:
    """``(length, None)``: the exact shortest collision-free length of a fully static scenario;
    ``(None, reason)`` when there is none (moving obstacles or goal, no path, start or goal in
    collision, or the time ``budget`` in seconds ran out). Remembered per equal scenario.

    With a ``budget`` the time is the only limit (the pairs are processed in chunks, so memory
    stays bounded): a map of many disks gives up with the budget's reason, which the CLI can
    raise (``--optimum-budget``), not with ``max_disks``, which it cannot. Without a budget
    ``max_disks`` (:data:`swarmpath.world.optimum.MAX_DISKS`) still bounds the search."""
    key = (scenario, budget)
    if key in _OPTIMA:
        _OPTIMA.move_to_end(key)
        return _OPTIMA[key]
    if scenario.is_dynamic:
        return None, "the map has moving obstacles or a moving goal"
    w, h = scenario.size
    value: float | None = None
    try:
        result = shortest_path(
            np.asarray(scenario.start, dtype=float),
            np.asarray(scenario.goal, dtype=float),
            scenario.static_obstacles(),
            scenario.robot.radius,
            world=(0.0, 0.0, float(w), float(h)),
            budget=budget,
            progress=progress,
            max_disks=MAX_DISKS if budget is None else 2**62,
        )
    except ValueError as exc:  # start or goal in collision: the run itself reports it too
        reason: str | None = str(exc)
    else:
        if result.exact and math.isfinite(result.length):
            value, reason = float(result.length), None
        else:
            reason = result.reason or "no collision-free path exists"
    _OPTIMA[key] = (value, reason)
    while len(_OPTIMA) > _OPTIMA_KEPT:
        _OPTIMA.popitem(last=False)
    return value, reason


def scenario_optimum(scenario: Scenario, budget: float | None = DEFAULT_BUDGET) -> float | None:
    """Exact shortest collision-free length for a fully static scenario (None otherwise)."""
    return optimum_of(scenario, budget)[0]


class Episode:
    def __init__(
        self,
        scenario: Scenario,
        planner: str,
        seed: int,
        run: int = 0,
        params: Mapping[str, Any] | None = None,
        step_limit: int | None = None,
        time_limit: float | None = None,
        optimum_budget: float | None = DEFAULT_BUDGET,
    ):
        cls: type[Planner] = get_planner(planner)
        self.optimum_budget = optimum_budget
        self.scenario = scenario
        self.seed = int(seed)
        self.run_index = int(run)
        known = cls.knows_static_map(cls.resolve_params(params))
        static = scenario.static_obstacles() if known else None
        self.planner = cls(scenario, params, run_generator(seed, run, OPTIMIZER), static)
        sensors = scenario.sensors or cls.default_sensors
        self.sim = Simulator(scenario, run_generator(seed, run, SIMULATION), sensors,
                             guard=cls.guarded)
        if time_limit is None:
            # the way to go is the exact optimum where the map has one: on a maze it is many
            # times the straight line (maze512-32-9 #500: 193 m for 120 m)
            way = math.dist(scenario.start, scenario.goal)
            optimum = optimum_of(scenario, optimum_budget)[0]
            if optimum is not None:
                way = max(way, optimum)
            time_limit = DEFAULT_TIME_FACTOR * way / scenario.robot.linear_speed + 60.0
        self.time_limit = float(time_limit)
        if step_limit is None:
            # every decision drives at least one simulated step (a planner that drives none
            # is stopped by this count)
            step_limit = max(DEFAULT_STEP_LIMIT,
                             math.ceil(self.time_limit / scenario.time_step - 1e-9))
        self.step_limit = int(step_limit)
        self._goal_moves = scenario.goal_motion is not None
        self.steps = 0
        self.iterations = 0
        self.planning_seconds = 0.0
        self.planning_cpu_seconds = 0.0
        self.reason: str | None = None

    @property
    def done(self) -> bool:
        return self.reason is not None

    def step(self) -> None:
        if self.done:
            return
        obs = self.sim.observe()
        started, cpu_started = time.perf_counter(), time.thread_time()
        decision = self.planner.decide(obs)
        self.planning_seconds += time.perf_counter() - started
        self.planning_cpu_seconds += time.thread_time() - cpu_started
        self.steps += 1
        self.iterations += decision.iterations
        if decision.target is None:
            self.reason = f"planner gave up: {decision.reason or 'no feasible move'}"
            return
        self.sim.drive(decision.target, decision.duration, self.time_limit, decision.finish,
                       decision.align)
        # A moving goal counts as reached within the tolerance. A static goal only when the
        # robot ends on it (FINISH_TOLERANCE; the papers report errors of ~1 mm): within the
        # tolerance the run drives the last straight stretch itself when that stretch is free
        # now, and otherwise goes on (stopping short of a goal it could not reach is no success,
        # and an executed path shorter than the optimum is impossible).
        if self.sim.reached and not self._goal_moves and not self._on_goal():
            self._final_approach()
        if self.sim.reached and (self._goal_moves or self._on_goal()):
            self.reason = "goal reached"
        elif self.sim.time >= self.time_limit - 1e-9:
            self.reason = f"time limit ({self.time_limit:.0f} s simulated)"
        elif self.steps >= self.step_limit:
            self.reason = f"step limit ({self.step_limit} decisions)"

    def _on_goal(self) -> bool:
        return self.sim.distance_to_goal() <= FINISH_TOLERANCE

    def _final_approach(self) -> None:
        """Drive straight onto a static goal within the tolerance if the segment keeps the robot's
        clearance from every obstacle where it is now (touching counts as a collision), until
        the centre is within FINISH_TOLERANCE of it (the simulator's usual arrival distance,
        0.1 mm, would leave a path up to that much short)."""
        pose = np.array([self.sim.pose.x, self.sim.pose.y])
        goal = np.asarray(self.sim.world.goal, dtype=float)
        obstacles = self.sim.world.obstacles()
        if not obstacles.is_empty:
            clearance = float(obstacles.segment_clearance(pose, goal))
            if collides(clearance, self.sim.radius):
                return
        self.sim.drive(goal, None, self.time_limit, finish=True, align=True,
                       arrive=FINISH_TOLERANCE)

    def _costs(self, path: np.ndarray) -> tuple[float | None, float | None]:
        """nav2's mean and largest costmap cost along the path (maps imported from a grid)."""
        if self.scenario.grid is None:
            return None, None
        from swarmpath.costmap import path_costs, scenario_costmap

        return path_costs(scenario_costmap(self.scenario), path)

    def run(self) -> RunOutcome:
        while not self.done:
            self.step()
        return self.outcome()

    def outcome(self, planner_name: str | None = None) -> RunOutcome:
        path = self.sim.path()
        world = self.sim.world
        gap_body, collisions = metrics.min_clearance(path, world.obstacles_at, self.sim.radius)
        causes = (metrics.contact_causes(path, world.obstacles_at, self.sim.radius)
                  if collisions else metrics.ContactCauses(0, 0))
        length = metrics.path_length(path)
        error = metrics.final_error(path, world.goal_at(float(path[-1, 2])))
        reached = self.reason == "goal reached"
        success = reached and collisions == 0
        reason = self.reason or "not finished"
        if reached and collisions:
            reason = f"collided {collisions} times"
        quality = path_metrics.path_quality(path, world.obstacles_at, self.sim.radius)
        grid = self.scenario.grid
        costs = self._costs(path)
        optimum = scenario_optimum(self.scenario, self.optimum_budget)
        gap = metrics.gap(length, optimum) if (success and optimum) else None
        failure = None if success else self._failure(path, reason, int(collisions))
        return RunOutcome(
            planner=planner_name or self.planner.name,
            map=self.scenario.name,
            run=self.run_index,
            seed=self.seed,
            success=success,
            reason=reason,
            collisions=int(collisions),
            length=float(length),
            error=float(error),
            smoothness=float(metrics.heading_smoothness(path)),
            ompl_smoothness=float(metrics.ompl_smoothness(path)),
            min_clearance=float(gap_body),
            steps=self.steps,
            iterations=self.iterations,
            seconds=self.planning_seconds,
            travel_time=float(path[-1, 2]),
            optimum=optimum,
            gap=gap,
            planned_length=self.planner.planned_length,
            robot_driven_contacts=causes.robot_driven,
            obstacle_driven_contacts=causes.obstacle_driven,
            cpu_seconds=self.planning_cpu_seconds,
            **quality._asdict(),
            costmap_cost_mean=costs[0],
            costmap_cost_max=costs[1],
            frame_origin=None if grid is None else list(grid.origin),
            failure_class=None if failure is None else failure.kind,
            failure_detail=None if failure is None else failure.detail,
            path=np.asarray(path, dtype=np.float64).tolist(),  # rows of Python floats
        )

    def _failure(self, path: np.ndarray, reason: str, collisions: int) -> failures.Failure:
        """The class of this failed run (:func:`swarmpath.planners.failures.classify`)."""
        world, scenario, radius = self.sim.world, self.scenario, self.sim.radius
        to_go: np.ndarray | None = None
        if not self._goal_moves:
            field_ = cost_to_go_of(scenario)
            if field_ is not None:
                to_go = failures.along_free_space(field_(path[:, :2]))
        along = to_go is not None
        if to_go is None:
            goals = (np.array([world.goal_at(float(t)) for t in path[:, 2]]) if self._goal_moves
                     else np.asarray(scenario.goal, dtype=float))
            to_go = np.hypot(*(path[:, :2] - goals).T)
        mover_gap = None
        moving = np.array([scenario.obstacles[k].is_moving for k in world.set_order], dtype=bool)
        if moving.any():
            def mover_gap(t: float, xy: np.ndarray) -> float:
                movers = failures.movers_of(world.obstacles_at(t), moving)
                return float(movers.point_clearance(xy[None, :])[0]) - radius
        end = float(np.hypot(*(path[-1, :2] - world.goal_at(float(path[-1, 2])))))
        return failures.classify(path, reason, collisions, radius, np.asarray(to_go), along,
                                 self._goal_moves, self.sim.goal_tolerance, end, mover_gap)


_FIELDS: OrderedDict[Scenario, CostToGo | None] = OrderedDict()


def cost_to_go_of(scenario: Scenario) -> CostToGo | None:
    """The free-space distance to a static goal on the static map, the robot radius kept
    (remembered for the last few scenarios; None when the goal has no free cell around it)."""
    if scenario in _FIELDS:
        _FIELDS.move_to_end(scenario)
        return _FIELDS[scenario]
    try:
        field_: CostToGo | None = CostToGo(
            scenario.static_obstacles(), scenario.size, np.asarray(scenario.goal, dtype=float),
            scenario.robot.radius)
    except ValueError:
        field_ = None
    _FIELDS[scenario] = field_
    while len(_FIELDS) > _OPTIMA_KEPT:
        _FIELDS.popitem(last=False)
    return field_
