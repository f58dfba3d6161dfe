"""CMA-ES (Hansen), with IPOP restarts as an option, vectorized over runs.

The algorithm of N. Hansen, "The CMA Evolution Strategy: A Tutorial", arXiv:1604.00772 (2016,
2023): its Table 1 (default parameters, negative weights included: "active" CMA) and the update
of its Appendix A (Fig. 6 / eqs 38-47), with the lazy eigendecomposition of its Appendix B.2.
Restarts: IPOP, A. Auger & N. Hansen, "A restart CMA evolution strategy with increasing
population size", CEC 2005: on any of its stopping criteria the run restarts from a new uniform
mean with lambda multiplied by ``incpopsize`` (2); ``restarts = "none"`` ends the run there
instead (pycma's ``fmin`` with ``restarts=0``). Bounds: the genotype is unconstrained and every
evaluated point is its image under pycma's periodic linear-quadratic box transformation
(``BoundTransform``, the default of ``cma.fmin`` with bounds), so every point lies in the box;
``bounds = "clip"`` clips instead.

Units: the genotype lives in box units, x = lower + (upper - lower) g, so ``sigma0`` is a
fraction of the box width (default 0.25: pycma's advice, about a quarter of the domain) and the
distribution's scale is the same on any box. The first mean is uniform in the box, as IPOP's.

Vectorized: runs with the same lambda are updated together (shapes per run depend on its own
lambda only); each run draws its normals from its own generator when its own generation starts.
How generations map onto the frame's iterations: :mod:`swarmpath.optimizers.generations`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from functools import lru_cache
from typing import ClassVar, NamedTuple

import numpy as np
from numpy.typing import NDArray

from swarmpath.optimizers.base import Array, ParameterError, ParamValue
from swarmpath.optimizers.bound_transform import box_transform
from swarmpath.optimizers.generations import Generational
from swarmpath.optimizers.registry import register

#: IPOP's stopping thresholds (Auger & Hansen 2005): TolFun, TolX (times sigma0), the condition
#: number of C
TOLFUN = 1e-12
TOLX = 1e-12
MAX_CONDITION = 1e14


class Setting(NamedTuple):
    """Table 1 of the tutorial for one (lambda, n)."""

    lam: int
    mu: int
    weights: Array  # (lambda,): positive for the mu best, negative after
    mueff: float
    cs: float
    ds: float
    cc: float
    c1: float
    cmu: float
    chin: float
    eigen_every: float  # generations between eigendecompositions (Appendix B.2)
    history: int  # 10 + ceil(30 n / lambda): the TolFun window


@lru_cache(maxsize=64)
def setting(lam: int, n: int) -> Setting:
    mu = lam // 2
    raw = np.log((lam + 1) / 2) - np.log(np.arange(1, lam + 1))
    pos, neg = raw[:mu], raw[mu:]
    mueff = pos.sum() ** 2 / (pos**2).sum()
    mueff_neg = neg.sum() ** 2 / (neg**2).sum() if neg.size and neg.any() else 0.0
    alpha_cov = 2.0
    c1 = alpha_cov / ((n + 1.3) ** 2 + mueff)
    cmu = min(1 - c1, alpha_cov * (0.25 + mueff + 1 / mueff - 2)
              / ((n + 2) ** 2 + alpha_cov * mueff / 2))
    alpha_mu = 1 + c1 / cmu
    alpha_mueff = 1 + 2 * mueff_neg / (mueff + 2)
    alpha_posdef = (1 - c1 - cmu) / (n * cmu)
    weights = np.where(raw >= 0, raw / pos.sum(),
                       min(alpha_mu, alpha_mueff, alpha_posdef) * raw / -neg.sum()
                       if neg.size and neg.any() else 0.0)
    cs = (mueff + 2) / (n + mueff + 5)
    ds = 1 + 2 * max(0.0, math.sqrt((mueff - 1) / (n + 1)) - 1) + cs
    cc = (4 + mueff / n) / (n + 4 + 2 * mueff / n)
    chin = math.sqrt(n) * (1 - 1 / (4 * n) + 1 / (21 * n**2))
    return Setting(lam, mu, weights, mueff, cs, ds, cc, c1, cmu, chin,
                   lam / (c1 + cmu) / n / 10, 10 + math.ceil(30 * n / lam))


def default_popsize(n: int) -> int:
    """Table 1: lambda = 4 + floor(3 ln n)."""
    return 4 + math.floor(3 * math.log(n))


@register
class CMAES(Generational):
    name = "CMA-ES"
    summary = "CMA-ES (Hansen's tutorial defaults, active weights) with IPOP restarts"
    reference = ("Hansen, The CMA Evolution Strategy: A Tutorial, arXiv:1604.00772, Table 1 and "
                 "Appendix A; IPOP: Auger & Hansen, CEC 2005")
    defaults: ClassVar = {"popsize": 0, "sigma0": 0.25, "restarts": "ipop", "incpopsize": 2.0,
                          "max_restarts": 9, "bounds": "transform"}
    choices: ClassVar = {"restarts": ("ipop", "none"), "bounds": ("transform", "clip")}

    @classmethod
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        if int(p["popsize"]) != p["popsize"] or not (p["popsize"] == 0 or p["popsize"] >= 2):
            raise ParameterError("CMA-ES.popsize must be 0 (4 + floor(3 ln n)) or an integer >= 2")
        if not 0 < float(p["sigma0"]) <= 10:
            raise ParameterError("CMA-ES.sigma0 must be in (0, 10] (a fraction of the box width)")
        if not float(p["incpopsize"]) >= 1:
            raise ParameterError("CMA-ES.incpopsize must be >= 1")
        if int(p["max_restarts"]) != p["max_restarts"] or int(p["max_restarts"]) < 0:
            raise ParameterError("CMA-ES.max_restarts must be an integer >= 0")

    def expected_evaluations(self) -> tuple[int, int]:
        """A run ends early when it stops without a restart left: at least its first quantum."""
        return min(self.N, self.N * (self.T + 1)), self.N * (self.T + 1)

    # ---------------------------------------------------------------------------- state
    def _begin(self) -> None:
        R, n = self.R, self.d
        self.width = (self.ub - self.lb)[:, 0, :]  # (R, n)
        self.lam0 = int(self.p["popsize"]) or default_popsize(n)
        self.lam = np.full(R, self.lam0, dtype=np.int64)
        self.restarts = np.zeros(R, dtype=np.int64)
        self.mean = np.zeros((R, n))
        self.sigma = np.zeros(R)
        self.C = np.zeros((R, n, n))
        self.B = np.zeros((R, n, n))
        self.D = np.zeros((R, n))
        self.ps = np.zeros((R, n))
        self.pc = np.zeros((R, n))
        self.gen = np.zeros(R, dtype=np.int64)
        self.eigen_gen = np.zeros(R, dtype=np.int64)
        self.history = np.zeros((R, setting(self.lam0, n).history))
        self.steps = np.zeros((R, self.lam0, n))  # y of the queued generation
        runs = np.arange(R)
        self._restart(runs)
        self._sample(runs)

    def _restart(self, runs: NDArray[np.int64]) -> None:
        n = self.d
        for r in runs:  # the new mean from the run's own stream
            self.mean[r] = self.rng.generators[r].random(n)
        self.sigma[runs] = float(self.p["sigma0"])
        self.C[runs] = np.eye(n)
        self.B[runs] = np.eye(n)
        self.D[runs] = 1.0
        self.ps[runs] = 0.0
        self.pc[runs] = 0.0
        self.gen[runs] = 0
        self.eigen_gen[runs] = 0

    def _groups(self, runs: NDArray[np.int64]) -> list[NDArray[np.int64]]:
        """``runs`` split by lambda (each group's arrays have the shapes of its own lambda)."""
        lams = self.lam[runs]
        return [runs[lams == lam] for lam in np.unique(lams)]

    def _sample(self, runs: NDArray[np.int64]) -> None:
        for group in self._groups(runs):
            lam = int(self.lam[group[0]])
            z = np.stack([self.rng.generators[r].standard_normal((lam, self.d)) for r in group])
            # y = B D z: (G, lam, n) @ (G, n, n)
            y = np.matmul(z * self.D[group, None, :], self.B[group].transpose(0, 2, 1))
            if y.shape[1] > self.steps.shape[1]:
                grown = np.zeros((self.R, y.shape[1], self.d))
                grown[:, : self.steps.shape[1]] = self.steps
                self.steps = grown
            self.steps[group, :lam] = y
            genotype = self.mean[group, None, :] + self.sigma[group, None, None] * y
            self.put(group, self._phenotype(group, genotype))

    def _phenotype(self, runs: NDArray[np.int64], genotype: Array) -> Array:
        lower = self.lb[runs]
        x = lower + self.width[runs, None, :] * genotype
        upper = self.ub[runs]
        if self.p["bounds"] == "clip":
            return np.clip(x, lower, upper)
        return box_transform(x, lower, upper)

    # ---------------------------------------------------------------------------- update
    def _end(self, runs: NDArray[np.int64]) -> None:
        stopped = []
        for group in self._groups(runs):
            stopped.append(group[self._update(group)])
        done = np.concatenate(stopped) if stopped else np.zeros(0, dtype=np.int64)
        going = np.setdiff1d(runs, done)
        if done.size:
            if self.p["restarts"] == "ipop":
                again = done[self.restarts[done] < int(self.p["max_restarts"])]
                ended = np.setdiff1d(done, again)
                if again.size:
                    self.restarts[again] += 1
                    self.lam[again] = np.maximum(
                        self.lam[again] + 1,
                        np.floor(self.lam0 * float(self.p["incpopsize"]) ** self.restarts[again]),
                    ).astype(np.int64)
                    self._restart(again)
                    going = np.union1d(going, again)
            else:
                ended = done
            if ended.size:
                self.stop(ended)
        if going.size:
            self._sample(going)

    def _update(self, g: NDArray[np.int64]) -> NDArray[np.bool_]:
        """One generation of the runs ``g`` (one lambda); returns which of them must stop."""
        n = self.d
        s = setting(int(self.lam[g[0]]), n)
        lam, mu = s.lam, s.mu
        F = self.queue_values[g, :lam]
        order = np.argsort(F, axis=1, kind="stable")
        y = np.take_along_axis(self.steps[g, :lam], order[:, :, None], axis=1)
        sigma = self.sigma[g]
        yw = np.matmul(s.weights[None, None, :mu], y[:, :mu])[:, 0]  # (G, n)
        self.mean[g] += sigma[:, None] * yw
        B, D = self.B[g], self.D[g]
        inv_sqrt = np.matmul(B / D[:, None, :], B.transpose(0, 2, 1))  # C^-1/2
        ps = (1 - s.cs) * self.ps[g] + math.sqrt(s.cs * (2 - s.cs) * s.mueff) * np.matmul(
            inv_sqrt, yw[:, :, None])[:, :, 0]
        gen = self.gen[g] + 1
        norm_ps = np.sqrt(np.sum(ps * ps, axis=1))
        hsig = norm_ps / np.sqrt(1 - (1 - s.cs) ** (2 * gen)) < (1.4 + 2 / (n + 1)) * s.chin
        pc = (1 - s.cc) * self.pc[g] + np.where(
            hsig, math.sqrt(s.cc * (2 - s.cc) * s.mueff), 0.0)[:, None] * yw
        # negative weights act on directions rescaled to length sqrt(n) in C's metric (eq 46)
        w = np.broadcast_to(s.weights, (len(g), lam)).copy()
        if lam > mu:
            z = np.matmul(y[:, mu:], inv_sqrt.transpose(0, 2, 1))
            w[:, mu:] *= n / np.maximum(np.sum(z * z, axis=2), 1e-300)
        rank_mu = np.matmul(y.transpose(0, 2, 1) * w[:, None, :], y)
        delta = np.where(hsig, 0.0, s.c1 * s.cc * (2 - s.cc))
        decay = 1 + delta - s.c1 - s.cmu * s.weights.sum()
        C = (decay[:, None, None] * self.C[g] + s.c1 * pc[:, :, None] * pc[:, None, :]
             + s.cmu * rank_mu)
        sigma = sigma * np.exp((s.cs / s.ds) * (norm_ps / s.chin - 1))
        self.ps[g], self.pc[g], self.C[g], self.sigma[g], self.gen[g] = ps, pc, C, sigma, gen
        fresh = gen - self.eigen_gen[g] > s.eigen_every
        bad = ~np.isfinite(C).all(axis=(1, 2)) | ~np.isfinite(sigma) | ~np.isfinite(
            self.mean[g]).all(axis=1)
        ok = fresh & ~bad
        if ok.any():
            idx = g[ok]
            sym = np.triu(self.C[idx]) + np.triu(self.C[idx], 1).transpose(0, 2, 1)
            vals, vecs = np.linalg.eigh(sym)
            self.C[idx] = sym
            self.D[idx] = np.sqrt(np.maximum(vals, 1e-300))
            self.B[idx] = vecs
            self.eigen_gen[idx] = gen[ok]
            bad[np.flatnonzero(ok)[vals.min(axis=1) <= 0]] = True
        return bad | self._stopping(g, s, F)

    def _stopping(self, g: NDArray[np.int64], s: Setting, F: Array) -> NDArray[np.bool_]:
        """IPOP's five criteria (Auger & Hansen 2005, Sect. 2) for the runs ``g``."""
        n = self.d
        gen = self.gen[g]
        window = s.history
        slot = (gen - 1) % self.history.shape[1]
        best = F.min(axis=1)
        self.history[g, slot] = best
        full = gen >= window
        stop = np.zeros(len(g), dtype=bool)
        if full.any():
            cols = (gen[:, None] - 1 - np.arange(window)[None, :]) % self.history.shape[1]
            hist = np.take_along_axis(self.history[g], cols, axis=1)
            flat = np.ptp(hist, axis=1) == 0
            spread = (np.maximum(hist.max(axis=1), F.max(axis=1))
                      - np.minimum(hist.min(axis=1), F.min(axis=1)))
            stop |= full & (flat | (spread < TOLFUN))
        sigma = self.sigma[g][:, None]
        tolx = TOLX * float(self.p["sigma0"])
        diag = np.sqrt(np.abs(np.diagonal(self.C[g], axis1=1, axis2=2)))
        stop |= np.all(sigma * np.abs(self.pc[g]) < tolx, axis=1) & np.all(sigma * diag < tolx,
                                                                           axis=1)
        m = self.mean[g]
        axis = (gen % n)
        rows = np.arange(len(g))
        step = 0.1 * sigma[:, 0] * self.D[g][rows, axis]
        stop |= np.all(m + step[:, None] * self.B[g][rows, :, axis] == m, axis=1)
        stop |= np.any(m + 0.2 * sigma * diag == m, axis=1)
        D = self.D[g]
        stop |= (D.max(axis=1) / D.min(axis=1)) ** 2 > MAX_CONDITION
        return stop
