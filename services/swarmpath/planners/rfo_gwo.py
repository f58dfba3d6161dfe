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

Phase A, Algorithm 1 (all three planners)
-----------------------------------------
``foxes`` foxes start at uniform points of the box of half-width ``radius`` around the start
(invalid draws stay at the start); each keeps its location history, which begins at the start.
Every iteration the foxes are sorted by eq 17 (distance to the target) and, in that order, each
proposes the eq 2 move x' = x + alpha sign(ref - x) with ref = the target (the prey, which the
planner knows; ``reference = "best"``: the best fox for the others, as eq 2 is printed, and the
target for the best fox). alpha = u d with u ~ U(0, 1) per fox (``alpha_draw = "population"``: one
u per iteration, section 3.1's reading) and d = sqrt(|x - target|) (eq 1/17 as printed, square
root of the Euclidean distance in metres; ``alpha_bound = "distance"``: d = |x - target|). Each
component of the step is clamped so that it does not pass the reference (the fox can land exactly
on the target) and the point is clipped to the world. The node is valid when it is closer to the
target, the segment from the fox's last node passes the safety rule and the node passes the node
rule (the target itself is exempt from the node rule). A valid node is appended to the fox's
history, except that a node within ``goal_snap`` (0.2 m, the episode's acceptance tolerance) of
the target is replaced by the target when the segment to it is valid (or, failing that, the target
is appended after it when that segment is valid). The first fox to reach the target returns its
history: the cost is the iteration count at that moment (0 if a fox reaches it at
initialisation). ``arrivals`` (RFO-GWO-EA: 5, else 1) foxes: the foxes that arrived stop and the
others go on until that many have arrived, or ``arrival_wait`` (1.0) times the first fox's
iterations have passed since (at least one), or the search stalls; the cost is then every
iteration consumed. The random numbers up to the first arrival are the same, so the first path is
``RFO-GWO``'s. Without the EA the shortest of the paths is used.

Clearance rules (section 4.1; the paper works in cm on 17000 cm maps, we in m, and both margins
are *in addition to* the robot radius r, as the paper's robot is a body, not a point):

* safety rule (the "more than 20 cm from the border of any barrier" rule): clearance of every
  segment, and of every node not produced by eq 2, > r + s with the scale-aware margin
  s = min(``safety_margin`` (0.2 m), ``safety_scale`` (0.01) * the larger world side)
  (:meth:`RfoFamilyPlanner.safety_clearance`): exactly 20 cm on the paper's 170 m maps, 10 cm on
  a 10 m map (the diff-drive robots of the ICOOT/IHPO maps leave the polyline by up to 7.5 cm at
  corners; 3 cm let them touch);
* node rule (the "smaller than one metre from the border of any barriers" rule that hands the
  fox to GWO): clearance of an eq 2 node > r + m with the scale-aware margin
  m = max(``safety_margin``, min(``node_margin`` (1.0 m), ``node_scale`` (0.02) * the larger
  world side)) (:meth:`RfoFamilyPlanner.node_clearance`): exactly 1 m on the paper's 170 m
  maps, 0.2 m on a 10 m map. Applying it to GWO's wolves as well left mfb-static (10 m wide,
  r = 0.5 m) unsolved after 2000 iterations.

Both are the product's collision rule (:func:`~swarmpath.world.geometry.collides`, touching
counts) applied with the enlarged radius, so every output segment is collision-free for the robot
with at least s to spare; the final path is re-checked with
:meth:`ObstacleSet.segment_clearance` before it is handed out.

When the eq 2 node is invalid:

* ``RFO`` (RFO alone): the fox stays at its previous place (section 3.1: "otherwise, they return
  to their previous place") and, if unnoticed (mu ~ U(0, 1) > ``notice`` = 0.75), makes the RFO
  local-search move of eqs 3-5 in two dimensions: x' = x + a r (cos phi1, sin phi1) with the scaling
  a ~ U(0, 1) once per iteration, phi0, phi1 ~ U(0, 2 pi) per fox and the observation radius
  r = ``radius`` sin(phi0)/phi0 (eq 4 with Table 1's r in [0, 3] as its scale, in metres). The
  move is kept if it passes the safety rule (it need not be closer). Reproduction (eqs 6-9) is
  not used: a fox born in the alpha couple's habitat has no collision-free history.
* ``RFO-GWO``: Algorithm 2. The "current obstacle" is the one the segment hits (least segment
  clearance) or, if only the node rule failed, the one nearest to the node. ``wolves`` (Table 1:
  M = 7) wolves, uniform in the box of half-width ``radius`` around the fox, run
  ``gwo_iterations`` iterations of the registered GWO (eqs 3-16, authors' leader update) on the
  negated distance from that obstacle (Algorithm 2 maximises it). A wolf counts only if it is
  "preferable to the current location of the fox": closer to the target, reached by a segment
  that passes the safety rule and itself passing the safety rule; others score PENALTY plus their
  violation. The best wolf found becomes the fox's next node; with none the fox stays
  ("return current position of fox_i"). The foxes handled by GWO in one iteration are optimised
  as one batch (they do not interact within an iteration; each has its own generator seeded from
  the planner's).

Phase B/C, section 4.2 (``RFO-GWO-EA`` only)
-------------------------------------------
Every path of the ``arrivals`` foxes is refined (side by side, independently) and the shortest
result is the plan. An EA with the Erase mutation as its only operator
(:meth:`RfoFamilyPlanner._ea`: a population of ``ea_population`` copies of the path; Erase picks
two nodes V_i, V_j, j > i + 1, and if V_i V_j passes the safety rule removes the nodes between
them; (mu + lambda) selection on length, ``ea_generations`` = 50) runs on the path; then up to
``phases`` (4) rounds of the multiphase technique: cut every segment longer than the split length
into equal pieces, run the EA again, and (``node_opt = "gwo"``) optimise the nodes with GWO
(:meth:`RfoFamilyPlanner._relax`: each interior node is a sub-problem, the point of a box around
it minimising the length of its two segments under the safety rule, odd and even nodes in turn,
``relax_sweeps`` = 2, box half-width ``relax_box`` = 0.5 times the longer adjacent segment; a node
moves only to a valid, shorter place). A path leaves the rounds once one shortens it by less than
``refine_tol`` (1e-4). Finally every node whose neighbours see each other under the safety rule is
erased (:meth:`RfoFamilyPlanner._prune`). Erase and the node moves never lengthen a path and add
only checked segments; the split points lie on valid segments, so ``RFO-GWO-EA`` is never longer
than ``RFO-GWO`` with the same seed.

Following the path among moving obstacles
-----------------------------------------
The planner gets only the static map. A moving goal: when the path is used up and the goal is more
than ``goal_snap`` from where it was planned to, the planner plans again from the robot to the
goal's new place. When the observation carries a sensor reading and the
scenario declares moving obstacles (that fact only), :meth:`RfoFamilyPlanner._follow` hands out
decisions of ``replan`` (0.25 s) so that the robot re-senses. Hits farther than ``STATIC_HIT``
from the static map and the border, with their positions predicted ``predict`` (1 s) ahead
(:func:`sensed_map.predict`) and condensed within ``watch`` (3 m) (:func:`sensed_map.condense`),
must stay farther than r + ``dynamic_margin`` (0.3 m) from the segment to the current waypoint;
otherwise the robot waits or steps ``side_step`` (0.3 m) to the candidate (12 directions) that
keeps that margin and is nearest the waypoint, or, with none, to the one with the most room. A
waypoint no longer reachable on the static map after a step aside triggers a new plan from the
current position. Without sensors or moving obstacles the waypoints are handed out as above.

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
