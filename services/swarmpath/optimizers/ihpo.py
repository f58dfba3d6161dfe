"""Improved Hunter-Prey Optimizer (IHPO).

Abdulsaheb & Kadhim, "Multi-Objective Robot Path Planning Using an Improved Hunter Prey
Optimization Algorithm", IJIES 16(2) 2023 (seed 001), eqs 11-14, on top of HPO (eqs 1-10, see
:mod:`swarmpath.optimizers.hpo`, whose decisions all carry over: sequential sweep, no greedy
selection, clip before evaluation, N (T + 1) evaluations).

The paper adds beta = 2 rand - 1 (eq 11), CP = sin(C - t/T) (eq 12) and alpha = beta CP (eq 13),
and prints the update (eq 14) as

    hunter (14a): x' = x + 0.5 [(alpha 2 C Z P - x) + (2 (1 - C) Z mu - x)]
    prey   (14b): x' = T + alpha C Z cos(2 pi r4) (T - x)

It leaves open what C is inside CP, how often beta is drawn and, read together with its prose
("randomization factor", "changing the direction of the search"), what alpha really scales. Our
readings, as parameters:

* ``alpha_on`` - what alpha multiplies in the branches it applies to:
    - ``"literal"`` (default): eq 14 exactly as printed. 14a expands to
      x' = Z (alpha C P + (1 - C) mu): alpha scales the prey position P itself, which pulls
      hunters toward the origin (on top of HPO's own pull, see ``hunter``); 14b is
      x' = T + alpha C Z cos(2 pi r4)(T - x).
    - ``"step"``: the random step of each rule about its own anchor. Prey: eq 14b as printed;
      hunter: x' = x + alpha (h - x), h the HPO hunter position. alpha adds no pull toward the
      origin (the default until issue 10: it made IHPO worse than HPO on every function).
    - ``"displacement"``: x' = x + alpha (x'_HPO - x) for both rules.
    - ``"position"``: x' = alpha x'_HPO, the whole new position (strongest origin bias: every
      move lands on a point of the segment from the origin through x'_HPO, or its mirror).
* ``alpha_branches``: ``"both"`` (eq 14, default), ``"hunter"`` or ``"prey"`` only.
* ``beta_draw``: beta per ``"agent"`` and iteration (default), per ``"iteration"`` (one for the
  population) or per ``"dimension"`` (one per component).
* ``cp_c``: C inside CP is HPO's C = 1 - 0.98 t/T (``"hpo"``, default: the same symbol in the
  same paper), so CP = sin(1 - 1.98 t/T) falls from sin 1 = 0.84 through 0 at t ~ 0.505 T to
  sin(-0.98) = -0.83; or ``"one"``, a constant C = 1: CP = sin(1 - t/T) falls from 0.84 to 0.
  Since beta is symmetric about 0, only |CP| matters for the law of alpha.
* ``hunter``: HPO's hunter rule, inherited unchanged (``"paper"``) so that IHPO and HPO differ
  only by alpha. That rule is itself origin-biased (see :mod:`swarmpath.optimizers.hpo`), and
  the printed 14a adds to it. ``"relative"`` removes HPO's bias, and then only ``literal`` and
  ``position`` still show one (tests/test_opt_hpo_rfo.py, docs). With ``"centre"`` (the
  planners), 14a's alpha scales P about the box centre too, so no reading pulls toward the
  world origin.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from swarmpath.optimizers.base import Array
from swarmpath.optimizers.hpo import HPO, Draw
from swarmpath.optimizers.registry import register


@register
class IHPO(HPO):
    name = "IHPO"
    summary = "Improved Hunter-Prey Optimizer (Abdulsaheb & Kadhim 2023), alpha = beta CP"
    reference = (
        "Abdulsaheb & Kadhim, IJIES 16(2) 2023, eqs 11-14, on HPO (Naruei et al., Soft Computing "
        "26 (2022) 1279-1314)"
    )
    defaults: ClassVar[dict[str, Any]] = {
        **HPO.defaults,
        "alpha_on": "literal",
        "alpha_branches": "both",
        "beta_draw": "agent",
        "cp_c": "hpo",
    }
    choices: ClassVar[dict[str, tuple[str, ...]]] = {
        **HPO.choices,
        "alpha_on": ("step", "displacement", "literal", "position"),
        "alpha_branches": ("both", "hunter", "prey"),
        "beta_draw": ("agent", "iteration", "dimension"),
        "cp_c": ("hpo", "one"),
    }

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        per_dim = self.p["beta_draw"] == "dimension"
        self.extra_slabs = 1 if per_dim else 0
        self.extra_rows = 0 if per_dim else 1
        self._terms: tuple[Draw, Array, Array | None] | None = None

    def _alpha(self, cp: float, slabs: Array, rows: Array) -> Array:
        """alpha = (2 u - 1) CP, broadcastable to (R, N, d)."""
        how = self.p["beta_draw"]
        if how == "dimension":
            u = slabs[:, 0]  # (R, N, d)
        elif how == "agent":
            u = rows[:, 0, :, None]  # (R, N, 1)
        else:
            u = rows[:, 0, :1, None]  # (R, 1, 1): the first agent's number serves everyone
        return (2.0 * u - 1.0) * cp

    def _iteration_terms(self, draw: Draw, C: float) -> tuple[Array, Array | None]:
        """alpha (R, N, d) of this iteration and, where eq 14b applies it, the prey's factor
        S alpha: computed once per draw (the sweep moves the agents in several blocks), the same
        products as per block."""
        cached = self._terms
        if cached is not None and cached[0] is draw:
            return cached[1], cached[2]
        cc = C if self.p["cp_c"] == "hpo" else 1.0
        cp = math.sin(cc - self.t / self.T)
        alpha = np.broadcast_to(self._alpha(cp, draw.slabs, draw.rows), self.X.shape)
        scaled = None
        if self.p["alpha_branches"] != "hunter" and self.p["alpha_on"] in ("step", "literal"):
            scaled = draw.S * alpha  # eq 14b: T + alpha C Z cos(2 pi r4) (T - x)
        self._terms = (draw, alpha, scaled)
        return alpha, scaled

    def _moved(self, draw: Draw, C: float, kbest: int, rows: slice) -> Array:
        alpha_all, scaled = self._iteration_terms(draw, C)
        X = self.X[:, rows].copy()
        alpha = alpha_all[:, rows]
        branches = self.p["alpha_branches"]
        on = self.p["alpha_on"]
        r, i = self._hunter_rows(draw, rows)

        # hunters (a few rows): HPO's move h, then alpha
        hunt = None
        if r.size:
            P, mu = self._hunter_anchor(C, kbest)
            z, x = draw.CZ[:, rows][r, i] / C, X[r, i]
            a = alpha[r, i]  # (h, d)
            if branches == "prey":
                hunt = self._hunter_move(z, x, C * P[r] + (1.0 - C) * mu[r], r)
            elif on == "literal":  # eq 14a: alpha scales the prey position
                if self.p["hunter"] == "centre":  # positions measured from the box centre
                    o = self.problem_centre[r]
                    anchor = a * (C * (P[r] - o)) + (1.0 - C) * (mu[r] - o) + o
                else:
                    anchor = a * (C * P[r]) + (1.0 - C) * mu[r]
                hunt = self._hunter_move(z, x, anchor, r)
            else:
                h = self._hunter_move(z, x, C * P[r] + (1.0 - C) * mu[r], r)
                hunt = a * h if on == "position" else x + a * (h - x)

        # prey on the selected rows (hunter rows are overwritten below)
        T = self.best_position[:, None, :]
        S = draw.S[:, rows]
        if branches == "hunter" or on in ("step", "literal"):
            if scaled is not None:
                S = scaled[:, rows]
            np.subtract(T, X, out=X)
            X *= S
            X += T
        elif on == "displacement":  # x + alpha (T + S (T - x) - x) = x + alpha (1 + S)(T - x)
            D = T - X
            D *= (S + 1.0) * alpha
            X += D
        else:  # position: alpha (T + S (T - x))
            np.subtract(T, X, out=X)
            X *= S
            X += T
            X *= alpha
        if hunt is not None:
            X[r, i] = hunt
        return X
