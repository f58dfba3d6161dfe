"""Particle Swarm Optimization with a linearly decreasing inertia weight.

Kennedy & Eberhart, "Particle swarm optimization", Proc. ICNN 1995, 1942-1948 (velocity and
position update); inertia weight from Shi & Eberhart, "A modified particle swarm optimizer",
Proc. IEEE ICEC 1998, 69-73:

    v_i <- w v_i + c1 r1 (pbest_i - x_i) + c2 r2 (gbest - x_i)        (velocity update)
    x_i <- x_i + v_i                                                  (position update)

with r1, r2 ~ U(0, 1) drawn per component. Defaults are the setting of the Mirjalili group's PSO
code (the one the GWO/SSA papers and the seeds' comparison tables use; EvoloPy ``PSO.py`` is a
port): c1 = c2 = 2, w = w_max - (t - 1)(w_max - w_min)/T for iterations t = 1..T (0.9 down to
0.2 + 0.7/T, the code's l = 0..T-1), velocities start at 0 and are clamped to |v| <= Vmax = 6
per component, an *absolute* bound independent of the box (``vmax_mode = "absolute"``).
Alternatives: ``vmax_mode = "range"`` clamps to ``vmax_fraction`` (ub - lb) per dimension,
``"none"`` does not clamp.

pbest and gbest change on strict improvement only; positions are never greedily reverted.

Bounds: positions are clipped to the box after every move, before evaluation (the code clips
the stored position, the velocity is left as it is).
Evaluations: ``agents`` at initialization and ``agents`` per iteration, ``agents * (T + 1)``.
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
    summary = "Particle swarm optimization (Mirjalili-group setting: w 0.9->0.2, c = 2, Vmax = 6)"
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
        "vmax_mode": "absolute",
        "vmax_fraction": 0.2,
    }
    choices: ClassVar = {"vmax_mode": ("absolute", "range", "none")}
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
        self.clip_inplace(X)
        F = self.evaluate(X)
        improved = np.nonzero(F < self.pbest_f)  # a minority of the agents: copy those rows
        self.pbest_f[improved] = F[improved]
        self.pbest[improved] = X[improved]
