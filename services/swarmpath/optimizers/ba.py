"""Bat Algorithm (echolocating micro-bats).

Yang, "A New Metaheuristic Bat-Inspired Algorithm", in Nature Inspired Cooperative Strategies for
Optimization (NICSO 2010), Studies in Computational Intelligence 284, Springer 2010, 65-74,
eqs (2)-(6); defaults from the author's demo ``bat_algorithm.m`` (MATLAB File Exchange 37582),
whose choices fill the gaps of the paper, except the local walk (see below):

* Frequency f_i = f_min + (f_max - f_min) beta, beta ~ U(0, 1) per bat (eq 2), f_min = 0,
  f_max = 2 (demo).
* Velocity and position (eqs 3-4): v_i <- v_i + (x* - x_i) f_i, s_i = x_i + v_i, with v_0 = 0.
  The paper writes (x_i - x*) f_i with f_i >= 0, which makes the (x, v) recursion divergent
  (an eigenvalue > 1); the demo draws Q = Q_min + (Q_min - Q_max) rand in [-2, 0] (a sign
  "typo") and so moves *toward* x*, which is what we do (``velocity = "toward"``). The paper's
  literal sign is available as ``velocity = "away"`` (it diverges and ends on the bounds).
* Local walk with probability 1 - r_i (``rand > r_i``), around the best: s_i = x* + eps A_mean
  with eps ~ U(-1, 1) per component and A_mean the mean loudness (eq 5, ``local_walk =
  "paper"``, default). The demo's walk x* + 0.001 N(0, 1) (``local_walk = "demo"``, scale
  ``walk_scale``) is *not* the default: with it the demo does not converge even on the 2-D
  sphere (a literal loop port of ``bat_algorithm.m``, 20 bats, 200 iterations on [-100, 100]^2,
  ends between 1e-9 and 180; see the docs), because its steps of 1e-3 are the only contraction
  the algorithm has.
* Acceptance: x_i <- s_i if f(s_i) <= f(x_i) and rand < A_i (demo, ``acceptance = "own"``);
  ``acceptance = "best"`` is the paper's pseudo-code test f(s_i) < f(x*) (x* before the
  iteration) instead of the bat's own fitness.
* Loudness and pulse rate: the demo keeps A = 0.5 and r = 0.5 constant (``updates = "demo"``).
  ``updates = "paper"`` applies eq (6) to every bat whose move was accepted: A_i <- alpha A_i,
  r_i <- r_0 (1 - exp(-gamma t)), alpha = gamma = 0.9, starting from A_i = A_0, r_i = r_0.

Decisions of the vectorized port: the demo updates x* bat by bat inside its sweep (later bats
steer toward a best found earlier in the same iteration, and it takes ties, ``<=``); we steer all
bats by the best point ever evaluated at the start of the iteration (the frame's record, strict
<). The demo applies its bounds to the *old* position and evaluates s_i unclipped (so its best
can lie outside the box); we clip s_i before evaluating it and keep the clipped point.

Bounds: candidates s_i are clipped to the box before evaluation; velocities are not changed.
Evaluations: ``agents`` at initialization and ``agents`` per iteration, ``agents * (T + 1)``,
like the demo (N + N T).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import ClassVar

import numpy as np

from swarmpath.optimizers.base import Optimizer, ParameterError, ParamValue
from swarmpath.optimizers.registry import register


@register
class BA(Optimizer):
    name = "BA"
    summary = (
        "Bat Algorithm (Yang 2010): demo settings (A = r = 0.5, f in [0, 2]), paper local walk"
    )
    reference = (
        "Yang, NICSO 2010, Studies in Computational Intelligence 284, 65-74, eqs 2-6; "
        "author's demo bat_algorithm.m (File Exchange 37582)"
    )
    defaults: ClassVar = {
        "f_min": 0.0,
        "f_max": 2.0,
        "loudness": 0.5,
        "pulse_rate": 0.5,
        "alpha": 0.9,
        "gamma": 0.9,
        "walk_scale": 0.001,
        "updates": "demo",
        "local_walk": "paper",
        "acceptance": "own",
        "velocity": "toward",
    }
    choices: ClassVar = {
        "updates": ("demo", "paper"),
        "local_walk": ("demo", "paper"),
        "acceptance": ("own", "best"),
        "velocity": ("toward", "away"),
    }
    min_agents = 1

    @classmethod
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        if not float(p["f_max"]) >= float(p["f_min"]):
            raise ParameterError("BA.f_max must be >= BA.f_min")
        for key in ("loudness", "pulse_rate"):
            if not 0.0 <= float(p[key]) <= 1.0:
                raise ParameterError(f"BA.{key} must be in [0, 1]")
        if not 0.0 < float(p["alpha"]) < 1.0:
            raise ParameterError("BA.alpha must be in (0, 1)")
        if not float(p["gamma"]) > 0:
            raise ParameterError("BA.gamma must be > 0")
        if not float(p["walk_scale"]) >= 0:
            raise ParameterError("BA.walk_scale must be >= 0")

    def _initialize(self) -> None:
        self.X = self.random_population()
        self.V = np.zeros_like(self.X)
        self.F = self.evaluate(self.X)
        self.A = np.full((self.R, self.N), float(self.p["loudness"]))
        self.r = np.full((self.R, self.N), float(self.p["pulse_rate"]))

    def _iterate(self) -> None:
        p = self.p
        N, d = self.N, self.d
        X, V = self.X, self.V
        best = self.best_position[:, None, :]  # (R, 1, d)
        u = self.rng.random(3, N)  # beta, pulse draw, loudness draw: (R, 3, N)
        f_min, f_max = float(p["f_min"]), float(p["f_max"])
        freq = (f_min + (f_max - f_min) * u[:, 0])[:, :, None]
        S = np.subtract(best, X) if p["velocity"] == "toward" else np.subtract(X, best)
        S *= freq
        V += S
        np.add(X, V, out=S)
        # local walk around the best for bats with rand > r_i
        if p["local_walk"] == "demo":
            walk = self.rng.normal(N, d)
            walk *= float(p["walk_scale"])
        else:
            walk = self.rng.random(N, d)
            walk *= 2.0
            walk -= 1.0
            walk *= self.A.mean(axis=1)[:, None, None]
        walk += best
        np.copyto(S, walk, where=(u[:, 1] > self.r)[:, :, None])
        np.maximum(S, self.lb, out=S)
        np.minimum(S, self.ub, out=S)
        reference = self.F if p["acceptance"] == "own" else self.best_fitness[:, None].copy()
        Fn = self.evaluate(S)
        if p["acceptance"] == "own":
            accept = (Fn <= reference) & (u[:, 2] < self.A)
        else:
            accept = (Fn < reference) & (u[:, 2] < self.A)
        np.copyto(X, S, where=accept[:, :, None])
        np.copyto(self.F, Fn, where=accept)
        if p["updates"] == "paper":
            self.A[accept] *= float(p["alpha"])
            self.r[accept] = float(p["pulse_rate"]) * (1.0 - math.exp(-float(p["gamma"]) * self.t))
