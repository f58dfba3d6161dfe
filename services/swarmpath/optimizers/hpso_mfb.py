"""Hybrid PSO-MFB: a particle swarm that tunes the MFB's alpha and gamma while it runs.

Ajeil, Ibraheem, Azar & Humaidi, Int. J. Adv. Robot. Syst. 17(3) (2020), "Hybrid PSO-MFB swarm
optimization algorithm", eqs 16-17 and Table 2. The paper says only that the PSO result "is a
vector of two columns", x[1,1] = alpha (eq 14) and x[1,2] = gamma (eq 15), and that "each
individual particle in PSO requests one complete MFB operation with alpha and gamma varying".
The concrete, vectorized design used here:

* P = ``particles`` (Table 2: 5) PSO particles, each a point (alpha, gamma) in the box
  [alpha_low, alpha_high] x [gamma_low, gamma_high] = [0.8, 0.999] x [0.01, 1], drawn uniformly
  at the start with zero velocity. The paper only says 0 < alpha < 1 and gamma > 0; with the
  per-iteration loudness decay A = A(0) alpha^t, alpha < 0.8 silences a bat within ~20
  iterations (A < 0.02), and a box starting at 0.01 measured 10-1000x worse on F1, F5, F11 at
  30 dims (docs/algorithms.md); ``alpha_low=0.01`` restores it.
* Each particle owns one MFB sub-swarm (mfb.py; all its rules and parameters apply). All
  sub-swarms advance together, one MFB iteration per ``step``, in the same (runs, bats, dim)
  arrays. ``split="divide"`` (default): ``agents`` is the total number of bats, bat j belongs to
  particle j % P (sub-swarms differ in size by at most one; P is capped at ``agents``), so the
  budget is ``agents`` evaluations per iteration like every other optimizer.
  ``split="per_particle"``: ``agents`` bats per particle, P x agents evaluations per iteration
  (Table 2's "5 PSO particles, 5 MFB bats").
* The run of T iterations is cut into ``pso_iterations`` (Table 2: 5) epochs of
  K = ceil(T / pso_iterations) iterations. In an epoch every sub-swarm performs one complete MFB
  run of K iterations with its particle's (alpha, gamma): the clock of eqs 10 and 15 is the
  iteration within the epoch, so beta rises from 0 to 1 in every epoch.
* A particle's fitness for an epoch is the best objective value its sub-swarm evaluated during
  the epoch. After each epoch but the last, pbest and gbest are updated (strict improvement) and
  eqs 16-17 move the particles: v <- w v + c1 r1 (pbest - x) + c2 r2 (gbest - x), x <- x + v,
  c1 = c2 = 2 (Table 2), w = 1 (eq 16 has no inertia weight), r1, r2 ~ U(0,1) per component;
  |v| is clamped to ``vmax`` (0.2) times the box width per component (Kennedy & Eberhart's
  Vmax, needed without inertia) and x is clipped to the box.
* Between epochs, ``restart="warm"`` (default) keeps each sub-swarm's bats and z* and resets
  v = 0, A = A_i(0), r = 0 (a new MFB run started from where the bats are);
  ``restart="cold"`` also redraws the bats uniformly (the first iteration of the epoch evaluates
  them) and forgets the sub-swarm's z*: literally "one complete MFB operation" per particle;
  ``restart="none"`` never restarts: the sub-swarms run one MFB over all T iterations (clock t/T)
  whose alpha and gamma change at every epoch end.
* ``best="global"`` (default): every bat flies toward and walks around the best point of all
  sub-swarms, so in an epoch all particles start from the same z* and their fitness compares
  their (alpha, gamma) on equal terms (and the sub-swarms cooperate); the mean loudness of eq 13
  stays per sub-swarm, so each particle's alpha sets its own walk radius. ``best="swarm"``: each
  sub-swarm is an independent MFB with its own z*, as separate MFB runs would be.

Evaluations: every bat candidate, Nb (T + 1) in all (Nb = agents, or P x agents with
``per_particle``), all through :meth:`Optimizer.evaluate`; the PSO layer costs none (it reuses
the values its sub-swarms produced). Bounds: bat candidates are clipped to the problem's box.
Randomness: MFB's draws plus one (runs, P, 4) draw per epoch boundary and (runs, P, 2) at start.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import ClassVar

import numpy as np

from swarmpath.optimizers.base import Array, ParameterError, ParamValue
from swarmpath.optimizers.mfb import BAT_CHOICES, BAT_DEFAULTS, BatSwarms, check_bat_params
from swarmpath.optimizers.registry import register


@register
class HPSOMFB(BatSwarms):
    name = "HPSO-MFB"
    summary = "Hybrid PSO-MFB (Ajeil et al. 2020): PSO tunes the bats' alpha and gamma"
    reference = (
        "Ajeil, Ibraheem, Azar & Humaidi, Int. J. Adv. Robot. Syst. 17(3) 2020, eqs 9-17, "
        "Tables 1-2; Kennedy & Eberhart 1995"
    )
    defaults: ClassVar = {
        **BAT_DEFAULTS,
        "particles": 5,  # Table 2
        "pso_iterations": 5,  # Table 2
        "c1": 2.0,  # Table 2
        "c2": 2.0,
        "w": 1.0,  # eq 16: no inertia weight
        "vmax": 0.2,  # fraction of the (alpha, gamma) box width
        "alpha_low": 0.8,
        "alpha_high": 0.999,
        "gamma_low": 0.01,
        "gamma_high": 1.0,
        "split": "divide",
        "restart": "warm",
        "best": "global",
    }
    choices: ClassVar = {
        **BAT_CHOICES,
        "split": ("divide", "per_particle"),
        "restart": ("warm", "cold", "none"),
        "best": ("swarm", "global"),
    }
    min_agents = 1

    @classmethod
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        check_bat_params(cls.name, p)
        for key in ("particles", "pso_iterations"):
            if int(p[key]) < 1:
                raise ParameterError(f"{cls.name}.{key} must be >= 1")
        for key in ("c1", "c2", "w"):
            if not float(p[key]) >= 0:
                raise ParameterError(f"{cls.name}.{key} must be >= 0")
        if not float(p["vmax"]) > 0:
            raise ParameterError(f"{cls.name}.vmax must be > 0")
        if not 0 < float(p["alpha_low"]) <= float(p["alpha_high"]) <= 1:
            raise ParameterError(f"{cls.name}.alpha_low/alpha_high need 0 < low <= high <= 1")
        if not 0 < float(p["gamma_low"]) <= float(p["gamma_high"]):
            raise ParameterError(f"{cls.name}.gamma_low/gamma_high need 0 < low <= high")

    # ------------------------------------------------------------------------------ hooks
    def _shared_best(self) -> bool:
        return self.G == 1 or self.p["best"] == "global"

    def _bat_alpha_gamma(self) -> tuple[Array, Array]:
        x = self.pos if self.G == 1 else self.pos[:, self.group]  # (R, Nb or 1, 2)
        return x[..., 0], x[..., 1]

    def expected_evaluations(self) -> tuple[int, int]:
        """Every bat each iteration and once first: ``agents`` bats with ``split="divide"``,
        P x ``agents`` with ``"per_particle"``."""
        p = self.p
        n = self.N if p["split"] == "divide" else min(int(p["particles"]), self.N) * self.N
        return n * (self.T + 1), n * (self.T + 1)

    # ------------------------------------------------------------------------------ run
    def _initialize(self) -> None:
        p = self.p
        P = min(int(p["particles"]), self.N)
        Nb = self.N if p["split"] == "divide" else P * self.N
        self._setup_bats(P, Nb)
        self.K = math.ceil(self.T / int(p["pso_iterations"]))  # MFB iterations per epoch
        self.track_epoch = True
        self.box_lo = np.array([p["alpha_low"], p["gamma_low"]], dtype=float)
        self.box_hi = np.array([p["alpha_high"], p["gamma_high"]], dtype=float)
        self._init_bats()
        #: PSO particles (alpha, gamma): positions, velocities, personal and global bests
        self.pos = self.box_lo + (self.box_hi - self.box_lo) * self.rng.random(P, 2)
        self.vel = np.zeros((self.R, P, 2))
        self.pbest = self.pos.copy()
        self.pbest_f = np.full((self.R, P), np.inf)
        self.gbest = self.pos[:, 0].copy()
        self.gbest_f = np.full(self.R, np.inf)

    def _iterate(self) -> None:
        t, K, T = self.t, self.K, self.T
        start = (t - 1) // K * K  # last iteration of the previous epoch
        length = min(start + K, T) - start  # iterations in this epoch
        local = t - start
        if self.p["restart"] == "none":
            self._bat_move(t, T)
        elif self.p["restart"] == "cold" and start > 0:
            if local == 1:
                self._redraw_bats()  # the new MFB run's initial population
            else:
                self._bat_move(local - 1, length - 1)
        else:
            self._bat_move(local, length)
        if t % K == 0 and t < T:
            self._pso_step()
            self.epoch_best[...] = np.inf
            if self.p["restart"] != "none":
                self._restart_bats()

    def _pso_step(self) -> None:
        """Eqs 16-17 on (alpha, gamma), scored by the epoch just finished."""
        p = self.p
        fit = self.epoch_best
        better = fit < self.pbest_f
        self.pbest = np.where(better[..., None], self.pos, self.pbest)
        self.pbest_f = np.where(better, fit, self.pbest_f)
        j = np.argmin(self.pbest_f, axis=1)
        rows = np.arange(self.R)
        self.gbest = self.pbest[rows, j]
        self.gbest_f = self.pbest_f[rows, j]
        u = self.rng.random(self.G, 4)
        self.vel = (
            float(p["w"]) * self.vel
            + float(p["c1"]) * u[..., :2] * (self.pbest - self.pos)
            + float(p["c2"]) * u[..., 2:] * (self.gbest[:, None, :] - self.pos)
        )
        vmax = float(p["vmax"]) * (self.box_hi - self.box_lo)
        np.clip(self.vel, -vmax, vmax, out=self.vel)
        self.pos = np.clip(self.pos + self.vel, self.box_lo, self.box_hi)
