"""OMPL baselines: ``OMPL-RRTstar`` and ``OMPL-BITstar`` (PyPI ``ompl`` 2.x, nanobind bindings).

Global planners: they are handed the static part of the map at construction (moving obstacles are
not known to them and the goal is the one observed at the first decision). The problem they solve:

* state space: ``RealVectorStateSpace(2)`` bounded by the world ``[0, w] x [0, h]`` - the robot's
  centre, planned in R^2 (the product's robots turn in place or are omnidirectional);
* state validity: clearance of the centre to every static obstacle ``> robot radius + margin``,
  i.e. obstacles inflated by the robot radius plus a small ``margin`` (the product's collision rule
  counts touching as a collision, so the margin keeps the planned path strictly clear of it; it is
  reduced automatically when the start or the goal is closer than that to an obstacle);
* motion validity: ``motion_check="exact"`` (default) tests each edge with exact segment distances
  (same formulas as :class:`~swarmpath.world.geometry.ObstacleSet`, in plain Python with bounding
  box filtering); ``"discrete"`` is OMPL's own discrete motion validator, which samples the edge
  every ``resolution`` metres (expressed to OMPL as a fraction of the world's extent);
* objective: ``PathLengthOptimizationObjective``; planners ``og.RRTstar`` / ``og.BITstar`` with
  OMPL's default settings;
* termination (``budget``): ``"iterations"`` (default) stops after exactly ``iterations`` planner
  iterations (a ``PlannerTerminationCondition`` on a Python counter: OMPL 2.0.1 has no iteration
  condition of its own), the same on any machine and under any load; ``"cpu"`` after ``time``
  seconds of this thread's CPU time (independent of other processes' load, not of the machine's
  speed); ``"wall"`` after ``time`` seconds of wall clock (the issue's original 1 s; depends on
  the load);
* ``simplify``: what OMPL's ``PathSimplifier`` does to the found path. ``"shortcut"`` (default):
  ``reduceVertices`` and ``collapseCloseVertices`` until nothing changes (at most 5 rounds), which
  drops redundant vertices and keeps straight segments; ``"max"``: ``simplifyMax`` (also shortcuts
  inside segments and smooths with B-splines, adding many short segments); ``"none"``: the
  planner's raw path. The default is not ``"none"`` because BIT*'s raw paths carry many nearly
  collinear vertices a few centimetres apart, around which the differential-drive waypoint
  controller loops (measured on icoot-map1/2 and ihpo-map1: executed paths up to 1.8 m longer,
  collisions in 6 of 9 runs; none with ``"shortcut"``). Simplifying counts in the planning time.

Only an exact solution is used (an approximate one is a failure with its distance to the goal).
Every segment of the returned path is then re-checked exactly with
:meth:`ObstacleSet.segment_clearance` against ``robot radius`` (the product's collision rule); a
path that fails is reported as a failure with the reason, never handed to the robot.

Reproducibility (what OMPL allows)
----------------------------------
OMPL draws every random number from ``ompl::RNG`` instances that are seeded, when they are
created, from one process-wide seed generator. ``RNG.setSeed`` is meant to be called once before
the first draw; called later it logs "Random number generation already started" but, in OMPL
2.0.1 as in 1.x, it still re-seeds that generator (checked: the same seed before a plan gives the
same samples, in any order, in a fresh process or after other plans). Before each plan this
module therefore re-seeds OMPL's generator with a seed drawn from the planner's own stream (seed,
run), with OMPL's logging silenced around the call. Consequences:

* ``budget = "iterations"`` (the default): same (scenario, params, seed, run) -> same path,
  exactly, in any process and order, on a loaded or a quiet machine;
* ``budget = "cpu"`` or ``"wall"``: the *sampling sequence* is seeded, but how far the planner
  gets in ``time`` seconds depends on the machine (and, for wall clock, on its load), so paths
  are not reproducible run by run;
* the generator is process-wide state: two OMPL plans must not run concurrently in threads of one
  process (the worker hosts one planner at a time).

At interpreter exit the nanobind bindings print "leaked instance" warnings for OMPL objects that
are still alive. Every OMPL object of a plan lives in one function frame and forms no reference
cycle (checked with the garbage collector disabled), so it is freed when the plan returns (the
path is copied into numpy) and nothing is left to report.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from swarmpath.planners.base import Decision, Observation, Planner, PlannerError, register
from swarmpath.planners.ompl_checks import FastChecker
from swarmpath.world.geometry import ObstacleSet, collides

try:  # a hard dependency; planning reports the problem instead of breaking the registry
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    OMPL_IMPORT_ERROR: str | None = None
except ImportError as _exc:  # pragma: no cover - depends on the installation
    ob = og = ou = None
    OMPL_IMPORT_ERROR = f"the ompl package is not available ({_exc})"

Array = NDArray[np.float64]
OMPL_REFERENCE = (
    "OMPL 2.0 (Sucan, Moll & Kavraki, IEEE RAM 2012); RRT* (Karaman & Frazzoli, IJRR 2011); "
    "BIT* (Gammell, Barfoot & Srinivasa, IJRR 2020)"
)
MAX_TIME = 600.0  # s: the largest accepted budget
MAX_ITERATIONS = 10_000_000
#: What ends a plan: an iteration count (the default: the same on any machine), CPU time of the
#: planning thread, or wall clock.
BUDGETS = ("iterations", "cpu", "wall")


# ----------------------------------------------------------------------------------- planning
@dataclass
class PlanResult:
    path: Array | None  # (n, 2) start .. goal, exactly re-checked; None on failure
    reason: str | None  # why path is None
    iterations: int  # planner iterations (OMPL's numIterations)
    status: str  # OMPL's planner status
    seconds: float  # wall time of the whole plan (setup, solve, simplify, re-check)
    min_clearance: float  # exact clearance of the path's centre line (inf without obstacles)


def ompl_seed(rng: np.random.Generator) -> int:
    """The OMPL seed of a plan, drawn from the planner's own stream (OMPL rejects 0)."""
    return int(rng.integers(1, 2**31 - 1))


def _seed_ompl(seed: int) -> None:
    level = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_NONE)  # "random number generation already started": expected
    try:
        ou.RNG.setSeed(int(seed))
    finally:
        ou.setLogLevel(level)


def plan_path(
    algorithm: str,
    obstacles: ObstacleSet,
    start: Array,
    goal: Array,
    radius: float,
    world: tuple[float, float],
    params: Mapping[str, Any],
    seed: int,
) -> PlanResult:
    """One OMPL plan from ``start`` to ``goal`` for a disk robot of ``radius`` (pure, no robot).

    ``algorithm`` is ``"RRTstar"`` or ``"BITstar"``; ``params`` as the planners' ``defaults``.
    """
    started = time.perf_counter()

    def fail(reason: str, iterations: int = 0, status: str = "not run") -> PlanResult:
        return PlanResult(None, reason, iterations, status, time.perf_counter() - started,
                          math.nan)

    if OMPL_IMPORT_ERROR is not None:
        return fail(OMPL_IMPORT_ERROR)
    start = np.asarray(start, dtype=float)
    goal = np.asarray(goal, dtype=float)
    w, h = float(world[0]), float(world[1])
    for label, p in (("start", start), ("goal", goal)):
        if not (0.0 <= p[0] <= w and 0.0 <= p[1] <= h):
            return fail(f"{label} ({p[0]:g}, {p[1]:g}) is outside the world")
    ends = obstacles.point_clearance(np.stack([start, goal]))
    for label, c in zip(("start", "goal"), ends, strict=True):
        if collides(c, radius):
            return fail(f"{label} is inside an obstacle inflated by the robot radius "
                        f"(clearance {c:.3f} m <= {radius:g} m)")
    # Keep the margin, unless the start or goal is closer than that to an obstacle.
    margin = min(float(params["margin"]), 0.5 * (float(ends.min()) - radius))
    checker = FastChecker(obstacles, radius + margin)
    for label, p, c in zip(("start", "goal"), (start, goal), ends, strict=True):
        if not checker.point_ok(float(p[0]), float(p[1])):
            # only when the clearance beyond the radius is lost in round-off (e.g. 1e-17 m)
            return fail(
                f"{label} ({p[0]:g}, {p[1]:g}) is not a valid state for the planner: its "
                f"clearance {c:.6g} m leaves {c - radius:.3g} m beyond the robot radius "
                f"{radius:g} m, too little for a state strictly clear of the obstacles; move "
                f"the {label} away from the obstacle"
            )

    _seed_ompl(seed)
    level = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_NONE)  # failures are reported through the result, not OMPL's log
    try:
        raw, iterations, status = _solve(algorithm, checker, start, goal, (w, h), params)
    finally:
        ou.setLogLevel(level)
    if raw is None:
        return fail(status, iterations, status)
    # The path is used only if every segment passes the product's own exact check.
    clear = obstacles.segment_clearance(raw[:-1], raw[1:]) if len(raw) > 1 else np.array([])
    bad = np.flatnonzero(collides(clear, radius))
    if bad.size:
        i = int(bad[0])
        return fail(
            f"OMPL path rejected by the exact re-check: segment {i} "
            f"({raw[i, 0]:.3f}, {raw[i, 1]:.3f}) -> ({raw[i + 1, 0]:.3f}, {raw[i + 1, 1]:.3f}) "
            f"has clearance {clear[i]:.4f} m <= robot radius {radius:g} m",
            iterations, status,
        )
    min_clear = float(clear.min()) if clear.size else math.inf
    return PlanResult(raw, None, iterations, status, time.perf_counter() - started, min_clear)


def _solve(
    algorithm: str,
    checker: FastChecker,
    start: Array,
    goal: Array,
    world: tuple[float, float],
    params: Mapping[str, Any],
) -> tuple[Array | None, int, str]:
    """Set up and run OMPL; return (path or None, iterations, status or failure reason).

    Every OMPL object lives in this frame only (freed on return: no nanobind leak report).
    """
    space = ob.RealVectorStateSpace(2)
    bounds = ob.RealVectorBounds(2)
    bounds.setLow(0, 0.0)
    bounds.setLow(1, 0.0)
    bounds.setHigh(0, world[0])
    bounds.setHigh(1, world[1])
    space.setBounds(bounds)
    si = ob.SpaceInformation(space)
    point_ok = checker.point_ok
    si.setStateValidityChecker(lambda s: point_ok(s[0], s[1]))
    if params["motion_check"] == "exact":
        si.setMotionValidator(_ExactMotionValidator(si, checker))
    else:
        extent = math.hypot(world[0], world[1])
        si.setStateValidityCheckingResolution(min(1.0, float(params["resolution"]) / extent))
    si.setup()
    ss = og.SimpleSetup(si)
    s0 = si.allocState()
    s0[0], s0[1] = float(start[0]), float(start[1])
    s1 = si.allocState()
    s1[0], s1[1] = float(goal[0]), float(goal[1])
    ss.setStartAndGoalStates(s0, s1)
    objective = ob.PathLengthOptimizationObjective(si)
    ss.setOptimizationObjective(objective)
    planner = og.RRTstar(si) if algorithm == "RRTstar" else og.BITstar(si)
    ss.setPlanner(planner)
    ss.setup()

    if params["budget"] == "iterations":
        ptc = ob.PlannerTerminationCondition(_IterationBudget(int(params["iterations"])))
    elif params["budget"] == "cpu":
        ptc = ob.PlannerTerminationCondition(_CpuBudget(float(params["time"])))
    else:
        ptc = ob.timedPlannerTerminationCondition(float(params["time"]))
    status = ss.solve(ptc)
    name = status.asString()
    iterations = int(planner.numIterations())
    if not ss.haveSolutionPath():
        return None, iterations, _no_path_reason(name, iterations, params)
    path = ss.getSolutionPath()
    if not ss.haveExactSolutionPath():
        last = path.getState(path.getStateCount() - 1)
        gap = math.hypot(last[0] - goal[0], last[1] - goal[1])
        return None, iterations, (
            f"no path to the goal found within {budget_text(params)} ({iterations} iterations "
            f"done; the best approximate path ends {gap:.2f} m from it)"
        )
    mode = params["simplify"]
    if mode != "none":
        simplifier = og.PathSimplifier(si, ss.getGoal(), objective)
        if mode == "max":
            simplifier.simplifyMax(path)
        else:  # "shortcut": fewer vertices, segments stay straight (no B-spline smoothing)
            for _ in range(5):
                changed = simplifier.reduceVertices(path)
                changed = simplifier.collapseCloseVertices(path) or changed
                if not changed:
                    break
    raw = np.array([[s[0], s[1]] for s in path.getStates()], dtype=float)
    raw[0], raw[-1] = start, goal  # exact ends (OMPL stores the same doubles)
    return raw, iterations, name


def _no_path_reason(status: str, iterations: int, params: Mapping[str, Any]) -> str:
    """Why OMPL returned no path, in words (OMPL's status alone said "Timeout, 0 iterations"
    for a start it considered invalid)."""
    limit = budget_text(params)
    if status == "Invalid start":
        return (f"no path found: OMPL rejected the start state (clearance within the planner's "
                f"margin {float(params['margin']):g} m of the inflated obstacles)")
    if status == "Invalid goal":
        return (f"no path found: OMPL rejected the goal state (clearance within the planner's "
                f"margin {float(params['margin']):g} m of the inflated obstacles)")
    if status == "Timeout":
        return (f"no path found within {limit} ({iterations} iterations done); a larger budget "
                "may find one, or the goal is unreachable at this clearance")
    return f"no path found (OMPL status {status!r}, {iterations} iterations done)"


def budget_text(params: Mapping[str, Any]) -> str:
    """The plan's budget in words ("10000 iterations", "1 s of CPU time", "1 s of wall clock")."""
    if params["budget"] == "iterations":
        return f"{int(params['iterations'])} iterations"
    clock = "CPU time" if params["budget"] == "cpu" else "wall clock"
    return f"the budget of {float(params['time']):g} s of {clock}"


class _CpuBudget:
    """Termination after ``seconds`` of the calling thread's CPU time (OMPL evaluates the
    condition in the planning thread; other processes' load does not count)."""

    def __init__(self, seconds: float):
        self.end = time.thread_time() + seconds

    def __call__(self) -> bool:
        return time.thread_time() >= self.end


class _IterationBudget:
    """Termination after ``n`` evaluations: the planners evaluate the condition once per
    iteration, so this is an iteration budget (RRTstar.numIterations() == n afterwards)."""

    def __init__(self, n: int):
        self.n = n
        self.count = 0

    def __call__(self) -> bool:
        self.count += 1
        return self.count > self.n


if ob is not None:

    class _ExactMotionValidator(ob.MotionValidator):
        """Exact edge test (the planners call only the two-state form)."""

        def __init__(self, si: Any, checker: FastChecker):
            super().__init__(si)
            self._segment_ok = checker.segment_ok

        def checkMotion(self, a: Any, b: Any) -> bool:  # OMPL's method name
            return self._segment_ok(a[0], a[1], b[0], b[1])


# ----------------------------------------------------------------------------------- planners
class OmplPlanner(Planner):
    """Plans the whole path with OMPL at the first decision, then hands out its waypoints."""

    name = "ompl"
    kind = "global"
    reference = OMPL_REFERENCE
    algorithm: ClassVar[str] = "RRTstar"
    defaults: ClassVar[dict[str, Any]] = {
        "budget": "iterations",  # what stops the planner: iterations, cpu or wall (time)
        "iterations": 10_000,  # planner iterations (budget "iterations"; deterministic)
        "time": 1.0,  # s of CPU time or wall clock (budget "cpu" / "wall")
        "margin": 0.02,  # m of clearance kept beyond the robot radius
        "motion_check": "exact",
        "resolution": 0.01,  # m between checked states (motion_check = "discrete")
        "simplify": "shortcut",
    }
    choices: ClassVar[dict[str, tuple[str, ...]]] = {
        "budget": BUDGETS,
        "motion_check": ("exact", "discrete"),
        "simplify": ("none", "shortcut", "max"),
    }

    @classmethod
    def resolve_params(cls, params):
        """The planner's parameters; ``time`` and ``iterations`` are refused where the budget
        does not use them (a silently ignored budget would mislead a study)."""
        merged = super().resolve_params(params)
        given = dict(params or {})
        budget = merged["budget"]
        if "time" in given and budget == "iterations":
            raise PlannerError(
                f"{cls.name}.time applies to budget 'cpu' or 'wall' only; the budget is "
                f"'iterations' ({int(merged['iterations'])}): add \"budget\": \"cpu\" (CPU "
                "seconds, independent of the load) or \"wall\" (wall clock), or give "
                "iterations")
        if "iterations" in given and budget != "iterations":
            raise PlannerError(f"{cls.name}.iterations applies to budget 'iterations' only; "
                               f"the budget is {budget!r} (time {float(merged['time']):g} s)")
        return merged

    @classmethod
    def check_params(cls, p):
        if not 0.0 < float(p["time"]) <= MAX_TIME:
            raise PlannerError(f"{cls.name}.time must be in (0, {MAX_TIME:g}] seconds")
        if not 1 <= int(p["iterations"]) <= MAX_ITERATIONS:
            raise PlannerError(f"{cls.name}.iterations must be in [1, {MAX_ITERATIONS}]")
        if float(p["margin"]) < 0.0:
            raise PlannerError(f"{cls.name}.margin must be >= 0")
        if not float(p["resolution"]) > 0.0:
            raise PlannerError(f"{cls.name}.resolution must be > 0")

    def __init__(self, scenario, params, rng, static_map=None):
        super().__init__(scenario, params, rng, static_map)
        self.result: PlanResult | None = None
        self.path: Array | None = None  # the planned path, start to goal
        self._next = 1

    @property
    def path_length(self) -> float | None:
        if self.path is None:
            return None
        return float(np.sum(np.hypot(*np.diff(self.path, axis=0).T)))

    @property
    def planned_length(self) -> float | None:
        return self.path_length

    def plan(self, start: Array, goal: Array, radius: float) -> PlanResult:
        obstacles = self.static_map if self.static_map is not None else ObstacleSet.empty()
        return plan_path(self.algorithm, obstacles, start, goal, radius, self.scenario.size,
                         self.p, ompl_seed(self.rng))

    def decide(self, obs: Observation) -> Decision:
        if self.result is None:
            start = np.array([obs.pose.x, obs.pose.y])
            self.result = self.plan(start, np.asarray(obs.goal, dtype=float), obs.robot_radius)
            self.path = self.result.path
            if self.path is None:
                return Decision(None, self.result.iterations, None,
                                f"{self.name}: {self.result.reason}")
            return self._waypoint(self.result.iterations)
        if self.path is None:
            return Decision(None, 0, None, f"{self.name}: {self.result.reason}")
        return self._waypoint(0)

    def _waypoint(self, iterations: int) -> Decision:
        assert self.path is not None
        if self._next >= len(self.path):
            return Decision(None, iterations, None,
                            f"{self.name}: path exhausted before the goal was reached (the "
                            "goal moved: the OMPL baselines plan once, to the goal at t = 0)")
        target = self.path[self._next].copy()
        self._next += 1
        # The last waypoint is the goal: drive onto it rather than stop at the goal tolerance.
        # align: turn in place at each vertex, then drive the checked segment straight.
        return Decision(target, iterations, None, finish=self._next == len(self.path),
                        align=True)


def _baseline(name: str, algorithm: str, iterations: int,
              description: str) -> type[OmplPlanner]:
    cls = type(name.replace("-", "_") + "Planner", (OmplPlanner,), {
        "name": name,
        "algorithm": algorithm,
        "description": description,
        "defaults": {**OmplPlanner.defaults, "iterations": iterations},
    })
    return register(cls)  # type: ignore[return-value]


_STATIC = ("given the static map (obstacles inflated by the robot radius), planned once in R^2 "
           "with a path-length objective; an iteration budget by default (the same result on "
           "any machine), every segment re-checked exactly")
#: Default iteration budgets: about what one second of wall clock gave on a quiet machine on the
#: papers' maps (docs/planners.md, "Budgets"), now the same on every machine.
RRTSTAR_ITERATIONS = 10_000
BITSTAR_ITERATIONS = 50_000
_baseline("OMPL-RRTstar", "RRTstar", RRTSTAR_ITERATIONS, f"OMPL RRT* baseline: {_STATIC}")
_baseline("OMPL-BITstar", "BITstar", BITSTAR_ITERATIONS, f"OMPL BIT* baseline: {_STATIC}")
