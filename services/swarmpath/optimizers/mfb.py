"""Modified Frequency Bat algorithm (MFB).

Ajeil, Ibraheem, Azar & Humaidi, "Autonomous navigation and obstacle avoidance of an
omnidirectional mobile robot using swarm optimization and sensors deployment", Int. J. Adv.
Robot. Syst. 17(3) (2020), eqs 9-15 and Table 1, on top of the bat algorithm of Yang, "A new
metaheuristic bat-inspired algorithm", NICSO 2010, SCI 284, 65-74 (loop, acceptance test, local
walk around the best). The paper leaves gaps; each is closed here and in
docs/algorithms.md, and each decision has a parameter selecting the alternative.

One iteration t = 1..T, for every bat i of every run at once:

1. Frequency, eqs 9-10: f_i = f_min + (f_max - f_min) beta_i, beta_i = (t/T) exp(-rho r), with
   [f_min, f_max] = [0, 10] and rho = 0.01 (paper). ``beta_time``: "normalized" (t/T, default),
   "literal" (the printed t, so beta grows to ~T), "uniform" (Yang's beta ~ U(0,1)). ``beta_r``:
   "uniform" (r ~ U(0,1), as the paper says, default) or "pulse" (the bat's pulse rate r_i).
   ``beta_per``: "bat" (one beta per bat, default) or "dimension". With rho = 0.01,
   exp(-rho r) is in [0.990, 1]: beta is t/T to within 1 %.
2. Velocity and flight, eqs 11-12: v_i += (z* - z_i) f_i, candidate S_i = z_i + v_i
   (``velocity="toward"``, default). The printed (z_i - z*) f_i with f >= 0
   (``velocity="literal"``) pushes bats away from the best: the (distance, velocity) recursion
   has an eigenvalue 1 + f/2 + sqrt(f + f^2/4) > 1 for every f > 0, so it diverges (the clip then
   pins candidates to the box faces; measured in tests/test_opt_bat.py). Eq 11's z_i(t+1) on the
   right-hand side is read as z_i(t), the only causal reading. Note that even the pull toward the
   best is unstable for f > 4 (trace of the recursion matrix 2 - f < -2), i.e. in the last 60 % of
   a run with f_max = 10: then the local walk carries the search.
3. Local walk, eq 13: with probability 1 - r_i the candidate is replaced by
   z* + sigma eps <A> (ub - lb), eps ~ U(-1,1) per component, <A> the swarm's mean loudness,
   sigma = 0.3 (Table 1). ``walk_scale="span"`` (default) reads sigma as a fraction of the box
   width; ``"absolute"`` is eq 13 in the problem's units (the paper's maps are 10 m wide, so
   sigma = 0.3 m is 3 % of its box; on [-100, 100]^d the absolute step is too small to move).
4. Bounds: candidates are clipped to the box, then evaluated (one evaluation per bat).
5. Acceptance (Yang 2010): bat i takes S_i if rand < A_i and f(S_i) < f(z*) (``accept="best"``,
   Yang's pseudocode, default) or f(S_i) <= f(z_i) (``accept="own"``, Yang's demo code). z* is
   the best point the swarm ever evaluated, accepted or not. ``move="accepted"`` (default) keeps
   z_i when the candidate is refused; ``move="always"`` is eq 12 read literally (the bat always
   flies to its candidate; the test then only gates the loudness/pulse update of ``"accept"``).
6. Loudness and pulse rate, eqs 14-15 (alpha = gamma = 0.9, Table 1): A_i <- alpha A_i and
   r_i <- r_i(0) [1 - exp(-gamma t)] for every bat after every iteration (``update="iteration"``,
   the equations as printed, default) or only for bats whose candidate passed the acceptance test
   (``update="accept"``, Yang's text). A_i(0) ~ U(A0_min, A0_max) = U(1, 2) and
   r_i(0) ~ U(r0_min, r0_max) = U(0, 1) per bat (Yang's ranges); the working pulse rate starts at
   eq 15's t = 0 value, 0, and rises toward r_i(0).

Evaluations: N at initialisation, then N per iteration, N (T + 1) in all, every one through
:meth:`Optimizer.evaluate`. Randomness: one draw of N (d + 3) numbers per run per iteration
(N (2 d + 2) with ``beta_per="dimension"``), plus N (d + 2) per run at initialisation.

The machinery is written for G independent sub-swarms (each with its own z*, mean loudness,
alpha and gamma) laid out along the agent axis, so that HPSO-MFB (hpso_mfb.py) runs one MFB per
PSO particle in the same arrays; MFB is the single-swarm case.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from swarmpath.optimizers.base import Array, Optimizer, ParameterError, ParamValue
from swarmpath.optimizers.registry import register

# The bat layer's parameters, shared with HPSO-MFB (which tunes alpha and gamma itself).
BAT_DEFAULTS: dict[str, Any] = {
    "f_min": 0.0,  # Table 1
    "f_max": 10.0,  # Table 1
    "rho": 0.01,  # eq 10 ("in our work")
    "sigma": 0.3,  # Table 1, eq 13
    "A0_min": 1.0,  # initial loudness A_i(0) ~ U(A0_min, A0_max) (Yang 2010)
    "A0_max": 2.0,
    "r0_min": 0.0,  # pulse-rate level r_i(0) ~ U(r0_min, r0_max) (Yang 2010)
    "r0_max": 1.0,
    "beta_time": "normalized",
    "beta_r": "uniform",
    "beta_per": "bat",
    "velocity": "toward",
    "walk_scale": "span",
    "accept": "best",
    "move": "accepted",
    "update": "iteration",
}
BAT_CHOICES: dict[str, tuple[str, ...]] = {
    "beta_time": ("normalized", "literal", "uniform"),
    "beta_r": ("uniform", "pulse"),
    "beta_per": ("bat", "dimension"),
    "velocity": ("toward", "literal"),
    "walk_scale": ("span", "absolute"),
    "accept": ("best", "own"),
    "move": ("accepted", "always"),
    "update": ("iteration", "accept"),
}


def check_bat_params(name: str, p: Mapping[str, Any]) -> None:
    if not float(p["f_max"]) >= float(p["f_min"]):
        raise ParameterError(f"{name}.f_max must be >= f_min")
    for key in ("rho", "sigma"):
        if not float(p[key]) >= 0:
            raise ParameterError(f"{name}.{key} must be >= 0")
    if not 0 <= float(p["A0_min"]) <= float(p["A0_max"]):
        raise ParameterError(f"{name}.A0_min and A0_max need 0 <= A0_min <= A0_max")
    if not 0 <= float(p["r0_min"]) <= float(p["r0_max"]) <= 1:
        raise ParameterError(f"{name}.r0_min and r0_max need 0 <= r0_min <= r0_max <= 1")


class BatSwarms(Optimizer):
    """MFB for G independent sub-swarms; bat j belongs to sub-swarm ``j % G``.

    Subclasses call :meth:`_setup_bats`, :meth:`_init_bats` and, once per iteration,
    :meth:`_bat_move` with the clock (t, T) of eqs 10 and 15, and provide per-bat alpha, gamma.
    """

    def _bat_alpha_gamma(self) -> tuple[Array | float, Array | float]:
        raise NotImplementedError

    def _shared_best(self) -> bool:
        """Whether every bat uses the best of all sub-swarms (always so with one sub-swarm)."""
        return self.G == 1

    def _group_sums(self, a: Array) -> Array:
        """Per sub-swarm, the sum of its bats' values of ``a`` (R, Nb) -> (R, G), added in bat
        order (g, g + G, g + 2G, ...: a cumulative sum, sequential by definition). A matmul
        with the membership matrix added in BLAS's order, which depends on the number of runs
        in the batch (4 sub-swarms: another order from 2 runs on), so a run's numbers depended
        on its batch; a run alone got this order."""
        R, G = a.shape[0], self.G
        n = -(-self.Nb // G)
        padded = np.zeros((R, n * G))  # the missing bats of the last row add 0.0: no change
        padded[:, :self.Nb] = a
        return np.cumsum(padded.reshape(R, n, G), axis=1)[:, -1]

    # ------------------------------------------------------------------------------ setup
    def _setup_bats(self, G: int, Nb: int) -> None:
        self.G, self.Nb = int(G), int(Nb)
        self.group: NDArray[np.int64] = np.arange(self.Nb) % self.G
        self.member = self.group[None, :] == np.arange(self.G)[:, None]  # (G, Nb)
        self.size = self.member.sum(axis=1).astype(float)  # (G,)
        self.span = self.ub - self.lb  # (R, 1, d)
        self._rows = np.arange(self.R)[:, None]
        self._beta_width = self.d if self.p["beta_per"] == "dimension" else 1
        self._D = np.empty((self.R, self.Nb, self.d))
        self.track_epoch = False
        self.epoch_best = np.full((self.R, self.G), np.inf)

    def _init_bats(self) -> None:
        """Fresh bats: uniform positions (evaluated), loudness A_i(0), pulse rates at 0."""
        p = self.p
        self.X = self.random_population(self.Nb)
        u = self.rng.random(self.Nb, 2)
        a_lo, a_hi = float(p["A0_min"]), float(p["A0_max"])
        r_lo, r_hi = float(p["r0_min"]), float(p["r0_max"])
        self.A0 = a_lo + (a_hi - a_lo) * u[..., 0]
        self.r0 = r_lo + (r_hi - r_lo) * u[..., 1]
        self.A = self.A0.copy()
        self.r = np.zeros((self.R, self.Nb))  # eq 15 at t = 0
        self.V = np.zeros((self.R, self.Nb, self.d))
        self.Fb = np.full((self.R, self.G), np.inf)  # z*: best ever evaluated per sub-swarm
        self.Zb = np.zeros((self.R, self.G, self.d))
        self.F = self._evaluate_bats(self.X)

    def _restart_bats(self) -> None:
        """A new MFB run in every sub-swarm from the current positions: v = 0, A = A_i(0), r = 0."""
        self.V[...] = 0.0
        self.A = self.A0.copy()
        self.r[...] = 0.0

    def _redraw_bats(self) -> None:
        """New uniform positions (evaluated); each sub-swarm forgets its z*."""
        self.X = self.random_population(self.Nb)
        self.Fb[...] = np.inf
        self.F = self._evaluate_bats(self.X)

    def _evaluate_bats(self, S: Array) -> Array:
        """Evaluate candidates (R, Nb, d); update each sub-swarm's z* (and epoch record)."""
        F = self.evaluate(S)
        rows = self._rows
        if self.G == 1:
            idx = np.argmin(F, axis=1)[:, None]  # (R, 1)
            cand = F[rows, idx]
        else:
            masked = np.where(self.member[None], F[:, None, :], np.inf)  # (R, G, Nb)
            idx = np.argmin(masked, axis=2)  # (R, G)
            cand = masked[rows, np.arange(self.G)[None, :], idx]
        better = cand < self.Fb
        if better.any():
            pts = S[rows, idx]  # (R, G, d)
            self.Fb = np.where(better, cand, self.Fb)
            self.Zb = np.where(better[..., None], pts, self.Zb)
        if self.track_epoch:
            np.minimum(self.epoch_best, cand, out=self.epoch_best)
        return F

    def _per_bat(self, a: Array) -> Array:
        """(R, G, ...) per sub-swarm -> (R, Nb, ...) per bat (broadcastable when G == 1)."""
        return a if self.G == 1 else a[:, self.group]

    # ------------------------------------------------------------------------------ one move
    def _bat_move(self, t: int, T: int) -> None:
        """One MFB iteration of every bat; t = 1..T is the clock of eqs 10 and 15."""
        p = self.p
        R, Nb, d, e = self.R, self.Nb, self.d, self._beta_width
        # one draw, laid out [eps (Nb d) | walk (Nb) | accept (Nb) | beta noise (Nb e)] so that
        # eps is a block with contiguous rows (strided views make in-place ops 3x slower)
        u = self.rng.random(Nb * (d + 2 + e))
        eps = u[:, : Nb * d].reshape(R, Nb, d)
        walk = u[:, Nb * d : Nb * (d + 1)] > self.r  # eq 13 for bats with rand > r_i
        u_acc = u[:, Nb * (d + 1) : Nb * (d + 2)]
        u_beta = u[:, Nb * (d + 2) :].reshape(R, Nb, e)

        # eqs 9-10
        if p["beta_time"] == "uniform":
            beta = u_beta
        else:
            tt = t / T if p["beta_time"] == "normalized" else float(t)
            rr = u_beta if p["beta_r"] == "uniform" else self.r[..., None]
            beta = tt * np.exp(-float(p["rho"]) * rr)
        freq = float(p["f_min"]) + (float(p["f_max"]) - float(p["f_min"])) * beta

        # z* seen by each bat, and the mean loudness <A> of its sub-swarm
        if self._shared_best():
            k = np.argmin(self.Fb, axis=1)[:, None]  # (R, 1)
            zstar = self.Zb[self._rows, k]  # (R, 1, d)
            fb_before = self.Fb[self._rows, k]
        else:
            zstar = self.Zb[:, self.group]  # (R, Nb, d)
            fb_before = self.Fb[:, self.group]
        if self.G == 1:
            Amean = self.A.mean(axis=1, keepdims=True)  # (R, 1)
        else:
            Amean = (self._group_sums(self.A) / self.size)[:, self.group]

        # eqs 11-12
        D = np.subtract(zstar, self.X, out=self._D)  # z* - z_i
        D *= freq
        if p["velocity"] == "toward":
            self.V += D
        else:
            self.V -= D  # eq 11 as printed: (z_i - z*) f_i
        S = np.add(self.X, self.V)

        # eq 13: z* + sigma eps <A> [(ub - lb)], eps ~ U(-1, 1)
        scale = (2.0 * float(p["sigma"])) * Amean[..., None]
        if p["walk_scale"] == "span":
            scale = scale * self.span
        eps *= scale
        eps += zstar - 0.5 * scale
        np.copyto(S, eps, where=walk[..., None])

        np.maximum(S, self.lb, out=S)
        np.minimum(S, self.ub, out=S)
        Fnew = self._evaluate_bats(S)

        # acceptance (Yang 2010)
        if p["accept"] == "best":
            acc = (u_acc < self.A) & (Fnew < fb_before)
        else:
            acc = (u_acc < self.A) & (Fnew <= self.F)
        if p["move"] == "always":
            self.X, self.F = S, Fnew
        else:
            np.copyto(self.X, S, where=acc[..., None])
            np.copyto(self.F, Fnew, where=acc)

        # eqs 14-15
        alpha, gamma = self._bat_alpha_gamma()
        level = self.r0 * (1.0 - np.exp(-np.asarray(gamma) * t))
        if p["update"] == "iteration":
            self.A *= alpha
            self.r = np.broadcast_to(level, self.r.shape).copy()
        else:
            self.A = np.where(acc, alpha * self.A, self.A)
            self.r = np.where(acc, level, self.r)


@register
class MFB(BatSwarms):
    name = "MFB"
    summary = "Modified Frequency Bat (Ajeil et al. 2020): bat frequency rising with t"
    reference = (
        "Ajeil, Ibraheem, Azar & Humaidi, Int. J. Adv. Robot. Syst. 17(3) 2020, eqs 9-15, "
        "Table 1; Yang, NICSO 2010, SCI 284, 65-74"
    )
    defaults: ClassVar = {**BAT_DEFAULTS, "alpha": 0.9, "gamma": 0.9}
    choices: ClassVar = BAT_CHOICES
    min_agents = 1

    @classmethod
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        check_bat_params(cls.name, p)
        if not 0 < float(p["alpha"]) <= 1:
            raise ParameterError("MFB.alpha must be in (0, 1]")
        if not float(p["gamma"]) > 0:
            raise ParameterError("MFB.gamma must be > 0")

    def _bat_alpha_gamma(self) -> tuple[float, float]:
        return float(self.p["alpha"]), float(self.p["gamma"])

    def _initialize(self) -> None:
        self._setup_bats(1, self.N)
        self._init_bats()

    def _iterate(self) -> None:
        self._bat_move(self.t, self.T)
