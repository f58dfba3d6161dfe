"""Salp Swarm Algorithm (salp chains; not the sparrow search algorithm that shares the acronym).

Mirjalili, Gandomi, Mirjalili, Saremi, Faris & Mirjalili, "Salp Swarm Algorithm: A bio-inspired
optimizer for engineering design problems", Adv. Eng. Softw. 114 (2017) 163-191, eqs (3.1)-(3.4)
of the single-objective SSA; semantics of the authors' ``SSA.m`` (v1.0):

* Leaders (eq 3.1): x_ij = F_j + c1((ub_j - lb_j) c2 + lb_j) if c3 < 0.5, else
  F_j - c1((ub_j - lb_j) c2 + lb_j), with c2, c3 ~ U(0, 1) per component and F the food source
  (the best point found so far). The paper branches on c3 >= 0, which is always true for
  c3 in [0, 1]; the code's 0.5 threshold is used.
* c1 = 2 exp(-(4 t / T)^2) (eq 3.2) for iterations t = 1..T (``SSA.m`` runs l = 2..T because it
  counts the initial evaluation as iteration 1; the frame counts it separately, see the docs).
* Followers (eq 3.4): x_i = (x_i + x_{i-1}) / 2 where x_{i-1} has *already* moved in this
  iteration (the code's in-place sweep). The sweep is computed without a loop over agents in
  closed form, y_i = 2^-i y_0 + sum_j 2^-(i-j+1) x_j (y_0 the last leader): one small matrix
  product per run whose weights are powers of two, the same values up to rounding.
* Who leads: the code makes the first half of the population leaders (i <= N/2, 1-based); the
  paper has a single leader (the first salp). ``leaders = "half"`` (default, code) or ``"one"``
  (paper).
* No greedy selection: every salp takes its new position. The food source is the best point ever
  evaluated (strict <, first index on ties: the code's sequential update), i.e. the frame's
  record.

Bounds: all salps are moved first (followers average with *unclipped* predecessors, as in the
code), then every position is clipped to the box and evaluated; the clipped positions are kept.
Evaluations: ``agents`` at initialization and ``agents`` per iteration, ``agents * (T + 1)``.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from swarmpath.optimizers.base import Optimizer
from swarmpath.optimizers.registry import register


@register
class SSA(Optimizer):
    name = "SSA"
    summary = "Salp Swarm Algorithm (Mirjalili et al. 2017), authors' SSA.m (half the chain leads)"
    reference = (
        "Mirjalili et al., Adv. Eng. Softw. 114 (2017) 163-191, eqs 3.1-3.4 (single-objective SSA)"
    )
    defaults: ClassVar = {"leaders": "half"}
    choices: ClassVar = {"leaders": ("half", "one")}
    min_agents = 2

    @staticmethod
    def c1(t: int, T: int) -> float:
        """Eq (3.2): the exploration/exploitation coefficient at iteration t of T."""
        return 2.0 * math.exp(-((4.0 * t / T) ** 2))

    @staticmethod
    def chain(k: int) -> NDArray[np.float64]:
        """The followers' sweep (eq 3.4) as a (k, k + 1) matrix applied to [leader, followers].

        y_0 = the last (moved) leader, y_i = (y_{i-1} + x_i) / 2: in closed form
        y_i = 2^-i y_0 + sum_{j=1..i} 2^-(i-j+1) x_j, a lower-triangular matrix of powers of two
        (one small matrix product per run); the leader's own row is left out.
        """
        i = np.arange(k + 1)
        gap = i[:, None] - i[None, :]
        chain = np.where(gap >= 0, 0.5 ** (gap + 1.0), 0.0)
        chain[:, 0] *= 2.0
        return np.ascontiguousarray(chain[1:])

    def _initialize(self) -> None:
        self.n_leaders = self.N // 2 if self.p["leaders"] == "half" else 1
        self.X = self.random_population()
        self.evaluate(self.X)
        NL = self.n_leaders
        lower, upper = self.full_bounds(NL)
        self._span = upper - lower  # (R, NL, d), contiguous
        self._lower = lower
        self._chain = self.chain(self.N - NL)

    def _iterate(self) -> None:
        NL, X = self.n_leaders, self.X
        c1 = self.c1(self.t, self.T)
        lead, c3 = self.rng.random_parts(2, NL, self.d)  # c2, c3
        lead *= self._span
        lead += self._lower  # (ub - lb) c2 + lb
        lead *= c1
        np.negative(lead, out=lead, where=c3 >= 0.5)
        lead += self.best_position[:, None, :]
        X[:, :NL] = lead
        # followers: the chain starts at the last (moved, unclipped) leader
        X[:, NL:] = np.matmul(self._chain, X[:, NL - 1 :])
        self.clip_inplace(X)
        self.evaluate(X)
