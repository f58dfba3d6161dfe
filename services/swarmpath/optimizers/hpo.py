"""Hunter-Prey Optimizer, following the authors' equations and their sequential sweep.

Naruei, Keynia & Sabbagh Molahosseini, "Hunter-prey optimization: algorithm and applications",
Soft Computing 26 (2022) 1279-1314, doi 10.1007/s00500-021-06401-0; equations as restated in
Abdulsaheb & Kadhim, IJIES 16(2) 2023 (seed 001), eqs 1-10, whose Table 2 has an HPO column.

Per iteration t = 1..T (paper eq 5 with it = t, so C ends at 0.02):

* C = 1 - t (0.98 / T); kbest = max(1, round(C N)) with MATLAB rounding (half away from zero);
  the max(1, .) guard avoids the authors' index 0 when C N < 0.5 (N < 25 late in a run).
* Z = r2 where r1 >= C, r3 where r1 < C (eqs 3-4): r1, r3 per component, r2 one per agent
  (r1 and r3 are taken from one uniform with the same joint law, see ``_draw``).
* Agent i is a hunter with probability ``beta`` (r5 < beta, eq 10), else prey.
* Hunter (eq 2 / 10a): x' = x + 0.5[(2 C Z P - x) + (2 (1 - C) Z mu - x)], computed as the
  algebraically identical Z (C P + (1 - C) mu). mu is the population mean, P the agent with the
  kbest-th smallest Euclidean distance to mu (eqs 6-9; stable ordering, first index wins ties).
  The rule is *not* translation invariant: Z in [0, 1] multiplies absolute positions, so a
  hunter lands on a random point of the box spanned by the origin and C P + (1 - C) mu. This is
  the published rule (``hunter = "paper"``) and HPO's main exploration move; it favours optima
  at or near the origin (exact zeros on F1, F9, F11) and fails on shifted problems (docs).
  ``hunter = "centre"`` measures positions from the box centre instead of the origin (identical
  on the symmetric F1-F13 boxes; sensible for boxes around a robot); ``hunter = "relative"``,
  x' = x + Z (C P + (1 - C) mu - x), is translation invariant but leaves HPO without exploration
  (it stalls, docs).
* Prey (eq 9 / 10b): x' = T + C Z cos(2 pi r4) (T - x), T the best point found so far, r4 in
  [-1, 1] independent of Z. ``prey_step = "2Z"`` and ``prey_angle = "from_z"`` give the authors'
  MATLAB code instead: step 2 Z (no decay with C) and angle 2 pi (2 Z - 1), derived from Z.

Decisions:

* **Sequential update (the authors' sweep), by default.** The authors' code moves agents one
  by one: mu and the distance ranking are recomputed for every hunter from the partially
  updated population, and the target T is replaced as soon as an agent improves on it, so later
  agents of the same iteration already use it. ``update = "sequential"`` (default) does exactly
  that: a loop over agents, vectorized over runs, with the same random numbers as the
  synchronous update. ``update = "synchronous"`` moves every agent from the population, mu, P
  and T of the start of the iteration and updates T after the whole population was evaluated
  (Jacobi instead of Gauss-Seidel; no loop over agents, about 4x faster). This is a real change,
  not a detail: without the immediate target update the prey cloud contracts around a fixed T
  and stalls (shifted F1 ~1e-5 sequential vs ~1e4 synchronous; Table 2's F6, F12, F13 reached
  sequentially and missed synchronously: docs/algorithms.md).
* Positions are always replaced (no greedy selection), as in paper and code.
* Bounds: the new position is clipped to the box before it is evaluated.
* Evaluations: N at initialization and N per iteration, N (T + 1) in all (the MATLAB loop starts
  at it = 2 and makes N T). T is the best point ever evaluated, which is exactly what the frame
  reports.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, ClassVar, NamedTuple

import numpy as np
from numpy.typing import NDArray

from swarmpath.optimizers.base import Array, Optimizer, ParameterError, ParamValue
from swarmpath.optimizers.ops import take_rows
from swarmpath.optimizers.registry import register

TWO_PI = 2.0 * math.pi


def matlab_round(x: float) -> int:
    """MATLAB's ``round``: half away from zero (Python's ``round`` rounds half to even)."""
    a = abs(x)
    r = math.floor(a)
    if a - r >= 0.5:
        r += 1
    return int(math.copysign(r, x))


def hpo_c(t: int, T: int) -> float:
    """C of eq 5, computed in the order of the authors' code: 1 - t (0.98 / T)."""
    return 1.0 - t * (0.98 / T)


def hpo_kbest(c: float, n: int) -> int:
    """kbest = round(C n) (eq 8), at least 1."""
    return max(1, matlab_round(n * c))


@register
class HPO(Optimizer):
    name = "HPO"
    summary = "Hunter-Prey Optimizer (Naruei, Keynia & Sabbagh Molahosseini 2022), paper equations"
    reference = (
        "Naruei, Keynia & Sabbagh Molahosseini, Soft Computing 26 (2022) 1279-1314, eqs 1-10 "
        "(numbering of Abdulsaheb & Kadhim, IJIES 16(2) 2023)"
    )
    defaults: ClassVar[dict[str, Any]] = {
        "beta": 0.1,
        "prey_step": "CZ",
        "prey_angle": "independent",
        "hunter": "paper",
        "update": "sequential",
    }
    choices: ClassVar[dict[str, tuple[str, ...]]] = {
        "prey_step": ("CZ", "2Z"),
        "prey_angle": ("independent", "from_z"),
        "hunter": ("paper", "centre", "relative"),
        "update": ("synchronous", "sequential"),
    }
    min_agents = 1

    @classmethod
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        if not 0.0 <= float(p["beta"]) <= 1.0:
            raise ParameterError(f"{cls.name}.beta must be in [0, 1]")

    # ------------------------------------------------------------------------------------------
    def _initialize(self) -> None:
        self.problem_centre = 0.5 * (self.problem.lower + self.problem.upper)  # (R, d)
        self.X = self.random_population()
        self.evaluate(self.X)

    # Subclass hooks: further uniforms drawn together with HPO's numbers (fixed shapes).
    extra_slabs = 0  # further (N, d) arrays
    extra_rows = 0  # further (N,) arrays

    def _draw(self, C: float) -> Draw:
        """All random numbers of one iteration, in two rng calls.

        Returns C Z (eqs 3-4), the prey's step factor S = s Z cos(angle) with s = C or 2, the
        hunters as (run, agent) index arrays, and the extra slabs/rows a subclass asked for.
        r1 and r3 come from one uniform u: r1 < C is u < C, and given u < C, u / C is uniform
        on (0, 1) and independent of the event, so Z = u / C there (r3 is only used there) -
        the same joint law as two draws, one slab of random numbers fewer. C Z is then u where
        u < C and C r2 elsewhere.
        """
        independent = self.p["prey_angle"] == "independent"
        k = 2 if independent else 1
        U = self.rng.random(k + self.extra_slabs, self.N, self.d)  # (R, k, N, d)
        V = self.rng.random(2 + self.extra_rows, self.N)  # (R, 2, N)
        CZ = U[:, 0]
        cr2 = V[:, 0, :, None] * C
        # CZ = u where u < C, else C r2, as an arithmetic blend (a masked copy is slower here)
        keep = CZ < C
        CZ -= cr2
        CZ *= keep
        CZ += cr2
        # Angles are reduced to [-pi, pi) before the cosine (cheaper, same values/distribution).
        if independent:
            # cos(2 pi r4), r4 ~ U(-1, 1), has the law of cos(theta), theta ~ U(-pi, pi)
            S = U[:, 1]
            S -= 0.5
            S *= TWO_PI
        else:
            # the code's rr = 2 z - 1 in [-1, 1): cos(2 pi rr) = cos(2 pi (rr - round(rr)))
            S = np.multiply(CZ, 2.0 / C)
            S -= 1.0
            S -= np.rint(S)
            S *= TWO_PI
        np.cos(S, out=S)
        S *= CZ
        if self.p["prey_step"] == "2Z":
            S *= 2.0 / C
        hunters = np.nonzero(V[:, 1] < float(self.p["beta"]))
        return Draw(CZ, S, hunters, U[:, k:], V[:, 2:])

    def _hunter_anchor(self, C: float, kbest: int) -> tuple[Array, Array]:
        """(P, mu): the prey the hunters chase (eq 9) and the population mean, each (R, d)."""
        X = self.X
        mu = X.mean(axis=1)
        diff = X - mu[:, None, :]
        dist2 = np.einsum("rnd,rnd->rn", diff, diff)
        idx = np.argsort(dist2, axis=1, kind="stable")[:, kbest - 1]
        return take_rows(X, idx), mu

    def _hunter_move(self, z: Array, x: Array, anchor: Array, runs: NDArray[np.intp]) -> Array:
        """New hunter rows from the rows of Z, of the old positions and of the anchors
        C P + (1 - C) mu (each (h, d)); ``runs`` gives each row's run."""
        how = self.p["hunter"]
        if how == "paper":
            return z * anchor  # eq 2: Z (C P + (1 - C) mu)
        base = x if how == "relative" else self.problem_centre[runs]
        out = anchor - base  # base + Z (anchor - base)
        out *= z
        out += base
        return out

    def _iterate(self) -> None:
        C = hpo_c(self.t, self.T)
        kbest = hpo_kbest(C, self.N)
        draw = self._draw(C)
        if self.p["update"] == "synchronous":
            X = self._moved(draw, C, kbest, slice(0, self.N))
            self._clip_inplace(X)
            self.X = X
            self.evaluate(X)
            return
        # The authors' sweep: agent i moves from the population as agents 0..i-1 left it (mu and
        # P recomputed) and toward the best point including their evaluations. A loop over
        # agents (vectorized over runs), or the same values in a few batches (``_sweep``).
        if self.R == 1 and self.problem.rowwise:
            self._sweep(draw, C, kbest)
            return
        for i in range(self.N):
            rows = slice(i, i + 1)
            X = self._moved(draw, C, kbest, rows)
            self._clip_inplace(X)
            self.X[:, rows] = X
            self.evaluate(X)

    def _sweep(self, draw: Draw, C: float, kbest: int) -> None:
        """The sequential sweep of one run in batches, with the values of the loop over agents.

        In the loop, a prey's new position depends on the agents moved before it only through
        the target T (the best point evaluated so far), a hunter's also through the population
        (mu and P). So a block of agents, from agent i up to the next hunter after it, is moved
        at once from the current T and the current population (the population is only read for
        agent i, when it is a hunter), evaluated in one call (``problem.rowwise``: a point's
        value does not depend on the batch), and kept up to and including its first agent that
        improves on T: until then every move used the T the loop would have used. The next block
        starts after it, from the new T. The evaluations counted and the best point recorded are
        those of the loop (``evaluate``'s record: strict improvement, as agent after agent). About
        (improvements of T + hunters + 1) objective calls per iteration instead of N.
        """
        _, agents = draw.hunters
        i = 0
        while i < self.N:
            later = agents[agents > i]
            end = int(later[0]) if later.size else self.N
            X = self._moved(draw, C, kbest, slice(i, end))
            self._clip_inplace(X)
            F = np.asarray(self.problem.objective(X, self.rng), dtype=float)
            better = np.flatnonzero(np.where(np.isnan(F[0]), np.inf, F[0]) < self.best_fitness[0])
            stop = X.shape[1] if better.size == 0 else int(better[0]) + 1
            self.X[:, i : i + stop] = X[:, :stop]
            # ``record`` of the kept agents: counted, and the last one, if it improved, is the
            # new best (every other kept value is at least the old best)
            self.evaluations += stop
            if better.size:
                self.best_fitness = F[:, stop - 1].copy()
                self.best_position = X[:, stop - 1].copy()
            i += stop

    def _hunter_rows(self, draw: Draw, rows: slice) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        """(run, agent-within-rows) of the hunters among ``rows``."""
        r, i = draw.hunters
        keep = (i >= rows.start) & (i < rows.stop)
        return r[keep], i[keep] - rows.start

    def _moved(self, draw: Draw, C: float, kbest: int, rows: slice) -> Array:
        """New positions (R, len(rows), d) of agents ``rows`` from the current population."""
        X = self.X[:, rows].copy()
        r, i = self._hunter_rows(draw, rows)
        hunt = None
        if r.size:
            P, mu = self._hunter_anchor(C, kbest)
            anchor = C * P + (1.0 - C) * mu
            hunt = self._hunter_move(draw.CZ[:, rows][r, i] / C, X[r, i], anchor[r], r)
        T = self.best_position[:, None, :]
        np.subtract(T, X, out=X)  # prey: x' = T + S (T - x)
        X *= draw.S[:, rows]
        X += T
        if hunt is not None:
            X[r, i] = hunt
        return X

    def _clip_inplace(self, X: Array) -> None:
        np.maximum(X, self.lb, out=X)
        np.minimum(X, self.ub, out=X)


class Draw(NamedTuple):
    CZ: Array  # (R, N, d): C times Z
    S: Array  # (R, N, d) prey step factor
    hunters: tuple[NDArray[np.intp], ...]  # (runs, agents) of the hunters
    slabs: Array  # (R, extra_slabs, N, d)
    rows: Array  # (R, extra_rows, N)
