"""Fitness Dependent Optimizer (scout bees choosing a new hive).

Abdullah & Rashid, "Fitness Dependent Optimizer: Inspired by the Bee Swarming Reproductive
Process", IEEE Access 7 (2019) 43473-43486, doi 10.1109/ACCESS.2019.2907012, eqs (1)-(5);
semantics of the author's code (github.com/Jaza-Abdullah/FDO: ``FDO.m``, ``Levy.m``,
``Main.m``), with weight factor wf = 0 as in ``Main.m``. The repository has two versions; the
default is the later one (``weight_rule = "threshold"``, ``trials = "nested"``), the 2019 one
(which is also the logic of the author's Java ``FDOSingleObjective``) is
``weight_rule = "ratio"``, ``trials = "split"``.

* Fitness weight (eq 2): fw = f(x*) / f(x_i) - wf (without the paper's absolute value, as both
  codes compute it). ``"threshold"`` (later code): fw = 0.2 when f(x*) < 0.05 f(x_i), else the
  ratio; ``"ratio"`` (2019 code): always the ratio.
* pace, per component, with r a fresh Levy step (``Levy.m``: Mantegna, beta = 1.5, 0.01 u /
  |v|^(2/3)): pace = x r if fw = 1 (the best bee: a multiplicative random walk), (x* - x) r if
  fw = 0, (x* - x) fw sign(r) otherwise (eqs 3-5; the code's distance is x* - x, the paper's
  x - x*, the same in distribution because the sign is random).
* Trial 1: x1 = x + pace (eq 1), kept if f(x1) < f(x) (greedy, strict).
* If trial 1 fails and the bee has moved before (it has a stored pace vector), trial 2:
  x2 = x + (x* - x) fw + pace_prev ("continue the previous direction").
  ``"nested"`` (later code): if trial 2 fails too, trial 3: x3 = x + x r with a fresh Levy r per
  component; a bee that never moved stops after trial 1. At most three evaluations per bee per
  iteration. ``"split"`` (2019 code): a bee that never moved tries trial 3 instead of trial 2;
  at most two evaluations. Every trial is kept only if it beats f(x).
* On any acceptance the bee's stored pace becomes this iteration's trial-1 pace (``FDO.m``
  stores the pace vector of its temporary bee, whichever trial was accepted).

Decisions of the vectorized port (details and evidence in docs/algorithms.md, FDO):

* ``FDO.m`` recomputes the best bee before every bee, so a bee sees the moves of the bees before
  it in the same iteration. We use the best bee at the start of the iteration for everyone (a
  synchronous update; a loop over agents is not an option). x* is the best bee (first index on
  ties), which is also the best point ever evaluated because every move is greedy.
* When f(x*) = 0 the code keeps the *previous bee's* fw (a stale value); we use fw = 0 (then
  pace = (x* - x) r, the code's fw = 0 branch). When f(x_i) = 0 but f(x*) != 0 (possible only
  with negative objective values) the ratio is infinite: we use the pace x r, as the author's
  Java code does for an infinite pace, and fw = 1 in trial 2. Other non-finite ratios give 0.
* The trial-3 Levy step of a bee in the general branch is |L| sign(v), L = 0.01 sigma u / |v|^(2/3)
  being its trial-1 step: trials 1 and 2 used only sign(L) = sign(u), and sign(u), sign(v), |L|
  are independent (u, v symmetric), so this is an exact, independent Levy step for half the cost
  and without a uniform draw. Bees of the fw = 1 / fw = 0 branches used |L| already; they take
  their trial-3 step from one extra Levy row per run (shared only if several such bees reach
  trial 3 in the same iteration: ties with the best, or f(x*) = 0).
* The general-branch pace (x* - x) fw sign(r) is computed as copysign((x* - x) fw, r), i.e.
  |(x* - x) fw| sign(r): the same law (sign(r) is a fair coin independent of everything else).

Bounds: ``bound = "clip"`` (default) clips every trial point to the box. ``bound = "author"`` is
the author's rule: a component above ub becomes ub L, below lb becomes lb L, with L a fresh
Levy step, which puts violators next to 0 -- a pull to the origin that flatters functions whose
optimum is at 0 -- and then clips, so that a heavy-tailed L or a box without 0 stays in the box.
Evaluations: ``agents`` at initialization; per iteration, every bee's trial 1 plus each trial 2
and trial 3 really tried (``evaluate(mask=...)``: the untried candidates of the vectorized
arrays are neither counted nor eligible as best). ``FDO.m``'s own count is meaningless (it
re-calls its fitness function on known points).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar

import numpy as np

from swarmpath.optimizers.base import Array, Optimizer, ParameterError, ParamValue
from swarmpath.optimizers.ops import mantegna_sigma
from swarmpath.optimizers.registry import register

_LEVY_SCALE = 0.01 * mantegna_sigma(1.5)  # Levy.m: beta = 3/2, step 0.01 u / |v|^(1/beta)


@register
class FDO(Optimizer):
    name = "FDO"
    summary = "Fitness Dependent Optimizer (Abdullah & Rashid 2019), author's FDO.m, wf = 0"
    reference = (
        "Abdullah & Rashid, IEEE Access 7 (2019) 43473-43486, doi 10.1109/ACCESS.2019.2907012, "
        "eqs 1-5"
    )
    defaults: ClassVar = {
        "weight_factor": 0.0,
        "weight_rule": "threshold",
        "trials": "nested",
        "bound": "clip",
    }
    choices: ClassVar = {
        "weight_rule": ("threshold", "ratio"),
        "trials": ("nested", "split"),
        "bound": ("clip", "author"),
    }
    min_agents = 1

    @classmethod
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        if not 0.0 <= float(p["weight_factor"]) <= 1.0:
            raise ParameterError("FDO.weight_factor must be in [0, 1]")

    def expected_evaluations(self) -> tuple[int, int]:
        """Trial 1 of every bee each iteration, trials 2 and 3 only where they are tried: from
        N (T + 1) up to N (2T + 1) (``split``: one of them) or N (3T + 1) (``nested``)."""
        per_bee = 2 if self.p["trials"] == "split" else 3
        return self.N * (self.T + 1), self.N * (per_bee * self.T + 1)

    def _initialize(self) -> None:
        self.X = self.random_population()
        self.F = self.evaluate(self.X)
        self.pace = np.zeros_like(self.X)
        self.has_pace = np.zeros((self.R, self.N), dtype=bool)
        # accepted moves per run by kind: trial 1, trial 2 (previous pace), trial 3 (x + x r)
        self.accepted = np.zeros((self.R, 3), dtype=np.int64)

    def _levy(self, m: int) -> Array:
        """Levy steps of shape (R, m, d): ``ops.levy`` with beta = 1.5, computed in place.

        Same formula (u ~ N(0, sigma^2), v ~ N(0, 1), 0.01 u / |v|^(2/3)), with |v|^(2/3) as
        cbrt(v^2): half the time of the generic version.
        """
        u, v = self.rng.normal_parts(2, m, self.d)
        np.multiply(v, v, out=v)
        np.cbrt(v, out=v)
        np.divide(u, v, out=u)
        u *= _LEVY_SCALE
        return u

    def _levy_pair(self, m: int) -> tuple[Array, Array]:
        """Levy steps L (R, m, d) as ``_levy``, and S = |L| sign(v) from the same draw.

        sign(u), sign(v) and |L| are independent: whoever uses only sign(L) of the first may use
        the second as an independent Levy step.
        """
        u, v = self.rng.normal_parts(2, m, self.d)
        w = np.multiply(v, v)
        np.cbrt(w, out=w)
        np.divide(u, w, out=u)
        u *= _LEVY_SCALE
        return u, np.copysign(u, v, out=v)

    def _bound(self, C: Array) -> Array:
        """Apply the bound rule to candidates C (R, N, d) in place and return them."""
        if self.p["bound"] == "author":
            L = self._levy(self.N)
            over = C > self.ub
            under = C < self.lb
            np.copyto(C, self.ub * L, where=over)
            np.copyto(C, self.lb * L, where=under)
        return self.clip_inplace(C)

    def _weights(self, fb: Array) -> tuple[Array, Array]:
        """fw (R, N) and the mask of bees whose ratio is infinite (f(x_i) = 0 != f(x*))."""
        F = self.F
        fbc = fb[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            fw = fbc / F
        wf = float(self.p["weight_factor"])
        if wf:
            fw -= wf
        if self.p["weight_rule"] == "threshold":
            np.putmask(fw, fbc < 0.05 * F, 0.2)
        # putmask with ufunc-broadcast masks: boolean setitem with broadcast_to costs more
        zero = np.isfinite(fw)
        np.logical_not(zero, out=zero)
        zero |= fbc == 0
        np.putmask(fw, zero, 0.0)
        infinite = F == 0
        infinite &= fbc != 0
        np.putmask(fw, infinite, 1.0)
        return fw, infinite

    def _iterate(self) -> None:
        R, N = self.R, self.N
        X, F = self.X, self.F
        rows = np.arange(R)
        b = np.argmin(F, axis=1)
        fb = F[rows, b]
        xb = X[rows, b][:, None, :]  # (R, 1, d)
        fw, infinite = self._weights(fb)
        walk = (fw == 1.0) | infinite  # pace = x r
        plain = (fw == 0.0) & ~walk  # pace = (x* - x) r
        special = walk | plain  # bees whose trial 1 uses the Levy magnitude, not only its sign
        any_special = bool(special.any())
        fw3 = fw[:, :, None]

        # Random numbers, fixed shapes: one Levy pair draw (u, v) per bee and component and one
        # Levy row per run for the trial 3 of special bees. L = c u / |v|^(2/3): trial 1 of a bee
        # in the general branch uses only sign(L) = sign(u); its trial-3 step is |L| sign(v).
        # sign(u), sign(v) and (|u|, |v|) are independent (u, v symmetric), so that step is an
        # exact Levy step independent of trial 1, without a second Levy or a uniform draw.
        L, S3 = self._levy_pair(N)
        row = self._levy(1)  # (R, 1, d)

        # ---- trial 1: x + pace
        dist = np.empty_like(X)
        np.copyto(dist, xb)  # contiguous operands: faster than broadcasting xb in numpy 1.26
        dist -= X
        if any_special:  # few bees: index them instead of computing whole arrays
            w = np.nonzero(walk)
            special_pace = [(w, X[w] * L[w])]
            if plain.any():
                q = np.nonzero(plain)
                special_pace.append((q, dist[q] * L[q]))
        fd = dist
        fd *= fw3  # (x* - x) fw, shared by trials 1 and 2
        # (x* - x) fw sign(r) has the law of |(x* - x) fw| sign(r): sign(r) is a fair coin
        # independent of everything else, so copysign gives the pace in one pass
        pace = np.copysign(fd, L)
        if any_special:
            for i, value in special_pace:
                pace[i] = value
        cand1 = self._bound(X + pace)
        F1 = self.evaluate(cand1)
        acc1 = F1 < F
        fresh = ~self.has_pace

        # ---- trial 2: x + (x* - x) fw + previous pace (bees that have moved before)
        tried2 = ~acc1 & self.has_pace
        cand2 = fd
        cand2 += X
        cand2 += self.pace
        # ---- trial 3: x + x r with a fresh Levy r per component
        cand3 = S3
        if any_special:
            sp = np.nonzero(special)
            cand3[sp] = row[sp[0], 0]
        cand3 *= X
        cand3 += X
        if self.p["trials"] == "split":
            # 2019 FDO.m: trial 2 for bees that moved before, trial 3 for the others
            tried3 = ~acc1 & fresh
            np.copyto(cand2, cand3, where=tried3[:, :, None])
            F2 = self.evaluate(self._bound(cand2), mask=tried2 | tried3)
            acc2 = F2 < F  # +inf where not tried
            acc3 = acc2 & tried3
            acc2 &= tried2
            F3 = F2
            cand3 = cand2
        else:
            # the author's later code: trial 3 only after trial 2 failed; a bee that never moved
            # stops after trial 1
            F2 = self.evaluate(self._bound(cand2), mask=tried2)
            acc2 = F2 < F
            tried3 = tried2 & ~acc2
            F3 = self.evaluate(self._bound(cand3), mask=tried3)
            acc3 = F3 < F

        # ---- greedy update (the three acceptances are disjoint; a minority of the rows moves)
        for acc, cand, value in ((acc1, cand1, F1), (acc2, cand2, F2), (acc3, cand3, F3)):
            i = np.nonzero(acc)
            X[i] = cand[i]
            F[i] = value[i]
        moved = acc1 | acc2 | acc3
        i = np.nonzero(moved)
        self.pace[i] = pace[i]
        self.accepted[:, 0] += np.count_nonzero(acc1, axis=1)
        self.accepted[:, 1] += np.count_nonzero(acc2, axis=1)
        self.accepted[:, 2] += np.count_nonzero(acc3, axis=1)
        self.has_pace |= moved
