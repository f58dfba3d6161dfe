"""Improved COOT (ICOOT): COOT with a gBest-led random movement and a density-based acceleration.

Abdulsaheb & Kadhim, "Robot Path Planning in Unknown Environments with Multi-Objectives Using an
Improved COOT Optimization Algorithm", IJIES 15(5) 2022 (seed 000), section 4, eqs 20-32; the
base algorithm is our COOT (authors' code semantics, see ``coot.py``), changed as follows.

* Random movement (eqs 20, 30): CP = CP + A acc R2 (target - CP) with the paper's target Q + gBest,
  Q ~ U(lb, ub) (eq 12 unchanged), R2 as in COOT (scalar or vector by COOT.m's rule).
  ``random_target``: "centred" (default) = gBest + Q - (lb + ub)/2, a uniform point in a box-sized
  neighbourhood centred on gBest: *identical* to the literal Q + gBest on every symmetric box
  (all of F1-F13) and translation-invariant on the others; "literal" = Q + gBest;
  "offset" = the two pulls (Q - CP) + (gBest - CP); "midpoint" = (Q + gBest) / 2.
* Leader following (eq 31): CP = LP_k + 2 acc R1 cos(2 pi R) (LP_k - CP).
* Leader movement (eq 32): Temp = 2 acc B R3 cos(2 pi R) (gBest - LP) +/- gBest; the paper's extra
  factor 2 is ``leader_gain``. The chain movement (eq 15) is unchanged, as in the paper.
* acc(j) = |(1 - D) + (1 - 1/|alpha|) - U(0, 2)| (eq 24): one U(0, 2) per agent and iteration
  (coots and leaders draw their own), D and alpha once per iteration and run from the coots'
  positions at the start of the iteration. The paper defines D and alpha on a 2-D map with a 1 m
  integer grid; our d-dimensional, scale-free reading (docs/algorithms.md):
  - coordinates in units of a lattice cell h = ``cell`` x (ub - lb) per axis (the paper's 1 m in
    a 10 m map is cell = 0.1);
  - r = max over axes of the half extent (max - min) / 2 of the coots, plus 1 cell (eqs 22-23,
    "|max| - |min|" read as the extent max - min);
  - D = N / (pi r^2) normalised by its largest value N / pi (r = 1 cell): D = r^-p in (0, 1],
    p = ``density_power`` (2: the paper's circle; p = dim gives a d-ball and D ~ 0 until collapse);
  - alpha = beta1 beta2 - eta (eq 25): beta1 = omega_p r^p lattice points in the circle/ball
    (omega_2 = pi), beta2 = eq 29 over all axes, sqrt(sum_k (s_k(2) - s_k(1))^2) with s_k the
    sorted k-th coordinates of the coots (in cells), eta = N_c points occupied by the coots;
  - guard: 1 - 1/max(|alpha|, 1), so the term is in [0, 1) and finite for alpha = 0.
  Hence acc is in [0, 2]. ``acc = "one"`` sets acc = 1 (ablation).

Bounds: clip before every evaluation. Evaluations: as COOT, N at initialization and N per
iteration (N_c coots + N_L leader proposals), N (T + 1) in all.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

from swarmpath.optimizers.base import Array, ParameterError, ParamValue
from swarmpath.optimizers.coot import COOT
from swarmpath.optimizers.registry import register


@register
class ICOOT(COOT):
    name = "ICOOT"
    summary = "Improved COOT (Abdulsaheb & Kadhim 2022): gBest-led random move, acceleration"
    reference = "Abdulsaheb & Kadhim, IJIES 15(5) 2022, eqs 20-32, on COOT (ESWA 183, 115352)"
    defaults: ClassVar[dict[str, Any]] = {
        **COOT.defaults,
        "random_target": "centred",
        "acc": "density",
        "cell": 0.1,
        "density_power": 2.0,
        "leader_gain": 2.0,
    }
    choices: ClassVar[dict[str, tuple[str, ...]]] = {
        **COOT.choices,
        "random_target": ("centred", "literal", "offset", "midpoint"),
        "acc": ("density", "one"),
    }

    @classmethod
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        super().check_params(p)
        if not 0.0 < float(p["cell"]) <= 1.0:
            raise ParameterError(f"{cls.name}.cell must be in (0, 1] (a fraction of the box)")
        if not float(p["density_power"]) > 0.0:
            raise ParameterError(f"{cls.name}.density_power must be > 0")
        if not float(p["leader_gain"]) > 0.0:
            raise ParameterError(f"{cls.name}.leader_gain must be > 0")

    def __init__(self, *args: Any, **kwargs: Any):
        super().__init__(*args, **kwargs)
        p = float(self.p["density_power"])
        self._omega = math.pi ** (p / 2.0) / math.gamma(p / 2.0 + 1.0)  # unit-ball volume
        self._cells = float(self.p["cell"]) * (self.ub - self.lb)[:, 0, :]  # (R, d)
        self._mid = (0.5 * (self.lb + self.ub))[:, 0, :]
        self.acc_coots = np.ones((self.R, self.Nc))
        self.acc_leaders = np.ones((self.R, self.NL))
        self.density = np.zeros(self.R)
        self.free_term = np.zeros(self.R)

    def _extra_layout(self) -> list[tuple[str, tuple[int, ...]]]:
        return [("c_accU", (self.Nc,)), ("l_accU", (self.NL,))]

    def swarm_terms(self, X: Array) -> tuple[Array, Array]:
        """(D, 1 - 1/|alpha|) of eqs 21-29 for coots X (R, n, d), each (R,) in [0, 1]."""
        p = float(self.p["density_power"])
        R, n, d = X.shape
        low = X.min(axis=1)
        extent = (X.max(axis=1) - low) / self._cells  # (R, d), in cells
        r = 0.5 * extent.max(axis=1) + 1.0  # eqs 22-23
        density = r ** (-p)  # eq 21 / its value at r = 1 cell
        if n >= 2:  # eqs 27-29: the two smallest coordinates per axis
            rest = X.copy()
            rest[np.arange(R)[:, None], X.argmin(axis=1), np.arange(d)] = np.inf
            gap = (rest.min(axis=1) - low) / self._cells
            beta2 = np.sqrt(np.einsum("rd,rd->r", gap, gap))
        else:
            beta2 = np.zeros(R)
        alpha = self._omega * r**p * beta2 - X.shape[1]  # eqs 25-26
        free = 1.0 - 1.0 / np.maximum(np.abs(alpha), 1.0)
        return density, free

    def _prepare(self, u: dict[str, Array]) -> None:
        if self.p["acc"] == "one":
            return
        self.density, self.free_term = self.swarm_terms(self.CP)
        s = ((1.0 - self.density) + self.free_term)[:, None]
        self.acc_coots = np.abs(s - 2.0 * u["c_accU"])  # eq 24, U(0, 2) = 2u
        self.acc_leaders = np.abs(s - 2.0 * u["l_accU"])

    def _acc(self, group: str) -> Array | None:
        if self.p["acc"] == "one":
            return None
        return self.acc_coots if group == "c" else self.acc_leaders

    def _leader_gain(self) -> float:
        return float(self.p["leader_gain"])

    def _random_target(self, Q: Array, X: Array) -> Array:
        mode = self.p["random_target"]
        g = self.g[:, None, :]
        if mode == "centred":
            Q += g - self._mid[:, None, :]
        elif mode == "literal":
            Q += g
        elif mode == "offset":  # X + w((Q - X) + (g - X)) = X + w(T - X) with T = Q + g - X
            Q += g
            Q -= X
        else:  # midpoint
            Q += g
            Q *= 0.5
        return Q
