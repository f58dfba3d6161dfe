"""The seeds' swarm local planner, usable with any registered optimizer, and its named presets.

Each decision (Abdulsaheb & Kadhim 2022, section 4 and its pseudocode; Ajeil et al. 2020,
Figure 8):

1. obstacle detection: the robot's virtual sensors return the obstacle points they hit; points
   seen in the last ``memory`` seconds are kept (static obstacles behind the robot stay known,
   moving ones fade);
2. path generation: a swarm of ``agents`` candidate waypoints in the box of half-width ``step``
   around the robot (clipped to the world) is optimised for ``iterations`` iterations by the chosen
   optimizer on w1 f1 + w2 f2 (:mod:`swarmpath.planners.local`), infeasible candidates repaired by
   the local search (MFB eqs 18-22 or ICOOT's grid search) or penalised. What f1 and f2 measure
   against is ``heuristic``: ``"euclidean"`` is the papers' literal objective, distance and
   heading to the goal (eqs 3 and 5). It makes the robot slide along every obstacle it meets
   (a greedy "bug" behaviour: 4% above the exact optimum on mfb-static). ``"visibility"``
   (default) aims instead at a point of the exact shortest path to the goal in the *sensed* map
   (hit groups wrapped in convex hulls, unseen space free: :mod:`swarmpath.planners.sensed_map`):
   with ``aim = "shortcut"`` the farthest point within ``lookahead`` metres along it that is
   reachable in a straight line with the margin, so the robot drives the path's tangents and
   leaves obstacles along them. The planner still knows only what its sensors returned;
3. the robot drives toward the best feasible waypoint through its kinematic model for at most
   ``replan`` seconds, then senses and decides again (receding horizon, so moving obstacles are
   re-sensed at a fixed rate). While that waypoint stays ahead, feasible and within
   ``hold_angle`` of the aim, later decisions keep it without running the swarm;
4. obstacle avoidance fallback: when no feasible candidate exists, the MFB paper's gap vector
   (eq 24) picks the free gap closest to the goal direction and the robot takes a short step
   into it; with no free gap it waits, unless a (predicted) obstacle comes within the margin of
   its spot: then it steps to where it keeps the most clearance.

Moving obstacles: sensed points that moved between the last two scans are extrapolated over
``predict`` seconds and added to the known points (:func:`sensed_map.motion`), so candidates
that an approaching obstacle is about to occupy are infeasible. An obstacle whose whole velocity
(:func:`sensed_map.group_velocity`) stays steady over ``track_scans`` scans is *tracked*: the aim
plans around it where it will be when the robot can get there (``lead``; behind a crossing
obstacle instead of ahead of it) and its remembered trail is forgotten (``moving_memory``,
``trail``). Erratic motion (a random walk) is not tracked and is handled as before.

Local minima: when the robot gets no closer to the goal for ``escape`` seconds (a stall),
``escape_plan = "memory"`` (default) hands the swarm, from then on, the shortcut point of the
shortest way on the robot's occupancy memory of everything its scans showed, unseen cells free,
planned again only when the memory changes on it (:mod:`swarmpath.planners.swarm_memory`);
``"hulls"`` (the earlier rule) makes the known path also avoid every static point sensed since
the start, until the robot is closer than ever before (:mod:`swarmpath.planners.swarm_escape`).

The run ends within 0.2 m of the goal, or fails at the episode's step or time limit.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from swarmpath.optimizers import RunStreams, get_optimizer
from swarmpath.optimizers.api import COMPUTING_BACKENDS
from swarmpath.optimizers.base import ParameterError
from swarmpath.planners import local, sensed_map, swarm_aim
from swarmpath.planners.base import Decision, Observation, PlannerError, register
from swarmpath.planners.swarm_escape import Escape
from swarmpath.planners.swarm_guide import Guide
from swarmpath.planners.swarm_memory import MemoryWay
from swarmpath.planners.swarm_moves import SwarmMoveLimits
from swarmpath.planners.swarm_search import searcher
from swarmpath.robot.sensors import get_sensor_model

Array = np.ndarray
# m: sensed points in one cell of this grid are merged (the first one is kept). A merged point
# can lie a cell diagonal from the kept one, and the clearance checks only see the kept one: with
# 5 cm the hit 2 cm from a polygon corner's tip was dropped for one 5 cm further along the edge
# and the robot touched the corner (rfogwo-map3, ICOOT seed 1, t = 234 s), and on mfb-static the
# least body gap fell to 0.78 cm under a 1 cm safety distance. 1 cm: at most 1.4 cm.
HIT_CELL = 0.01
#: The planner family ``swarm:<optimizer>`` (:func:`swarm_planner`).
SWARM = "swarm:"
#: A ``swarm:<optimizer>`` planner's parameters for its optimizer: ``optimizer.<parameter>``.
OPTIMIZER_PREFIX = "optimizer."
CARROT_CLEARANCE = 0.01  # m: the known-map path keeps this much beyond the planner's margin


class SwarmLocalPlanner(SwarmMoveLimits):
    """Generic swarm local planner; named subclasses fix the optimizer and its paper's settings."""

    name = "swarm-local"
    kind = "local"
    guarded = True  # a swarm waypoint reached by a turning diff drive may graze a wall
    default_sensors = "mfb-12"
    defaults: ClassVar[dict[str, Any]] = {
        "optimizer": "PSO",
        "agents": 20,
        "iterations": 20,
        "step": 0.8,  # m: candidate box half-width (the sensing range)
        "w1": 0.9,
        "w2": 0.1,
        "safety": 0.01,  # m: clearance kept beyond the robot radius (ds of eqs 19-20)
        "corner_safety": 0.03,  # m: instead, near a sensed corner or with coarse time steps
        "corner_angle": 30.0,  # deg: a sensed surface turning more than this is a corner
        "diff_drive_safety": 0.05,  # m: always, for a diff-drive robot (it turns as it drives)
        "repair": "mfb",
        "objective": "cost",
        "memory": 2.0,  # s: how long sensed points are remembered
        "moving_memory": 0.0,  # s: ... tracked moving points (then only where they are now)
        "trail": 0.05,  # m: remembered points this close to a tracked surface's trail are dropped
        "consistency": 0.25,  # m/s: a moving obstacle is tracked when its velocity is this steady
        "track_scans": 2,  # ... in this many scans in a row
        "track_gap": 0.3,  # m: ... between two scans' moving points this close
        "lead": 2.0,  # s: the aim plans around tracked points where they will be (0: off)
        "replan": 0.25,  # s: drive time per decision
        "heuristic": "visibility",  # what f1 measures the distance to (see module docstring)
        "lookahead": 1.0,  # m: carrot distance along the known shortest path
        "predict": 1.0,  # s: horizon over which moving sensed points are extrapolated (0: off)
        "surface": 0.2,  # m: previous hits joined into a surface for motion (0: nearest point)
        "map_cell": 0.1,  # m: hits merged on this grid before they are wrapped in hulls
        "rejoin": 0.02,  # m: reuse the last known path while the robot is this close to it (0: off)
        "aim": "shortcut",  # point of the known path f1 aims at: "shortcut" or "carrot"
        "carrot_clearance": CARROT_CLEARANCE,  # m beyond the margin the known path keeps
        "hold_angle": 3.0,  # deg: keep the last waypoint while it stays this close to the aim
        "hold_min": 0.3,  # m: ... and at least this far ahead (0 hold_angle: always re-search)
        "patience": 0,  # stop the swarm after this many iterations without improvement (0: off)
        "tolerance": 1e-6,  # relative improvement that counts for ``patience``
        "knowledge": "sensors",  # "map": the static obstacles are known from the start
        # knowledge = "map": the global guide (planners.swarm_guide): the exact shortest path
        # ("optimum"; the cost-to-go's when that gives up) or the cost-to-go's descent, keeping
        # the planner's safety + carrot_clearance beyond the robot radius (as the known path
        # does); planned again when the robot is guide_rejoin off it
        "guide": "optimum",
        "guide_rejoin": 0.3,  # m
        "aim_hits": "known",  # the known path avoids: "known" (all remembered) or "near"
        # the sensed hulls leave no known path: "grid" plans on the sensed points themselves
        # (swarm_aim.free_space_path), "line" aims at the straight line (the earlier rule)
        "no_path": "grid",
        "contact_band": 0.2,  # m beyond the body: no move closes on a sensed point this near
        # s without getting closer to the goal by ``escape_progress``: then the known path also
        # avoids every static point sensed since the start (planners.swarm_escape; 0: off)
        "escape": 5.0,
        "escape_progress": 0.05,  # m
        # at a stall (sensors only): "memory" follows, from then on, the way on the occupancy
        # memory of every scan (planners.swarm_memory); "hulls": the known path also avoids the
        # escape's points until a new record (the earlier rule)
        "escape_plan": "memory",
        "give_way": 1.5,  # s: moves scored against predicted moving points this far (0: off)
        "give_way_spread": 1.0,  # an untracked moving point may be this x the top speed x t away
        # "numba": the repairs, the aim's clearances and sensing's surface distances compiled
        # (planners.compiled; the same numbers, optional dep.)
        "backend": "numpy",
    }
    choices: ClassVar[dict[str, tuple[str, ...]]] = {
        "repair": ("mfb", "grid", "none"),
        "objective": ("cost", "inverse"),
        "heuristic": ("visibility", "euclidean"),
        "aim": ("shortcut", "carrot"),
        "knowledge": ("sensors", "map"),
        "guide": ("optimum", "cost-to-go"),
        "aim_hits": ("known", "near"),
        "no_path": ("grid", "line"),
        "escape_plan": ("memory", "hulls"),
        "backend": COMPUTING_BACKENDS,
    }
    #: Optimizer parameters of the preset (e.g. ICOOT's two leaders), merged under user ones.
    optimizer_params: ClassVar[dict[str, Any]] = {}
    #: The optimizer class of a ``swarm:<optimizer>`` planner (None for the presets).
    optimizer_class: ClassVar[type | None] = None

    @classmethod
    def check_params(cls, p):
        for key in ("agents", "iterations"):
            if int(p[key]) < 1:
                raise PlannerError(f"{cls.name}.{key} must be >= 1")
        for key in ("step", "replan", "lookahead", "map_cell"):
            if not float(p[key]) > 0:
                raise PlannerError(f"{cls.name}.{key} must be > 0")
        for key in ("w1", "w2", "safety", "corner_safety", "corner_angle", "diff_drive_safety",
                    "memory", "moving_memory", "trail", "lead", "consistency", "track_gap",
                    "track_scans", "predict", "surface", "carrot_clearance", "rejoin", "hold_angle",
                    "hold_min", "patience", "tolerance", "contact_band", "escape",
                    "escape_progress", "give_way", "give_way_spread", "guide_rejoin"):
            if float(p[key]) < 0:
                raise PlannerError(f"{cls.name}.{key} must be >= 0")
        try:
            opt_cls = get_optimizer(str(p["optimizer"]))
        except KeyError as exc:
            raise PlannerError(f"{cls.name}.optimizer: {exc.args[0]}") from None
        fixed = cls.defaults["optimizer"]
        if opt_cls.name != fixed:  # a table must name what ran: the planner named after it
            raise PlannerError(
                f"{cls.name}.optimizer: this planner runs {fixed}; the swarm local planner "
                f"driven by {opt_cls.name} is the planner '{SWARM}{opt_cls.name}'")
        try:
            opt_cls.resolve_params(cls.optimizer_settings(p))
        except ParameterError as exc:
            raise PlannerError(f"{cls.name}: {exc}") from None
        if p["backend"] == "numba":
            try:
                import numba  # noqa: F401
            except ImportError:
                raise PlannerError(f"{cls.name}.backend: 'numba' needs numba installed "
                                   "(pip install 'swarmpath[fast]')") from None

    @classmethod
    def optimizer_settings(cls, p: dict[str, Any]) -> dict[str, Any]:
        """The optimizer's parameters: the preset's, under the ``optimizer.<name>`` ones."""
        return {**cls.optimizer_params, **{k[len(OPTIMIZER_PREFIX):]: v for k, v in p.items()
                                           if k.startswith(OPTIMIZER_PREFIX)}}

    @classmethod
    def knows_static_map(cls, p):
        return p["knowledge"] == "map"

    def __init__(self, scenario, params, rng, static_map=None):
        super().__init__(scenario, params, rng, static_map)
        self._streams = RunStreams([rng])
        backend = str(self.p["backend"])
        if backend == "numba":
            _load_kernel()  # compiled or loaded from numba's cache here, not in a decision
        # knowledge = "map": the guide to the goal on the static map, whose surfaces near the
        # robot, sampled like sensor hits, are known at every decision (``_prior``)
        self._prior = np.zeros((0, 2))
        self._guide: Guide | None = None
        if static_map is not None:
            clearance = self._guide_clearance(scenario, static_map)
            self._guide = Guide(scenario, static_map, scenario.robot.radius, clearance,
                                str(self.p["guide"]), float(self.p["guide_rejoin"]), None, backend)
        self._memory: list[tuple[float, Array, np.ndarray]] = []  # (time, hits, moving)
        self._last_scan: tuple[float, Array] | None = None
        self._scan: tuple[Array, NDArray[np.bool_]] = (np.zeros((0, 2)), np.zeros(0, dtype=bool))
        self._held: Array | None = None  # the last swarm waypoint (see ``hold_angle``)
        self._escape = Escape(float(self.p["escape"]), float(self.p["escape_progress"]),
                              float(self.p["map_cell"]))
        self._path: Array | None = None  # the last known path (see ``rejoin``)
        # sensors only: the occupancy memory and its way, followed from the first stall on
        self._memory_way: MemoryWay | None = None
        if (static_map is None and self.p["escape_plan"] == "memory"
                and float(self.p["escape"]) > 0):
            self._memory_way = MemoryWay(
                (float(scenario.size[0]), float(scenario.size[1])), float(self.p["map_cell"]),
                scenario.robot.radius + self._memory_clearance(scenario),
                float(self.p["guide_rejoin"]), backend)
        self._moving_until = -np.inf  # motion was sensed in the last ``memory`` seconds
        self._moving: tuple[Array, Array] = (np.zeros((0, 2)), np.zeros((0, 2)))  # this scan's
        self._settled = np.zeros((0, 2))  # the known points but this scan's tracked ones
        self._threats: tuple[Array, Array, NDArray[np.bool_]] = (
            np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0, dtype=bool))
        self._gave: Array | None = None  # the direction the robot last gave way in
        self._way_out: Array | None = None  # away from the points last seen near the body
        self._last_moving = np.zeros((0, 2))  # the last scan's moving points
        self._threat_until = -np.inf  # ``_give_way`` saw moving points in the last ``memory`` s
        # the last scan's moving points, their whole-obstacle velocities and steady scans in a row
        self._tracks: tuple[Array, Array, NDArray[np.int64]] = (
            np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0, dtype=np.int64))
        self._speed = float(scenario.robot.linear_speed)
        # The planner knows its own robot (not the map): a differential drive turns while it
        # drives, so its path bulges off the straight segment it was sent along.
        self._diff_drive = scenario.robot.model == "diff-drive"
        self._corner_until = -np.inf  # a corner was sensed in the last ``memory`` seconds
        # More than 5 cm per simulated step (the rfogwo maps: 1 m): the robot's motion between
        # two commands is too coarse for a 1 cm clearance.
        robot = scenario.robot
        self._coarse = scenario.time_step * robot.linear_speed > 0.05 + 1e-9
        # The simulator drives whole time steps: a decision of ``replan`` seconds moves the robot
        # up to ``_travel`` metres before it senses again (1 m on the rfogwo maps: one 1 s step
        # at 1 m/s, against 0.125 m on mfb-static). Unseen space is assumed free, so with coarse
        # steps a move is cut (``_commit``) to what the sensors covered: the body at the end of a
        # move of d reaches d + radius from where it sensed, the sensors radius + range; and a
        # corner's tip between two rays a gap g apart sticks out of the sensed points by up to
        # about g / 2 (right angle), g = (d + radius + safety) x the rays' angular spacing.
        steps = max(1, math.ceil(float(self.p["replan"]) / scenario.time_step - 1e-9))
        self._travel = steps * scenario.time_step * robot.linear_speed
        sensors = scenario.sensors or self.default_sensors
        self._range, self._ray_gap = np.inf, 0.0
        if sensors:
            model = get_sensor_model(sensors)
            self._range = float(np.max(model.ranges))
            far = np.mod(model.angles[model.ranges >= self._range - 1e-9], 2 * np.pi)
            angles = np.unique(np.round(far, 9))
            self._ray_gap = float(np.max(np.diff(np.append(angles, angles[0] + 2 * np.pi))))
        opt_cls = get_optimizer(str(self.p["optimizer"]))
        try:
            self._opt_params = opt_cls.resolve_params(
                {k: v for k, v in self.optimizer_settings(self.p).items()
                 if k in opt_cls.defaults}
            )
        except ParameterError as exc:
            raise PlannerError(str(exc)) from None
        self._search = searcher(opt_cls.name, self._opt_params, int(self.p["agents"]),
                                self._streams, backend, str(self.p["repair"]),
                                str(self.p["objective"]))

    def _guide_clearance(self, scenario: Any, static_map: Any) -> float:
        """m beyond the robot radius the guide keeps: the largest safety the planner keeps near
        this map (``_safety``: a diff drive's, or the corner safety on a map with corners or
        with coarse steps) + ``carrot_clearance``, the known path's rule."""
        robot = scenario.robot
        if robot.model == "diff-drive":
            safety = float(self.p["diff_drive_safety"])
        elif static_map.polygons or scenario.time_step * robot.linear_speed > 0.05 + 1e-9:
            safety = float(self.p["corner_safety"])
        else:
            safety = float(self.p["safety"])
        return safety + float(self.p["carrot_clearance"])

    def _memory_clearance(self, scenario: Any) -> float:
        """m beyond the robot radius the memory's way keeps: the largest safety the planner may
        keep (a diff drive's, else the corner safety: a maze is all corners) + the known path's
        ``carrot_clearance``."""
        key = "diff_drive_safety" if scenario.robot.model == "diff-drive" else "corner_safety"
        return float(self.p[key]) + float(self.p["carrot_clearance"])

    # ----------------------------------------------------------------------------- deciding
    def _hold(self, p: Array, aim: Array, ctx: local.StepContext) -> bool:
        """Keep driving to the last swarm waypoint: still ahead, still feasible in the current
        sensed map, and still within ``hold_angle`` of the direction to the aim."""
        held = self._held
        if held is None or float(self.p["hold_angle"]) <= 0:
            return False
        to_held, to_aim = held - p, aim - p
        if np.hypot(*to_held) < float(self.p["hold_min"]) or np.hypot(*to_aim) < 1e-9:
            return False
        turn = abs(np.arctan2(to_held[0] * to_aim[1] - to_held[1] * to_aim[0],
                              to_held @ to_aim))
        if np.degrees(turn) > float(self.p["hold_angle"]):
            return False
        return swarm_aim.clear(held, ctx)

    def decide(self, obs: Observation) -> Decision:
        if self._guide is not None:  # the static surfaces within every reach of this decision
            self._prior = self._guide.near(np.array([obs.pose.x, obs.pose.y]),
                                           float(self.p["step"]) + float(self.p["lookahead"]))
        return self._keep_off(obs, self._give_way(obs, self._cut(obs, self._decide(obs))))

    def _decide(self, obs: Observation) -> Decision:
        p = np.array([obs.pose.x, obs.pose.y])
        goal = np.asarray(obs.goal, dtype=float)
        w, h = obs.world_size
        reach = float(self.p["step"])
        backend = str(self.p["backend"])
        known_hits = self._known_hits(obs)  # first: this scan may show a corner
        if self._memory_way is not None:
            self._memory_way.remember(self._scan[0])
        else:
            self._escape.remember(*self._scan)
        margin = obs.robot_radius + self._safety(obs.time)
        # Only hits that can touch a candidate segment matter, one per HIT_CELL (1 cm) cell.
        hits = sensed_map.condense(known_hits, p, reach + 2 * margin, HIT_CELL, backend)
        # Newly seen parts of a static obstacle can put the robot inside its own safety
        # distance; then moves that keep at least the clearance it has are feasible (never
        # closer than now), instead of none. Not when something moved in the last ``memory``
        # seconds (the clearance to it shrinks on its own: the gap-vector fallback steps away),
        # nor within the body radius.
        room = swarm_aim.nearest_hit(p, hits, backend)
        if obs.time > self._moving_until and obs.robot_radius < room < margin:
            margin = room - 1e-9
        plan_hits = hits
        known = known_hits
        if float(self.p["lead"]) > 0 and len(self._moving[0]):
            known = self._plan_hits(p)
            plan_hits = sensed_map.condense(known, p, reach + 2 * margin, HIT_CELL, backend)
        # The known path is planned around everything known (sensed within ``memory``, or the
        # map), not only around the hits near enough to touch a candidate (``aim_hits = "near"``):
        # with those alone it ran into obstacles already sensed farther on (icoot-map2, ICOOT,
        # seed 1: 10.2 % above the optimum, 6.4 % with everything known; docs/planners.md).
        if self._guide is not None:  # knowledge = "map": a point of the guide
            aim = self._guide.aim(p, goal, plan_hits, margin, float(self.p["lookahead"]),
                                  str(self.p["aim"]))
        else:
            aim = self._sensed_aim(obs.time, p, goal, plan_hits, margin, known,
                                   (0.0, 0.0, float(w), float(h)))
        to_goal = float(np.hypot(*(goal - p)))
        lower = np.maximum(p - reach, [0.0, 0.0])
        upper = np.minimum(p + reach, [w, h])
        ctx = local.StepContext(
            position=p,
            goal=aim,
            hits=hits,
            margin=margin,
            w1=float(self.p["w1"]),
            w2=float(self.p["w2"]),
            objective=str(self.p["objective"]),
            repair=str(self.p["repair"]),
            safety=self._safety(obs.time),
            lower=lower,
            upper=upper,
            backend=backend,
        )
        duration = float(self.p["replan"])
        # The goal itself is a candidate: when it is within reach and visible, go straight there.
        if to_goal <= reach:
            cost, fixed = local.score(goal[None, :], ctx)
            if cost[0] < local.PENALTY and np.allclose(fixed[0], goal):
                # drive onto the goal (the papers' runs end ~1 mm from it), re-sensing as usual
                self._held = None
                return Decision(goal, 0, duration, finish=True)
        if self._hold(p, aim, ctx):
            assert self._held is not None
            return Decision(self._held.copy(), 0, duration)

        patience, tol = int(self.p["patience"]), float(self.p["tolerance"])
        best, position, iterations = self._search(ctx, int(self.p["agents"]),
                                                  int(self.p["iterations"]), patience, tol)
        if best < local.PENALTY:
            target = local.repair(position[None, :], ctx)[0]
            self._held = target
            return Decision(target, iterations, duration)
        self._held = None
        return self._avoid(obs, ctx, iterations, duration)

    def _sensed_aim(self, time: float, p: Array, goal: Array, plan_hits: Array, margin: float,
                    known: Array, world: tuple[float, float, float, float]) -> Array:
        """The aim with sensors only: the known path's (module docstring, step 2), or, from the
        first stall on with ``escape_plan = "memory"``, the memory's way's (local minima)."""
        backend = str(self.p["backend"])
        escaping = self._escape.stalled(time, float(np.hypot(*(goal - p))))
        way = self._memory_way
        if way is not None and (escaping or way.leading):
            way.leading = True
            return way.aim(p, goal, plan_hits, margin, float(self.p["lookahead"]),
                           str(self.p["aim"]))
        if escaping:  # ``escape``: the path also avoids every static point sensed so far
            known = np.concatenate([known, self._escape.points()])
        if self.p["aim_hits"] == "known" or escaping:
            known = sensed_map.condense(known, p, np.inf, float(self.p["map_cell"]), backend)
        else:
            known = plan_hits
        return self._aim(p, goal, plan_hits, margin, world, known)

    def _avoid(
        self, obs: Observation, ctx: local.StepContext, iterations: int, duration: float
    ) -> Decision:
        """Gap-vector fallback (MFB eq 24): a short step into the free gap nearest the goal."""
        p = ctx.position
        angles = obs.pose.theta + np.arange(12) * (2 * np.pi / 12)
        if obs.reading is not None and obs.reading.fired.size == 12:
            free = ~obs.reading.gap_vector()
        else:
            free = np.ones(12, dtype=bool)
        step = 0.5 * float(self.p["step"])
        cands = p + step * np.stack([np.cos(angles), np.sin(angles)], axis=1)
        cands = np.clip(cands, ctx.lower, ctx.upper)
        cost = local.raw_cost(cands, ctx)
        cost = np.where(free & (local.violation(cands, ctx) == 0), cost, np.inf)
        if np.isfinite(cost).any():
            return Decision(cands[int(np.argmin(cost))], iterations, duration)
        # Boxed in: wait while the spot stays clear; when a (predicted) obstacle comes within the
        # margin, flee toward the option that keeps the most clearance (waiting would let a moving
        # obstacle drive into the robot).
        options = np.vstack([p[None, :], cands])
        room, _ = local.point_hit_distance(options, ctx.hits)  # clearance where it would stand
        if room[0] > obs.robot_radius:  # only imminent contact is worth a detour
            return Decision(p.copy(), iterations, duration)  # safe here: wait for a way to open
        return Decision(options[int(np.argmax(room))], iterations, duration)


def _load_kernel() -> None:
    """Load the compiled kernels (one call each on a tiny problem)."""
    hit = np.array([[1.0, 0.0]])
    ctx = local.StepContext(position=np.zeros(2), goal=np.array([2.0, 0.0]), hits=hit,
                            margin=0.5, repair="grid", backend="numba")
    local.repair_grid(np.array([[0.9, 0.0]]), ctx)
    local.repair_mfb(np.array([[0.9, 0.0]]), ctx)
    swarm_aim.load_kernels()

def _preset(name: str, optimizer: str, description: str, reference: str, sensors: str,
            settings: dict[str, Any], optimizer_params: dict[str, Any] | None = None) -> type:
    attrs = {
        "__module__": __name__,
        "name": name,
        "description": description,
        "reference": reference,
        "default_sensors": sensors,
        "defaults": {**SwarmLocalPlanner.defaults, "optimizer": optimizer, **settings},
        "optimizer_params": optimizer_params or {},
    }
    cls = type(name.replace("-", "_") + "Planner", (SwarmLocalPlanner,), attrs)
    return register(cls)


ICOOT_PAPER = "Abdulsaheb & Kadhim, IJIES 15(5) 2022, sections 4.1-4.3"
IHPO_PAPER = "Abdulsaheb & Kadhim, IJIES 16(2) 2023, section 5 (framework of the ICOOT paper)"
MFB_PAPER = "Ajeil, Ibraheem, Azar & Humaidi, IJARS 2020, Tables 1-2, eqs 3-8, 18-24"

# ICOOT paper: 80 coots, 2 leaders, 80 virtual sensors, grid local search (section 4.1).
_COOT_SETTINGS = {"agents": 80, "iterations": 5, "step": 0.8, "repair": "grid"}
_preset("ICOOT", "ICOOT", "ICOOT swarm local planner (80 coots, 2 leaders)", ICOOT_PAPER,
        "icoot-80", _COOT_SETTINGS, {"leaders": 2})
_preset("COOT", "COOT", "COOT in the ICOOT paper's planning framework", ICOOT_PAPER, "icoot-80",
        _COOT_SETTINGS, {"leaders": 2})
# HPO's published hunter rule scales absolute positions (a pull toward the world origin);
# around a robot the box centre is the meaningful origin (docs/algorithms.md, HPO).
_preset("IHPO", "IHPO", "IHPO swarm local planner", IHPO_PAPER, "icoot-80",
        {"agents": 80, "iterations": 5, "step": 0.8, "repair": "grid"}, {"hunter": "centre"})
_preset("HPO", "HPO", "HPO in the IHPO paper's planning framework", IHPO_PAPER, "icoot-80",
        {"agents": 80, "iterations": 5, "step": 0.8, "repair": "grid"}, {"hunter": "centre"})
# MFB paper Table 1: 8 bats, 8 iterations, sensing range 0.8 m; fitness 1/(f + eps) (eq 8).
_preset("MFB", "MFB", "Modified Frequency Bat local planner", MFB_PAPER, "mfb-12",
        {"agents": 8, "iterations": 8, "step": 0.8, "repair": "mfb", "objective": "inverse"})
# Table 2: 5 PSO particles, each tuning its own 5 bats ("Population size PSO 5, Population size
# MFB 5": split per_particle, 25 bats), 5 iterations.
_preset("HPSO-MFB", "HPSO-MFB", "Hybrid PSO-MFB local planner", MFB_PAPER, "mfb-12",
        {"agents": 5, "iterations": 5, "step": 0.8, "repair": "mfb", "objective": "inverse"},
        {"split": "per_particle"})
_preset("PSO", "PSO", "PSO in the seeds' local planning framework", MFB_PAPER, "mfb-12",
        {"agents": 20, "iterations": 20})
_preset("GWO", "GWO", "GWO in the seeds' local planning framework", MFB_PAPER, "mfb-12",
        {"agents": 20, "iterations": 20})
