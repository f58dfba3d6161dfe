"""Phase A of the RFO family (Algorithm 1, RFO's local search, Algorithm 2: GWO).

Ketafa & Al-Darraji, Iraqi J. Science 65(2) (2024) 1070-1088, doi 10.24996/ijs.2024.65.2.38,
sections 3.1-3.2 and 4.1. :class:`RfoSearch` holds the search of
:class:`~swarmpath.planners.rfo_gwo.RfoFamilyPlanner` together with its measure of progress and
validity rules; the planner sets the state it reads when it plans.

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
  (``RfoFamilyPlanner.safety_clearance``): exactly 20 cm on the paper's 170 m maps, 10 cm on
  a 10 m map (the diff-drive robots of the ICOOT/IHPO maps leave the polyline by up to 7.5 cm at
  corners; 3 cm let them touch);
* node rule (the "smaller than one metre from the border of any barriers" rule that hands the
  fox to GWO): clearance of an eq 2 node > r + m with the scale-aware margin
  m = max(``safety_margin``, min(``node_margin`` (1.0 m), ``node_scale`` (0.02) * the larger
  world side)) (``RfoFamilyPlanner.node_clearance``): exactly 1 m on the paper's 170 m
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
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from swarmpath.optimizers import Optimizer, Problem, RunStreams, create
from swarmpath.planners.base import Planner
from swarmpath.planners.cost_to_go import CostToGo
from swarmpath.planners.rfo_geometry import _BoxQuery, _Clearance
from swarmpath.world.geometry import ObstacleSet, collides

Array = NDArray[np.float64]
STALL_TOLERANCE = 0.01  # m: smaller gains of the best fox do not count as progress
PENALTY = 1e6  # GWO objective of an invalid wolf (plus its violation): any valid wolf beats it


class RfoSearch(Planner):
    """Algorithm 1 with its fallbacks; :meth:`RfoFamilyPlanner._plan` sets the state below."""

    #: What a fox whose eq (2) node is infeasible does: "local" = RFO's local search (eqs 3-5,
    #: RFO alone), "gwo" = Algorithm 2 (GWO obstacle avoidance).
    fallback: ClassVar[str] = "local"

    _failure: str | None
    _geo: _Clearance
    _goal: Array
    _thr_node: float
    _thr_safe: float
    _lo: Array
    _hi: Array
    _togo: Callable[[Array], Array]
    _stall: tuple[int, float] | None
    progress_used: str
    trace: list[float]


    # ------------------------------------------------------------------------ progress
    def _euclidean(self, P: Array) -> Array:
        """Eq 17: the straight-line distance to the target."""
        return np.asarray(np.hypot(P[..., 0] - self._goal[0], P[..., 1] - self._goal[1]))

    def _use_geodesic(self, obstacles: ObstacleSet, start: Array, goal: Array,
                      note: str = "") -> bool:
        """Switch "closer to the target" to the way along free space (:class:`CostToGo`, keeping
        the safety clearance); False, with the failure set, when the start has no such way."""
        field = CostToGo(obstacles, self.scenario.size, goal, self._thr_safe,
                         int(self.p["progress_cells"]))
        self._togo = field
        self.progress_used = "geodesic"
        if not math.isfinite(float(field(start[None, :])[0])):
            self._failure = (
                f"no way from the start to the goal keeping {self._thr_safe:.3g} m from every "
                f"obstacle (robot radius + safety margin) on a grid of "
                f"{field.spec.resolution:.3g} m cells: the goal is walled off, or the way "
                f"passes gaps narrower than the grid resolves (raise progress_cells){note}"
            )
            return False
        return True

    # ------------------------------------------------------------------------ validity
    def _segments_ok(self, A: Array, B: Array) -> NDArray[np.bool_]:
        d = self._geo.segment(A, B, self._thr_safe)
        return ~collides(d, self._thr_safe)

    def _moves_ok(self, A: Array, B: Array, node_threshold: float) -> tuple[
        NDArray[np.bool_], NDArray[np.bool_]
    ]:
        """Segments AB under the safety rule, and nodes B under ``node_threshold`` (goal exempt)."""
        seg, end = self._geo.segment_and_end(A, B, max(self._thr_safe, node_threshold))
        at_goal = np.all(B == self._goal, axis=-1)
        return ~collides(seg, self._thr_safe), at_goal | ~collides(end, node_threshold)

    # ------------------------------------------------------------ phase A: Algorithm 1
    def _search(self, start: Array, goal: Array) -> tuple[list[Array], int]:
        """Algorithm 1. Returns the histories of the foxes that reached the target, in order of
        arrival (empty: none did), and the iterations consumed.

        With ``arrivals`` = 1 (RFO, RFO-GWO) the first fox to reach the target ends the search
        (lines 25-27). With more (RFO-GWO-EA, where the EA's population is built from them), the
        foxes that arrived stop and the others go on until ``arrivals`` foxes have arrived, or
        ``arrival_wait`` times the first fox's iterations (at least one) have passed since, or
        the search stalls or runs out of iterations. Up to the first arrival the random numbers
        drawn are the same, so the first path is the one ``arrivals`` = 1 returns.
        """
        rng = self.rng
        N = int(self.p["foxes"])
        T = int(self.p["iterations"])
        R = float(self.p["radius"])
        snap = float(self.p["goal_snap"])
        want = int(self.p["arrivals"])
        lo, hi = self._lo, self._hi
        arrived: list[Array] = []
        active = np.ones(N, dtype=bool)

        def arrive(i: int) -> None:
            arrived.append(np.array(hist[i]))
            active[i] = False

        # Line 1: n foxes around the start, each at a valid node reached by a free segment.
        cand = np.clip(start + rng.uniform(-R, R, (N, 2)), lo, hi)
        starts = np.broadcast_to(start, cand.shape)
        good = np.logical_and(*self._moves_ok(starts, cand, self._thr_safe))
        pos = np.broadcast_to(start, cand.shape).copy()
        hist: list[list[Array]] = [[start.copy()] for _ in range(N)]
        for i in np.flatnonzero(good).tolist():
            if self._move(i, cand[i], pos, hist, goal, snap):
                arrive(i)
                if len(arrived) >= want:
                    return arrived, 0
        for i in range(N):  # a fox at the start may already see the target
            if active[i] and self._arrive(i, pos, hist, goal, snap):
                arrive(i)
                if len(arrived) >= want:
                    return arrived, 0
        first = 0  # iteration of the first arrival

        patience = int(self.p["patience"])
        wait = float(self.p["arrival_wait"])
        record, stalled = math.inf, 0
        for t in range(1, T + 1):
            if arrived and t - 1 - first >= max(1, math.ceil(wait * first)):
                return arrived, t - 1
            dist = self._togo(pos)  # eq 17 (or the way along free space, see ``progress``)
            dist = np.where(active, dist, np.inf)
            self.trace.append(float(dist.min()))
            if dist.min() < record - STALL_TOLERANCE:
                record, stalled = float(dist.min()), 0
            else:
                stalled += 1
                if patience and stalled >= patience:
                    if not arrived:
                        self._stall = (patience, record)
                    return arrived, t - 1
            order = np.argsort(dist, kind="stable")  # line 6
            best = order[0]  # line 7
            ref = np.broadcast_to(goal, pos.shape).copy()
            if self.p["reference"] == "best":
                ref[np.arange(N) != best] = pos[best]
            reach = np.where(active, dist, 0.0)
            bound = reach if self.p["alpha_bound"] == "distance" else np.sqrt(reach)
            u = rng.random(N) if self.p["alpha_draw"] == "fox" else np.full(N, rng.random())
            alpha = u * bound
            delta = ref - pos
            step = np.sign(delta) * np.minimum(alpha[:, None], np.abs(delta))  # eq 2, clamped
            new = np.clip(pos + step, lo, hi)
            closer = self._togo(new) < dist
            seg_ok, node_ok = self._moves_ok(pos, new, self._thr_node)
            ok = closer & seg_ok & node_ok
            if self.fallback == "local":
                moved = self._local_phase(pos, new, ok, rng, active)
            else:
                moved = ok.copy()
                fail = order[~ok[order] & active[order]]  # lines 16 and 21, in fitness order
                if fail.size:
                    # the obstacle the segment hits, or the one too close to the node
                    seg_bad = ~seg_ok[fail]
                    ends = np.where(seg_bad[:, None], pos[fail], new[fail])
                    ks = np.where(
                        seg_bad,
                        self._geo.nearest(ends, new[fail], self._thr_safe),
                        self._geo.nearest(new[fail], new[fail], self._thr_node),
                    )
                    q, found = self._gwo(pos[fail], ks, dist[fail])
                    new[fail[found]] = q[found]
                    moved[fail[found]] = True
            for i in order:
                if active[i] and moved[i] and self._move(i, new[i], pos, hist, goal, snap):
                    arrive(i)  # lines 25-27
                    if len(arrived) == 1:
                        first = t
                    if len(arrived) >= want:
                        return arrived, t
        return arrived, T

    def _move(self, i: int, q: Array, pos: Array, hist: list[list[Array]], goal: Array,
              snap: float) -> bool:
        """Fox i moves to node q (onto the target instead if q is within ``snap`` of it and the
        segment to the target is valid); True when it has reached the target."""
        if (not np.array_equal(q, goal) and math.dist(q, goal) <= snap
                and self._segments_ok(pos[i], goal)[0]):
            q = goal
        pos[i] = q
        hist[i].append(pos[i].copy())
        return self._arrive(i, pos, hist, goal, snap)

    def _arrive(self, i: int, pos: Array, hist: list[list[Array]], goal: Array,
                snap: float) -> bool:
        if np.array_equal(pos[i], goal):
            return True
        if math.dist(pos[i], goal) <= snap and self._segments_ok(pos[i], goal)[0]:
            pos[i] = goal
            hist[i].append(goal.copy())
            return True
        return False

    # ------------------------------------------------- RFO alone: local search (eqs 3-5)
    def _local_phase(self, pos: Array, new: Array, ok: NDArray[np.bool_],
                     rng: np.random.Generator, active: NDArray[np.bool_]) -> NDArray[np.bool_]:
        """Foxes whose eq (2) node failed stay put; the unnoticed ones (mu > notice) explore."""
        N = pos.shape[0]
        mu = rng.random(N)
        a = rng.random()  # scaling a, once per iteration
        phi0: Array = np.asarray(rng.random(N)) * (2 * math.pi)
        phi1: Array = np.asarray(rng.random(N)) * (2 * math.pi)
        rmax = float(self.p["radius"])
        with np.errstate(invalid="ignore", divide="ignore"):
            r: Array = np.asarray(
                np.where(phi0 > 0, rmax * np.sin(phi0) / np.where(phi0 > 0, phi0, 1.0), rmax)
            )
        movers = ~ok & active & (mu > float(self.p["notice"]))
        moved = ok.copy()
        if movers.any():
            idx = np.flatnonzero(movers)
            step = (a * r[idx])[:, None] * np.column_stack([np.cos(phi1[idx]), np.sin(phi1[idx])])
            cand = np.clip(pos[idx] + step, self._lo, self._hi)
            good = np.logical_and(*self._moves_ok(pos[idx], cand, self._thr_safe))
            good &= np.any(cand != pos[idx], axis=1)
            new[idx[good]] = cand[good]
            moved[idx[good]] = True
        return moved

    # ----------------------------------------------------------------- Algorithm 2: GWO
    def _gwo(self, P: Array, ks: NDArray[np.intp], dist: Array) -> tuple[Array, NDArray[np.bool_]]:
        """Algorithm 2 for the foxes at P (F, 2) blocked by obstacles ks (F,), as one batch.

        For each fox, ``wolves`` wolves in the box of half-width ``radius`` around it maximise
        their distance from its obstacle (minimise the negated distance) for ``gwo_iterations``
        iterations of the registered GWO (eqs 3-16). A wolf is admissible when it is a valid node
        reached from the fox by a valid segment and is closer to the target than the fox (it is
        "preferable to the current location of fox_i"); an inadmissible wolf scores PENALTY plus
        its violation. Returns the best admissible wolf per fox and whether one was found.
        """
        F = P.shape[0]
        R = float(self.p["radius"])
        lower = np.maximum(P - R, self._lo)
        upper = np.minimum(P + R, self._hi)
        togo = self._togo
        thr = self._thr_safe
        m = int(self.p["wolves"])
        query = _BoxQuery(self._geo, P, lower, upper, thr, m, ks)
        dp = np.repeat(dist, m)
        blocked = np.repeat(ks >= 0, m)

        def objective(X: Array, streams: RunStreams) -> Array:
            W = X.reshape(-1, 2)
            dseg, dnode, dobs = query(W)
            dg = togo(W)
            valid = ~collides(dseg, thr) & ~collides(dnode, thr) & (dg < dp)
            viol = (np.maximum(thr - dseg, 0.0) + np.maximum(thr - dnode, 0.0)
                    + np.maximum(dg - dp, 0.0))
            fit = np.where(blocked, -dobs, dg)
            return np.where(valid, fit, PENALTY + viol).reshape(F, m)

        opt = self._run_gwo(objective, lower, upper, m, F)
        return opt.best_position.copy(), opt.best_fitness < PENALTY

    def _run_gwo(self, objective: Callable[..., Array], lower: Array, upper: Array, m: int,
                 runs: int) -> Optimizer:
        """GWO with ``m`` wolves for ``gwo_iterations`` on ``runs`` independent problems, one
        generator per run seeded from the planner's generator; returns the finished optimizer."""
        seeds = np.asarray(self.rng.integers(0, 2**63, size=runs), dtype=np.int64)
        streams = RunStreams([np.random.Generator(np.random.PCG64(int(s))) for s in seeds])
        opt = create("GWO", Problem(objective, lower, upper), m,
                     int(self.p["gwo_iterations"]), streams)
        opt.initialize()
        while not opt.done:
            opt.step()
        return opt

