"""RFO, RFO-GWO and RFO-GWO-EA: the global planners of Ketafa & Al-Darraji (2024).

Ketafa & Al-Darraji, "Path Planning for Autonomous Mobile Robots Using the RFO-GWO Optimization
Algorithm", Iraqi J. Science 65(2) (2024) 1070-1088, doi 10.24996/ijs.2024.65.2.38: section 3.1
(RFO, eqs 1-2), 3.2 (GWO, eqs 3-16), 4.1 (the hybrid, eq 17, Algorithms 1 and 2), 4.2 (the EA
with the Erase mutation and the multiphase refinement), 5 (Table 1 parameters, Table 2 metrics).
docs/planners.md has the measurements next to Table 2.

Global planners: the static map is given at construction; the first ``decide`` plans the whole
path (its wall time is the episode's planning time) and returns the first waypoint with
``iterations`` = the paper's *cost* (RFO iterations consumed, Table 2); later calls hand out the
remaining waypoints one by one (``duration=None``: drive until reached). The paper's *nodes* are
the waypoints after the start, i.e. the episode's ``steps``. A failed search returns
``Decision(None, reason=...)`` with the iterations it consumed; nothing raises.

Phase A (Algorithm 1, the clearance rules): :mod:`swarmpath.planners.rfo_search`; phase B/C
(section 4.2, ``RFO-GWO-EA`` only): :mod:`swarmpath.planners.rfo_refine`; following the path
among moving obstacles and a moving goal: :mod:`swarmpath.planners.rfo_follow`. Their module
docstrings describe each.

Deviations, all parameters
--------------------------
``foxes`` = 15 (section 5's text; Table 1 says 10), ``iterations`` = 2000 (Table 1),
``radius`` = 3 m (Table 1's r in [0, 3]), ``wolves`` = 7 (Table 1, also the node optimisation's
population). ``gwo_iterations`` = 10 (also for the node optimisation),
not Table 1's 500: 500 iterations per blocked fox per iteration costs about 50 times the planning
time and measured no better (the box is small and 2-D). ``patience`` (RFO-GWO variants: 50,
RFO: off) ends a search after that many iterations in which the best fox got no closer than
before by ``STALL_TOLERANCE`` (1 cm): in successful runs RFO-GWO never stalled for more than one
iteration, and a trapped search would otherwise call GWO for all 2000 iterations. EA:
``ea_population`` = 10, ``ea_generations`` = 50, ``split_length`` = 2 m capped at
``split_scale`` (0.025) times the larger world side (2 m on 170 m maps, 0.25 m on 10 m maps),
``phases`` = 4 (the paper gives none of them); ``arrivals``, the node optimisation and the
scale-aware safety margin are ours (docs/planners.md has the measurements). Randomness comes only
from the planner's generator: the same seed gives the same path.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from swarmpath.planners.base import (
    Decision,
    Observation,
    ParamValue,
    PlannerError,
    register,
)
from swarmpath.planners.rfo_follow import RfoFollow
from swarmpath.planners.rfo_geometry import _Clearance, path_length
from swarmpath.world.geometry import (
    ObstacleSet,
    collides,
)
from swarmpath.world.scenario import Scenario

Array = NDArray[np.float64]
REFERENCE = (
    "Ketafa & Al-Darraji, Iraqi J. Science 65(2) 2024 1070-1088, doi 10.24996/ijs.2024.65.2.38, "
    "sections 3-4, eqs 1-17, Algorithms 1-2, Tables 1-2"
)




# ------------------------------------------------------------------------------------ planners
class RfoFamilyPlanner(RfoFollow):
    """Shared machinery of the three planners; the registered subclasses fix the stages."""

    name = "rfo-family"
    kind = "global"
    reference = REFERENCE
    #: Run section 4.2 (EA with the Erase mutation, multiphase refinement) on the found path.
    smooth: ClassVar[bool] = False

    defaults: ClassVar[dict[str, Any]] = {
        "foxes": 15,  # section 5: fifteen individuals (Table 1 says N = 10)
        "iterations": 2000,  # Table 1: t = 2000
        "radius": 3.0,  # m, Table 1: r in [0, 3] (neighbourhood of the start, wolves, local moves)
        "alpha_bound": "sqrt",
        "alpha_draw": "fox",
        "reference": "target",
        "node_margin": 1.0,  # m beyond the robot radius: section 4.1's one-metre rule (eq 2 nodes)
        "node_scale": 0.02,  # node rule capped at this fraction of the larger world side
        "safety_margin": 0.2,  # m beyond the robot radius: section 4.1's 20 cm rule (the rest)
        "safety_scale": 0.01,  # safety rule capped at this fraction of the larger world side
        "patience": 0,  # stop after this many iterations without progress (0: never)
        "goal_snap": 0.2,  # m: a fox this close to the target with a free segment steps onto it
        "arrivals": 1,  # foxes that must reach the target before the search ends
        "arrival_wait": 1.0,  # then at most this many times the first fox's iterations more
        # "closer to the target": eq 17's straight line, the way along free space, or the
        # straight line first and the way along free space when that search stalls
        "progress": "auto",
        "progress_cells": 300,  # grid cells along the longer side for the way along free space
        # following the path with sensors (moving obstacles)
        "watch": 3.0,  # m: sensed points farther than this from the robot are ignored
        "dynamic_margin": 0.3,  # m beyond the robot radius kept from sensed points
        "predict": 1.0,  # s: horizon over which moving sensed points are extrapolated (0: off)
        "replan": 0.25,  # s: decision length while moving obstacles are sensed
        "side_step": 0.3,  # m: length of a step aside
    }
    choices: ClassVar[dict[str, tuple[str, ...]]] = {
        "alpha_bound": ("sqrt", "distance"),
        "alpha_draw": ("fox", "population"),
        "reference": ("target", "best"),
        "node_opt": ("gwo", "off"),
        "progress": ("auto", "euclidean", "geodesic"),
    }

    @classmethod
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        for key in ("foxes", "iterations", "wolves", "gwo_iterations", "ea_population",
                    "ea_generations", "arrivals", "progress_cells"):
            if key in p and int(p[key]) < 1:
                raise PlannerError(f"{cls.name}.{key} must be >= 1")
        for key in ("radius", "split_length", "watch", "replan", "side_step", "relax_box"):
            if key in p and not float(p[key]) > 0:
                raise PlannerError(f"{cls.name}.{key} must be > 0")
        for key in ("node_margin", "node_scale", "split_scale", "safety_margin", "safety_scale",
                    "goal_snap", "phases", "dynamic_margin", "predict", "refine_tol",
                    "relax_sweeps", "arrival_wait"):
            if key in p and float(p[key]) < 0:
                raise PlannerError(f"{cls.name}.{key} must be >= 0")
        if "notice" in p and not 0.0 <= float(p["notice"]) <= 1.0:
            raise PlannerError(f"{cls.name}.notice must be in [0, 1]")
        if float(p["safety_margin"]) > float(p["node_margin"]):
            raise PlannerError(f"{cls.name}.safety_margin must not exceed node_margin")

    def __init__(
        self,
        scenario: Scenario,
        params: Mapping[str, Any] | None,
        rng: np.random.Generator,
        static_map: ObstacleSet | None = None,
    ):
        super().__init__(scenario, params, rng, static_map)
        self._waypoints: Array | None = None
        self._next = 0
        self._cost = 0
        self._failure: str | None = None
        self.raw_path: Array | None = None  # phase A's path (before any smoothing)
        self.raw_paths: list[Array] = []  # every fox's path to the target (``arrivals``)
        self.path: Array | None = None  # the path handed out, start included
        self.trace: list[float] = []  # distance of the best fox to the target, per iteration
        self._static = static_map if static_map is not None else scenario.static_obstacles()
        self._last_scan: tuple[float, Array] | None = None
        self._moving = any(o.is_moving for o in scenario.obstacles)

    # --------------------------------------------------------------------------- contract
    def decide(self, obs: Observation) -> Decision:
        if self._waypoints is None:
            return self._begin(obs)
        if self._failure is not None:
            return Decision(None, 0, None, self._failure)
        if self._next >= len(self._waypoints) and self._goal_moved(obs):
            return self._begin(obs)
        if self._watching(obs):
            return self._follow(obs)
        if self._next >= len(self._waypoints):
            return Decision(None, 0, None, "path exhausted before the goal was reached")
        target = self._waypoints[self._next].copy()
        self._next += 1
        # the last waypoint is the goal: drive onto it so the executed path is complete
        return Decision(target, 0, None, finish=self._next >= len(self._waypoints), align=True)

    def _begin(self, obs: Observation) -> Decision:
        """Plan from the robot to the goal as observed and hand out the first waypoint."""
        self._plan(np.array([obs.pose.x, obs.pose.y]), np.asarray(obs.goal, dtype=float),
                   float(obs.robot_radius))
        if self._failure is not None:
            return Decision(None, self._cost, None, self._failure)
        assert self._waypoints is not None
        self._next = 1
        if self._watching(obs):  # watch from the first step on
            decision = self._follow(obs)
            return Decision(decision.target, self._cost + decision.iterations,
                            decision.duration, decision.reason, decision.finish, align=True)
        return Decision(self._waypoints[0].copy(), self._cost, None,
                        finish=len(self._waypoints) == 1, align=True)

    # --------------------------------------------------------------------------- planning
    def plan(self, start: Array, goal: Array, radius: float) -> Array | None:
        """Plan once (no robot needed): the path with the start, or None (see ``failure``)."""
        self._plan(np.asarray(start, dtype=float), np.asarray(goal, dtype=float), radius)
        return self.path

    def node_clearance(self, width: float, height: float) -> float:
        """Margin of the node rule beyond the robot radius on a ``width`` x ``height`` world.

        ``min(node_margin, node_scale * max(width, height))``, never below ``safety_margin``:
        1 m on the paper's 170 m maps (0.02 * 170 = 3.4), 0.2 m on a 10 m map.
        """
        scaled = float(self.p["node_scale"]) * max(width, height)
        margin = min(float(self.p["node_margin"]), scaled)
        return max(margin, float(self.p["safety_margin"]))

    def safety_clearance(self, width: float, height: float) -> float:
        """Margin of the safety rule beyond the robot radius on a ``width`` x ``height`` world.

        ``min(safety_margin, safety_scale * max(width, height))`` (``safety_scale = 0`` turns the
        cap off): the paper's 20 cm on its 170 m maps (0.003 * 170 = 0.51), 3 cm on a 10 m map
        (the margin the swarm local planners keep there).
        """
        margin = float(self.p["safety_margin"])
        scale = float(self.p["safety_scale"])
        return min(margin, scale * max(width, height)) if scale > 0 else margin

    @property
    def failure(self) -> str | None:
        return self._failure

    @property
    def planned_length(self) -> float | None:
        """Length of the last plan (a moving goal makes the planner plan again)."""
        return None if self.path is None else path_length(self.path)

    @property
    def cost(self) -> int:
        """The paper's cost: RFO iterations consumed (Table 2)."""
        return self._cost

    def _plan(self, start: Array, goal: Array, radius: float) -> None:
        obstacles = self.static_map if self.static_map is not None else (
            self.scenario.static_obstacles()
        )
        self._geo = _Clearance(obstacles)
        self._goal = goal
        w, h = self.scenario.size
        self._thr_node = radius + self.node_clearance(float(w), float(h))
        self._thr_safe = radius + self.safety_clearance(float(w), float(h))
        split = float(self.p.get("split_length", 2.0))
        scale = float(self.p.get("split_scale", 0.0))
        self._split_length = min(split, scale * max(w, h)) if scale > 0 else split
        self._lo = np.array([0.0, 0.0])
        self._hi = np.array([float(w), float(h)])
        self._waypoints = np.zeros((0, 2))
        self.raw_path = self.path = None
        self.raw_paths = []
        self.trace = []
        if bool(collides(obstacles.point_clearance(start), radius)):
            self._failure = "start is in collision"
            return
        if bool(collides(obstacles.point_clearance(goal), radius)):
            self._failure = "goal is in collision"
            return
        # A start or goal closer to an obstacle than the safety rule allows could never be left
        # or reached: the safety margin shrinks to half their clearance beyond the radius.
        ends = obstacles.point_clearance(np.stack([start, goal]))
        spare = float(ends.min()) - radius
        if spare > 0 and radius + 0.5 * spare < self._thr_safe:
            self._thr_safe = radius + 0.5 * spare
            self._thr_node = max(self._thr_node, self._thr_safe)
        self._stall: tuple[int, float] | None = None
        mode = str(self.p["progress"])
        self._togo = self._euclidean
        self.progress_used = "euclidean"
        note = ""
        if mode == "geodesic":
            if not self._use_geodesic(obstacles, start, goal):
                return
        found, self._cost = self._search(start, goal)
        if not found and self._stall is not None and mode == "auto":
            # eq 17's straight line has traps (an obstacle facing the goal); the way along free
            # space has none: search again with it
            note = (f"; with eq 17's straight-line progress first, no fox got closer for "
                    f"{self._stall[0]} iterations ({self._stall[1]:.2f} m away)")
            self._stall = None
            if not self._use_geodesic(obstacles, start, goal, note):
                return
            found, more = self._search(start, goal)
            self._cost += more
        if not found:
            away = "along free space" if self.progress_used == "geodesic" else "in a straight line"
            if self._stall is not None:
                self._failure = (
                    f"no fox got closer to the goal for {self._stall[0]} iterations (best "
                    f"{self._stall[1]:.2f} m away {away}){note}"
                )
            else:
                self._failure = f"no path to the goal within {self._cost} iterations{note}"
            return
        # already at the target: one waypoint, the target itself
        found = [np.vstack([q, goal]) if len(q) == 1 else q for q in found]
        self.raw_path = found[0]
        self.raw_paths = found
        path = found[int(np.argmin([path_length(q) for q in found]))]  # the first of the shortest
        if self.smooth:
            refined = [self._prune(q) for q in self._refine(found)]
            lengths = [path_length(q) for q in refined]
            path = refined[int(np.argmin(lengths))]  # the first of the shortest
        # The product's rule on every output segment (the planner's own rule is stricter).
        clearance = obstacles.segment_clearance(path[:-1], path[1:])
        if np.any(collides(clearance, radius)):  # pragma: no cover - guards a geometry bug
            self._failure = "internal error: planned segment in collision"
            return
        self.path = path
        self._waypoints = path[1:]


_COMMON = RfoFamilyPlanner.defaults
_GWO_PARAMS: dict[str, Any] = {
    "patience": 50,
    "wolves": 7,  # Table 1: M = 7
    "gwo_iterations": 10,
}
_EA_PARAMS: dict[str, Any] = {
    "arrivals": 5,  # the EA's population is built from the paths of the first five foxes home
    "ea_population": 10,
    "ea_generations": 50,
    "split_length": 2.0,  # m
    "split_scale": 0.025,  # split length capped at this fraction of the larger world side
    "phases": 4,
    "refine_tol": 1e-4,  # a path leaves the rounds once one shortens it by less than this
    "node_opt": "gwo",  # "gwo": GWO optimisation of the path nodes in every round; "off"
    "relax_sweeps": 2,
    "relax_box": 0.5,  # node box half-width / its longer adjacent segment
}


@register
class RfoPlanner(RfoFamilyPlanner):
    name = "RFO"
    description = "Red fox optimizer as a global path planner (eq 2 moves, eqs 3-5 local search)"
    fallback = "local"
    defaults: ClassVar[dict[str, Any]] = {**_COMMON, "notice": 0.75}


@register
class RfoGwoPlanner(RfoFamilyPlanner):
    name = "RFO-GWO"
    description = "Hybrid red fox / grey wolf global planner (Algorithms 1 and 2)"
    fallback = "gwo"
    defaults: ClassVar[dict[str, Any]] = {**_COMMON, **_GWO_PARAMS}


@register
class RfoGwoEaPlanner(RfoFamilyPlanner):
    name = "RFO-GWO-EA"
    description = "RFO-GWO, then EA Erase mutation and multiphase refinement (section 4.2)"
    fallback = "gwo"
    smooth = True
    defaults: ClassVar[dict[str, Any]] = {**_COMMON, **_GWO_PARAMS, **_EA_PARAMS}
