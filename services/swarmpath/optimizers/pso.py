"""Particle Swarm Optimization with a linearly decreasing inertia weight.

Kennedy & Eberhart, "Particle swarm optimization", Proc. ICNN 1995, 1942-1948 (velocity and
position update); inertia weight from Shi & Eberhart, "A modified particle swarm optimizer",
Proc. IEEE ICEC 1998, 69-73:

    v_i <- w v_i + c1 r1 (pbest_i - x_i) + c2 r2 (gbest - x_i)        (velocity update)
    x_i <- x_i + v_i                                                  (position update)

with r1, r2 ~ U(0, 1) drawn per component. Defaults are the setting of the Mirjalili group's PSO
code (``PSO.m`` shipped with the GWO paper; EvoloPy ``PSO.py`` is a port): c1 = c2 = 2,
w = w_max - (t - 1)(w_max - w_min)/T for iterations t = 1..T (0.9 down to 0.2 + 0.7/T, the
code's l = 0..T-1), velocities start at 0 and are clamped per component, with one change: the
clamp is relative to the box, |v| <= ``vmax_fraction`` (ub - lb) = 0.1 (ub - lb)
(``vmax_mode = "range"``), where the code has an absolute Vmax = 6 (``vmax_mode = "absolute"``,
``vmax``), i.e. 0.1 of F5's box. Why: with free flight (below) the absolute 6 reproduces the GWO
paper's 30-D PSO column but leaves every particle outside the small boxes of F2/F7 at 100 and
500 dims (no particle is ever feasible again), while 0.1 of the range lands within a decade of
37 of the 39 PSO cells of the ICOOT paper's Tables 2-4 (docs/algorithms.md, PSO).
``vmax_mode = "none"`` does not clamp.

pbest and gbest change on strict improvement only; positions are never greedily reverted.

Bounds (``bounds``): the reference code distributed with the GWO paper (``PSO.m``, also shipped
with later Mirjalili-group codes) applies its clip outside the particle loop, to ``pos(i,:)``
with ``i`` left at the last particle: every other particle flies freely and is evaluated
wherever it is. Default ``bounds = "fly"`` is that behaviour within the frame's box contract
("let particles fly", Bratton & Kennedy, IEEE SIS 2007): positions and velocities are never
touched by the box; a particle outside the box is infeasible, is not evaluated (its point is
handed to the objective projected onto the box, masked and not counted) and cannot become pbest
or gbest; the velocity pulls it back. ``bounds = "clip"`` is the former rule (EvoloPy's port):
positions are clipped after every move and the velocity is kept, which pins coordinates on the
bounds (30-D F2: most runs end at 10-30 with coordinates at +-10; docs/algorithms.md).
Evaluations: ``agents`` at initialization and the particles inside the box each iteration
(``"clip"``: all, ``agents * (T + 1)``).
gbest is the best point ever evaluated, i.e. the frame's record (strict <, first index on ties,
which is what the code's sequential sweep does).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar

import numpy as np

from swarmpath.optimizers.base import Array, Optimizer, ParameterError, ParamValue
from swarmpath.optimizers.registry import register


@register
class PSO(Optimizer):
    name = "PSO"
    summary = (
        "Particle swarm optimization (Mirjalili-group code: w 0.9->0.2, c = 2, free flight; "
        "Vmax = 0.1 of the box)"
    )
    reference = (
        "Kennedy & Eberhart, Proc. ICNN 1995, 1942-1948; Shi & Eberhart, Proc. ICEC 1998, 69-73 "
        "(velocity and position update with inertia weight)"
    )
    defaults: ClassVar = {
        "c1": 2.0,
        "c2": 2.0,
        "w_max": 0.9,
        "w_min": 0.2,
        "vmax": 6.0,
        "vmax_mode": "range",
        "vmax_fraction": 0.1,
        "bounds": "fly",
    }
    choices: ClassVar = {"vmax_mode": ("absolute", "range", "none"), "bounds": ("fly", "clip")}
    min_agents = 1

    @classmethod
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        for key in ("c1", "c2", "w_max", "w_min"):
            if float(p[key]) < 0:
                raise ParameterError(f"PSO.{key} must be >= 0")
        if not float(p["vmax"]) > 0:
            raise ParameterError("PSO.vmax must be > 0")
        if not 0 < float(p["vmax_fraction"]) <= 1:
            raise ParameterError("PSO.vmax_fraction must be in (0, 1]")

    def expected_evaluations(self) -> tuple[int, int]:
        """The first population and every particle each iteration at most; with ``bounds =
        "fly"`` a particle outside the box is not evaluated, so a run may count as few as the
        first population."""
        most = self.N * (self.T + 1)
        return (self.N if self.p["bounds"] == "fly" else most), most

    def _initialize(self) -> None:
        self.X = self.random_population()
        self.V = np.zeros_like(self.X)
        self._tmp = np.empty_like(self.X)
        mode = self.p["vmax_mode"]
        self.clamp = mode != "none"
        self.vmax: Array | float
        if mode == "range":
            self.vmax = np.ascontiguousarray(
                np.broadcast_to(float(self.p["vmax_fraction"]) * (self.ub - self.lb), self.X.shape)
            )
            self.vmin: Array | float = -self.vmax
        else:
            self.vmax, self.vmin = float(self.p["vmax"]), -float(self.p["vmax"])
        self.pbest_f = self.evaluate(self.X)
        self.pbest = self.X.copy()

    def _iterate(self) -> None:
        p = self.p
        w_max, w_min = float(p["w_max"]), float(p["w_min"])
        w = w_max - (self.t - 1) * (w_max - w_min) / self.T
        c1, c2 = float(p["c1"]), float(p["c2"])
        X, V, tmp = self.X, self.V, self._tmp
        r1, r2 = self.rng.random_parts(2, self.N, self.d)
        # In place, on contiguous operands: V = w V + c1 r1 (P - X) + c2 r2 (G - X)
        np.subtract(self.pbest, X, out=tmp)
        r1 *= tmp
        np.copyto(tmp, self.best_position[:, None, :])
        tmp -= X
        r2 *= tmp
        if c1 == c2:  # c (a + b): one multiplication fewer (exactly c a + c b for c = 2)
            r1 += r2
            r1 *= c1
        else:
            r1 *= c1
            r2 *= c2
            r1 += r2
        V *= w
        V += r1
        if self.clamp:
            np.maximum(V, self.vmin, out=V)
            np.minimum(V, self.vmax, out=V)
        X += V
        if self.p["bounds"] == "clip":
            self.clip_inplace(X)
            F = self.evaluate(X)
        else:
            F = self._evaluate_inside(X)
        improved = np.nonzero(F < self.pbest_f)  # a minority of the agents: copy those rows
        self.pbest_f[improved] = F[improved]
        self.pbest[improved] = X[improved]

    def _evaluate_inside(self, X: Array) -> Array:
        """Values of the particles inside the box; +inf (not counted) for those outside."""
        lower, upper = self.full_bounds(self.N)
        outside = (X < lower) | (X > upper)
        if not outside.any():
            return self.evaluate(X)
        inside = np.logical_not(np.any(outside, axis=2))
        # The objective only ever sees points of the box: outside points go in projected,
        # masked out (their value is neither used nor counted).
        return self.evaluate(np.clip(X, lower, upper), mask=inside)
