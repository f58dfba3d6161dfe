"""Grey Wolf Optimizer, as its authors published and coded it.

Mirjalili, Mirjalili & Lewis, "Grey Wolf Optimizer", Adv. Eng. Softw. 69 (2014) 46-61,
eqs (3.1)-(3.7); semantics of the authors' GWO.m:

* alpha, beta and delta are best-so-far records updated agent by agent in population order with
  strict inequalities, and a new alpha does *not* demote the old alpha to beta (nor beta to delta).
  The sequential sweep is computed exactly without a loop over agents (see ``_update_leaders``).
* A = 2a r1 - a and C = 2 r2 are drawn per component and per leader; a = 2 - 2(t-1)/T for
  iterations t = 1..T (the code's l = 0..T-1), so a goes from 2 down to 2/T.
* Positions are the mean of the three leader-guided trial vectors (eq 3.7), with no greedy
  selection; they are clipped to the box before evaluation.

Parameter ``leaders = "elitist"`` swaps in the textbook reading (the three best distinct points
ever found, with demotion) for users who want it; it is not the published algorithm.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar

import numpy as np

from swarmpath.optimizers.base import Array, Optimizer, ParameterError, ParamValue
from swarmpath.optimizers.registry import register


@register
class GWO(Optimizer):
    name = "GWO"
    summary = "Grey Wolf Optimizer (Mirjalili et al. 2014), authors' leader update"
    reference = "Mirjalili, Mirjalili & Lewis, Adv. Eng. Softw. 69 (2014) 46-61, eqs 3.1-3.7"
    defaults: ClassVar = {"a_max": 2.0, "leaders": "authors"}
    choices: ClassVar = {"leaders": ("authors", "elitist")}
    min_agents = 1

    @classmethod
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        if not float(p["a_max"]) > 0:
            raise ParameterError("GWO.a_max must be > 0")

    def _initialize(self) -> None:
        self.X = self.random_population()
        self.scores = np.full((self.R, 3), np.inf)  # alpha, beta, delta
        self.leaders = np.zeros((self.R, 3, self.d))
        self._evaluate_and_rank()

    def _evaluate_and_rank(self) -> None:
        self.X = self.clip(self.X)
        F = self.evaluate(self.X)
        if self.p["leaders"] == "authors":
            self._update_leaders(F)
        else:
            self._update_elitist(F)

    def _update_leaders(self, F: Array) -> None:
        """Exact vectorized replay of GWO.m's sequential, non-demoting leader update.

        Sweeping agents in order: alpha takes f if f < alpha; otherwise beta takes f if
        alpha < f < beta; otherwise delta takes f if alpha < f, beta < f and f < delta. Since alpha
        only decreases, "f > alpha at the time" equals f > (running min of alpha before agent i),
        so each record is a masked minimum whose first attaining index is the strict-< winner.
        """
        R = F.shape[0]
        rows = np.arange(R)
        a0, b0, d0 = self.scores[:, 0], self.scores[:, 1], self.scores[:, 2]
        # alpha before agent i (exclusive running min, seeded with the stored alpha)
        run_a = np.minimum.accumulate(np.concatenate([a0[:, None], F], axis=1), axis=1)
        a_before = run_a[:, :-1]
        cand_b = np.where(F > a_before, F, np.inf)
        run_b = np.minimum.accumulate(np.concatenate([b0[:, None], cand_b], axis=1), axis=1)
        b_before = run_b[:, :-1]
        cand_d = np.where((F > a_before) & (F > b_before), F, np.inf)

        for k, (cand, old) in enumerate(((F, a0), (cand_b, b0), (cand_d, d0))):
            idx = np.argmin(cand, axis=1)  # first index of the minimum: strict-< sweep winner
            best = cand[rows, idx]
            take = best < old
            self.scores[:, k] = np.where(take, best, old)
            self.leaders[:, k] = np.where(take[:, None], self.X[rows, idx], self.leaders[:, k])

    def _update_elitist(self, F: Array) -> None:
        pool_f = np.concatenate([self.scores, F], axis=1)
        pool_x = np.concatenate([self.leaders, self.X], axis=1)
        order = np.argsort(pool_f, axis=1, kind="stable")[:, :3]
        self.scores = np.take_along_axis(pool_f, order, axis=1)
        self.leaders = np.take_along_axis(pool_x, order[:, :, None], axis=1)

    def control(self) -> float:
        """The control parameter a of iteration ``self.t`` (1..T): a_max (1 - (t-1)/T), linear
        from a_max down to a_max/T as GWO.m computes it. Variants with another schedule
        override this method alone (e.g. the example plugin's mGWO, examples/)."""
        return float(self.p["a_max"]) * (1.0 - (self.t - 1) / self.T)

    def _iterate(self) -> None:
        a = self.control()
        r = self.rng.random(2, 3, self.N, self.d)  # r1, r2 for each leader: (R, 2, 3, N, d)
        L = self.leaders[:, :, None, :]  # (R, 3, 1, d)
        # In-place arithmetic: large temporaries cost more than the flops here.
        A = r[:, 0]
        A *= 2.0 * a
        A -= a  # A = 2 a r1 - a
        D = r[:, 1]
        D *= 2.0  # C = 2 r2
        D *= L
        D -= self.X[:, None]
        np.abs(D, out=D)  # D = |C L - X|
        A *= D
        # X = mean_k (L_k - A_k D_k)
        self.X = (L.sum(axis=1) - A.sum(axis=1)) / 3.0
        self._evaluate_and_rank()
