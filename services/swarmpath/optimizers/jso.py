"""jSO (Brest, Maucec & Boskovic, CEC 2017): iL-SHADE with weighted mutation, on L-SHADE's frame.

J. Brest, M. S. Maucec and B. Boskovic, "Single objective real-parameter optimization:
algorithm jSO", IEEE CEC 2017, 1311-1318; where the paper leaves room, the authors' C++ code
(the jSO package of the CEC 2017 competition, whose runs are the paper's tables), as
docs/algorithms.md lists. Changes to L-SHADE (:mod:`swarmpath.optimizers.lshade`):

* N_init = round(25 ln(D) sqrt(D)), N_min = 4; H = 5 memory slots starting at M_F = 0.3,
  M_CR = 0.8; the last slot always gives M_F = M_CR = 0.9 (the update still cycles through it,
  so one update in H is never read); archive rate 1; p from p_max = 0.25 down to p_max / 2
  linearly in NFE (recomputed when the population shrinks);
* CR_i at least 0.7 while NFE < MAX/4 and at least 0.6 while NFE < MAX/2; F_i at most 0.7 while
  NFE < 0.6 MAX; a memory slot below 0 gives CR_i = 0 (the code's test, where averaging the
  terminal -1 with an old value lands);
* current-to-pBest-w/1: v = x_i + F_w (x_pbest - x_i) + F (x_r1 - x_r2), F_w = 0.7 F while NFE <
  0.2 MAX, 0.8 F while NFE < 0.4 MAX, 1.2 F after; pbest is not x_i itself while NFE < MAX/2;
* the memory slot takes the mean of its old value and the weighted Lehmer mean (iL-SHADE).
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from swarmpath.optimizers.base import Array
from swarmpath.optimizers.lshade import SHADEFamily, c_round
from swarmpath.optimizers.registry import register


@register
class JSO(SHADEFamily):
    name = "jSO"
    summary = "jSO (Brest, Maucec & Boskovic, CEC 2017): iL-SHADE with weighted mutation"
    reference = ("Brest, Maucec & Boskovic, IEEE CEC 2017, 1311-1318, Algorithm 1; authors' "
                 "C++ jSO (CEC 2017 package)")
    defaults: ClassVar = {"popsize": 0, "n_min": 4, "memory_size": 5, "archive_rate": 1.0,
                          "p_best": 0.25}
    memory_f0 = 0.3
    memory_cr0 = 0.8

    def initial_size(self) -> int:
        """N_init = round(25 ln(D) sqrt(D))."""
        return c_round(25 * math.log(self.d) * math.sqrt(self.d))

    def terminal(self, mu_cr: Array) -> NDArray[np.bool_]:
        return mu_cr < 0

    def slot_means(self, slot: NDArray[np.int64], mu_f: Array, mu_cr: Array) -> tuple[Array,
                                                                                       Array]:
        last = slot == self.memory_f.shape[1] - 1
        return np.where(last, 0.9, mu_f), np.where(last, 0.9, mu_cr)

    def adjust(self, f: Array, cr: Array, nfes: int) -> tuple[Array, Array, Array]:
        top = self.planned
        if nfes < 0.25 * top:
            cr = np.maximum(cr, 0.7)
        elif nfes < 0.5 * top:
            cr = np.maximum(cr, 0.6)
        if nfes < 0.6 * top:
            f = np.minimum(f, 0.7)
        weight = 0.7 if nfes < 0.2 * top else 0.8 if nfes < 0.4 * top else 1.2
        return f, cr, weight * f

    def exclude_target(self, nfes: int) -> bool:
        return nfes < 0.5 * self.planned

    def merge_memory(self, new: Array, old: Array) -> Array:
        return (new + old) / 2

    def p_after_reduction(self, nfes: int) -> float:
        return float(self.p["p_best"]) * (1 - 0.5 * nfes / self.planned)
