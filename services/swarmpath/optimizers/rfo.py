"""Red Fox Optimization (RFO) - Połap & Woźniak, not Rüppell's fox optimizer.

Połap & Woźniak, "Red fox optimization algorithm", Expert Systems with Applications 166 (2021)
114107, doi 10.1016/j.eswa.2020.114107; eqs 1-2 as restated in Ketafa & Al-Darraji, Iraqi J.
Science 65(2) 2024 (seed 003, section 3.1); eqs 3-9 after the original paper. No author code
exists; every gap below is our decision (docs/algorithms.md).

One iteration, as three population-level phases (the paper loops over foxes; we move all foxes
of a phase together, so a fox's phase sees the population as it was when the phase began):

1. Global search (eqs 1-2). x_best is the best fox of the current population. For every other
   fox, d_i = sqrt(||x_i - x_best||) (square root of the Euclidean distance, eq 1) and
   x_i' = x_i + alpha_i sign(x_best - x_i) (eq 2). The paper draws "a single, iterative
   adjustment of a randomly chosen scaling hyperparameter for the whole population" with
   alpha in (0, d_i): we draw one u ~ U(0, 1) per iteration and set alpha_i = u d_i
   (``alpha_draw = "fox"``: one u per fox). A fox keeps x_i' only if it is strictly better
   (greedy). The best fox does not move and is not evaluated: N - 1 evaluations.
2. Local search (eqs 3-5). Each fox draws mu ~ U(0, 1) and moves when it is not noticed,
   mu > ``notice`` (0.75), otherwise it stays hidden. Decision: exactly
   n_move = round((1 - notice) N) foxes move, those with the largest mu (a uniformly random
   subset: the expected number of the paper's Bernoulli rule without its binomial spread), so
   that the points handed to the objective have a fixed shape and are all counted. a ~
   U(0, ``a_max``) once per iteration for the population; the observation radius is
   r = a sin(phi0)/phi0 (eq 4), phi0 ~ U(0, 2 pi) per moving fox, and r = theta ("weather",
   drawn once per run in (0, 1)) when phi0 = 0. With angles phi_1..phi_{n-1} ~ U(0, 2 pi) per
   moving fox (eq 5),
       x_0' = x_0 + a r cos(phi_1)
       x_j' = x_j + a r (sum_{k<=j} sin(phi_k) + cos(phi_{j+1}))   for 0 < j < n-1
       x_{n-1}' = x_{n-1} + a r sum_{k<=n-1} sin(phi_k)
   (in one dimension: x_0' = x_0 + a r cos(phi_1)). The steps are absolute, as printed: |a r|
   <= a_max^2 = 0.04 times a sum of O(sqrt(n)) size, whatever the box. The move is accepted
   unconditionally (``local_greedy = True``: only if better).
3. Reproduction (eqs 6-9). The worst round(``replace_fraction`` N) foxes (MATLAB rounding, at
   least 1, at most N - 2) are replaced. From the two best, habitat centre H = (x(1) + x(2))/2
   (eq 6) and diameter delta = sqrt(||x(1) - x(2)||) (eq 7). kappa ~ U(0, 1), once per iteration
   (``kappa_draw = "fox"``: per new fox): kappa >= ``kappa_threshold`` (0.45) gives a nomad, a
   uniform point of the box pushed radially out of the habitat ball (radius delta/2) if it
   fell inside; kappa < 0.45 a fox reproduced by the alpha couple. The paper writes it as
   kappa (x(1) + x(2))/2 = kappa H (eq 9), a point between the origin and H: that pulls
   toward the origin, a bias that flatters F1-F4, F9-F11. Default ``reproduction =
   "habitat"``: a uniform point of the habitat ball around H; ``"scaled_centre"`` is the
   literal kappa H. Every new fox is evaluated.

Bounds: every candidate is clipped to the box before it is evaluated. Evaluations: N at
initialization, then N - 1 + n_move + n_rep per iteration (N = 30: 29 + 8 + 2 = 39), the
same in every run; only new points are handed to the objective and all of them are counted.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

from swarmpath.optimizers.base import Array, Optimizer, ParameterError, ParamValue
from swarmpath.optimizers.hpo import matlab_round
from swarmpath.optimizers.ops import take_rows
from swarmpath.optimizers.registry import register

TWO_PI = 2.0 * math.pi


@register
class RFO(Optimizer):
    name = "RFO"
    summary = "Red Fox Optimization (Połap & Woźniak 2021)"
    reference = "Połap & Woźniak, Expert Syst. Appl. 166 (2021) 114107, eqs 1-9"
    defaults: ClassVar[dict[str, Any]] = {
        "replace_fraction": 0.05,
        "a_max": 0.2,
        "notice": 0.75,
        "kappa_threshold": 0.45,
        "alpha_draw": "population",
        "kappa_draw": "iteration",
        "reproduction": "habitat",
        "local_greedy": False,
    }
    choices: ClassVar[dict[str, tuple[str, ...]]] = {
        "alpha_draw": ("population", "fox"),
        "kappa_draw": ("iteration", "fox"),
        "reproduction": ("habitat", "scaled_centre"),
    }
    min_agents = 2

    @classmethod
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        if not 0.0 <= float(p["replace_fraction"]) <= 1.0:
            raise ParameterError("RFO.replace_fraction must be in [0, 1]")
        if not float(p["a_max"]) > 0.0:
            raise ParameterError("RFO.a_max must be > 0")
        for key in ("notice", "kappa_threshold"):
            if not 0.0 <= float(p[key]) <= 1.0:
                raise ParameterError(f"RFO.{key} must be in [0, 1]")

    def replaced(self) -> int:
        """How many of the worst foxes are replaced each iteration."""
        frac = float(self.p["replace_fraction"])
        if frac <= 0.0:
            return 0
        return max(0, min(self.N - 2, max(1, matlab_round(frac * self.N))))

    def movers(self) -> int:
        """How many foxes move in the local phase: round((1 - notice) N), MATLAB rounding."""
        return min(self.N, matlab_round((1.0 - float(self.p["notice"])) * self.N))

    def expected_evaluations(self) -> tuple[int, int]:
        n = self.N + self.T * (self.N - 1 + self.movers() + self.replaced())
        return n, n

    # ------------------------------------------------------------------------------------------
    def _initialize(self) -> None:
        self.X = self.random_population()
        self.F = self.evaluate(self.X)
        self.theta = self.rng.random(1)[:, 0]  # "weather", per run (used only when phi0 == 0)
        self.n_rep = self.replaced()
        self.n_move = self.movers()
        self.rows = np.arange(self.R)[:, None]
        self.others = np.arange(self.N - 1)[None, :]

    def _iterate(self) -> None:
        # All uniforms of the iteration in one call (per-run generator calls dominate otherwise).
        N, d, k, m = self.N, self.d, self.n_rep, self.n_move
        n_u = 1 if self.p["alpha_draw"] == "population" else N - 1
        n_ang = max(d - 1, 1)
        n_dir = 2 * k * d if self.p["reproduction"] == "habitat" else 0
        sizes = (n_u, N, m, 1, m * n_ang, k * d, k, k, n_dir)
        U = self.rng.random(sum(sizes))
        cut = np.cumsum((0, *sizes))
        u_alpha, mu, phi0, a, ang, box, kappa, frac, bm = (
            U[:, cut[j] : cut[j + 1]] for j in range(len(sizes))
        )
        self._global_phase(u_alpha)
        if m:
            self._local_phase(mu, phi0, a[:, 0], ang.reshape(self.R, m, n_ang))
        if k:
            normal = None
            if n_dir:  # Box-Muller normals (cheaper here than a second generator call)
                u1, u2 = bm[:, : k * d], bm[:, k * d :]
                normal = np.sqrt(-2.0 * np.log1p(-u1)) * np.cos(TWO_PI * u2)
                normal = normal.reshape(self.R, k, d)
            self._reproduction(box.reshape(self.R, k, d), kappa, frac, normal)

    def _global_phase(self, u: Array) -> None:
        """Eqs 1-2 for the N - 1 foxes other than the best; greedy."""
        X, F = self.X, self.F
        b = np.argmin(F, axis=1)
        idx = self.others + (self.others >= b[:, None])  # every fox but the best, in order
        rows = self.rows
        Xo = X[rows, idx]  # (R, N - 1, d)
        step = take_rows(X, b)[:, None, :] - Xo  # x_best - x_i
        dist = np.sqrt(np.sqrt(np.einsum("rnd,rnd->rn", step, step)))  # eq 1
        alpha = u * dist  # u: (R, 1) for the population or (R, N - 1) per fox
        np.sign(step, out=step)
        step *= alpha[..., None]
        step += Xo  # eq 2
        self._clip_inplace(step)
        Fc = self.evaluate(step)
        r, j = np.nonzero(Fc < F[rows, idx])  # greedy
        i = idx[r, j]
        X[r, i] = step[r, j]
        F[r, i] = Fc[r, j]

    def _local_phase(self, mu: Array, phi0: Array, a: Array, angles: Array) -> None:
        """Eqs 3-5 for the n_move foxes with the largest mu."""
        d, m, rows = self.d, self.n_move, self.rows
        movers = np.argpartition(mu, self.N - m, axis=1)[:, self.N - m :]  # (R, m)
        movers.sort(axis=1)
        a = (a * float(self.p["a_max"]))[:, None]  # (R, 1)
        # observation radius (eq 4)
        p0 = phi0 * TWO_PI  # (R, m)
        with np.errstate(invalid="ignore", divide="ignore"):
            radius = np.where(p0 != 0.0, a * np.sin(p0) / p0, self.theta[:, None])
        # eq 5: cumulative sines plus the next cosine
        phi = angles * TWO_PI  # (R, m, n_ang)
        if d == 1:
            delta = np.cos(phi)
        else:
            delta = np.empty((self.R, m, d))
            np.cos(phi, out=delta[..., : d - 1])
            delta[..., d - 1] = 0.0
            np.sin(phi, out=phi)
            np.cumsum(phi, axis=2, out=phi)
            delta[..., 1:] += phi
        delta *= (a * radius)[..., None]
        delta += self.X[rows, movers]
        self._clip_inplace(delta)
        Fc = self.evaluate(delta)
        if self.p["local_greedy"]:
            r, j = np.nonzero(Fc < self.F[rows, movers])
            i = movers[r, j]
            self.X[r, i] = delta[r, j]
            self.F[r, i] = Fc[r, j]
        else:
            self.X[rows, movers] = delta
            self.F[rows, movers] = Fc

    def _reproduction(
        self, box: Array, kappa: Array, frac: Array, normal: Array | None
    ) -> None:
        d, k = self.d, self.n_rep
        order = np.argsort(self.F, axis=1, kind="stable")
        worst = order[:, self.N - k :]  # (R, k)
        x1, x2 = take_rows(self.X, order[:, 0]), take_rows(self.X, order[:, 1])
        C = (0.5 * (x1 + x2))[:, None, :]  # habitat centre (eq 6)
        diff = x1 - x2
        rad = 0.5 * np.sqrt(np.sqrt(np.einsum("rd,rd->r", diff, diff)))[:, None, None]  # eq 7 / 2
        if self.p["kappa_draw"] == "iteration":
            kappa = kappa[:, :1]
        nomad = (kappa >= float(self.p["kappa_threshold"]))[..., None]  # (R, k or 1, 1)

        # nomads: uniform in the box, pushed radially onto the habitat sphere if inside it
        new = self.lb + (self.ub - self.lb) * box
        off = new - C
        norm = np.sqrt(np.einsum("rkd,rkd->rk", off, off))[..., None]
        inside = (norm < rad) & (norm > 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            new = np.where(inside, C + off * (rad / norm), new)

        if normal is not None:  # "habitat": uniform in the habitat ball
            nn = np.sqrt(np.einsum("rkd,rkd->rk", normal, normal))[..., None]
            scale = rad * frac[..., None] ** (1.0 / d)
            with np.errstate(invalid="ignore", divide="ignore"):
                born = C + normal * np.where(nn > 0.0, scale / nn, 0.0)
        else:  # "scaled_centre", literal eq 9: kappa H
            born = kappa[..., None] * C
        new = np.where(nomad, new, born)
        self._clip_inplace(new)
        Fn = self.evaluate(new)
        self.X[self.rows, worst] = new
        self.F[self.rows, worst] = Fn

    def _clip_inplace(self, X: Array) -> None:
        np.maximum(X, self.lb, out=X)
        np.minimum(X, self.ub, out=X)
