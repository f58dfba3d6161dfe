"""L-SHADE (Tanabe & Fukunaga, CEC 2014), vectorized over runs; the frame jSO builds on.

R. Tanabe and A. S. Fukunaga, "Improving the search performance of SHADE using linear
population size reduction", IEEE CEC 2014, 1658-1665, Algorithm 1 and eqs (1)-(13); where the
paper leaves room, the authors' C++ code (L-SHADE 1.0.1, whose numbers the CEC 2014 tables
are), as docs/algorithms.md lists:

* current-to-pbest/1/bin with an external archive: v = x_i + F (x_pbest - x_i) + F (x_r1 - x_r2),
  pbest uniform among the round(p N) best (at least 2), r1 from the population (not i), r2 from
  population plus archive (neither i nor r1); binomial crossover with one forced component; a
  component outside the box is set midway between the parent's and the bound (JADE's rule);
* CR_i ~ N(M_CR,r, 0.1) clipped to [0, 1] (0 when M_CR,r is the terminal value), F_i ~
  Cauchy(M_F,r, 0.1) redrawn while <= 0 and cut to 1, r uniform over the H memory slots;
* selection u_i <= x_i; parents beaten strictly go to the archive (random slot once full) and
  their (F, CR, |delta f|) to the success sets; the memory slot k (cycling, advanced only after a
  generation with successes) takes the weighted Lehmer means (terminal CR when every successful
  CR is 0);
* after each generation N = round(N_init + (N_min - N_init) NFE / MAX_NFE): the worst go, the
  archive shrinks to floor(r_arc N) keeping its first entries, round(p N) is recomputed.

Vectorized: the population size depends only on the evaluations spent, the same in every run,
so all runs step in lockstep and every draw is one array over runs (each row from its run's own
stream). Draws with exclusions (r1 != i, r2 != i, r1; F > 0) are drawn directly from the
conditional distribution instead of by rejection, so each run uses the same count of numbers
whatever the other runs do. MAX_NFE: see :mod:`swarmpath.optimizers.generations`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from swarmpath.optimizers.base import Array, ParameterError, ParamValue
from swarmpath.optimizers.generations import Generational
from swarmpath.optimizers.registry import register

#: The terminal value of a CR memory slot (the paper's bottom symbol; the code's -1).
TERMINAL = -1.0


def c_round(x: float) -> int:
    """C's round() for x >= 0 (half away from zero), which the authors' codes use."""
    return math.floor(x + 0.5)


class SHADEFamily(Generational):
    """The shared frame of L-SHADE and jSO; subclasses set the parameter rules (hooks)."""

    memory_f0: ClassVar[float] = 0.5
    memory_cr0: ClassVar[float] = 0.5

    @classmethod
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        for key in ("popsize", "memory_size", "n_min"):
            if int(p[key]) != p[key] or int(p[key]) < 0:
                raise ParameterError(f"{cls.name}.{key} must be a non-negative integer")
        if int(p["memory_size"]) < 1:
            raise ParameterError(f"{cls.name}.memory_size must be >= 1")
        if int(p["n_min"]) < 4:
            raise ParameterError(f"{cls.name}.n_min must be >= 4 (r1, r2, pbest and i)")
        if not float(p["archive_rate"]) >= 0:
            raise ParameterError(f"{cls.name}.archive_rate must be >= 0")
        if not 0 < float(p["p_best"]) <= 1:
            raise ParameterError(f"{cls.name}.p_best must be in (0, 1]")

    def initial_size(self) -> int:
        raise NotImplementedError

    # ---------------------------------------------------------------- hooks (L-SHADE's rules)
    def terminal(self, mu_cr: Array) -> NDArray[np.bool_]:
        """Where CR_i is 0: the memory holds the terminal value."""
        return mu_cr == TERMINAL

    def slot_means(self, slot: NDArray[np.int64], mu_f: Array, mu_cr: Array) -> tuple[Array,
                                                                                       Array]:
        """The (M_F, M_CR) drawn for each individual."""
        return mu_f, mu_cr

    def adjust(self, f: Array, cr: Array, nfes: int) -> tuple[Array, Array, Array]:
        """(F, CR, F of the pbest term) for the generation starting at ``nfes``."""
        return f, cr, f

    def exclude_target(self, nfes: int) -> bool:
        """Whether pbest may not be the target itself."""
        return False

    def merge_memory(self, new: Array, old: Array) -> Array:
        return new

    def p_after_reduction(self, nfes: int) -> float:
        return float(self.p["p_best"])

    # ----------------------------------------------------------------------------- state
    def _begin(self) -> None:
        R, H = self.R, int(self.p["memory_size"])
        self.n_init = max(int(self.p["n_min"]), int(self.p["popsize"]) or self.initial_size())
        self.size = self.n_init
        self.archive_size = int(self.size * float(self.p["archive_rate"]) + 0.5)
        self.archive = np.zeros((R, max(self.archive_size, 1), self.d))
        self.archive_count = np.zeros(R, dtype=np.int64)
        self.memory_f = np.full((R, H), self.memory_f0)
        self.memory_cr = np.full((R, H), self.memory_cr0)
        self.memory_pos = np.zeros(R, dtype=np.int64)
        self.p_num = max(c_round(self.size * float(self.p["p_best"])), 2)
        self.pop = self.random_population(self.size)
        self.fit: Array | None = None
        self.put(self._run_index, self.pop)

    def _end(self, runs: NDArray[np.int64]) -> None:
        if runs.size != self.R:  # every run has the same schedule (module docstring)
            raise AssertionError("the SHADE family steps all runs together")
        values = self.queue_values[:, : self.size]
        nfes = int(self.spent[0])
        if self.fit is None:
            self.fit = values.copy()
        else:
            self._select(values)
            self._reduce(nfes)
        self._trials(nfes)

    def _select(self, values: Array) -> None:
        assert self.fit is not None
        better = values < self.fit
        replace = better | (values == self.fit)
        self._archive(better)
        self._remember(better, np.abs(self.fit - values))
        trials = self.queue[:, : self.size]
        self.pop = np.where(replace[:, :, None], trials, self.pop)
        self.fit = np.where(replace, values, self.fit)

    def _archive(self, better: NDArray[np.bool_]) -> None:
        """Parents beaten strictly, in index order: into free slots, then random slots."""
        if self.archive_size <= 1:  # the code keeps no archive of size 0 or 1
            return
        order = np.cumsum(better, axis=1) - 1  # rank of each success within its run
        free = self.archive_size - self.archive_count
        slot = self.archive_count[:, None] + order
        randoms = np.floor(self.rng.random(self.size) * self.archive_size).astype(np.int64)
        slot = np.where(order < free[:, None], slot, randoms)
        r, i = np.nonzero(better)  # row-major: each run's successes in index order
        self.archive[r, slot[r, i]] = self.pop[r, i]  # a repeated slot keeps the last parent
        self.archive_count = np.minimum(self.archive_count + better.sum(axis=1),
                                        self.archive_size)

    def _remember(self, better: NDArray[np.bool_], delta: Array) -> None:
        """The weighted Lehmer means of the successful F and CR into each run's next slot."""
        wins = better.any(axis=1)
        if not wins.any():
            return
        delta = np.where(better, delta, 0.0)
        infinite: NDArray[np.bool_] = np.isinf(delta)
        delta = np.where(np.any(infinite, axis=1)[:, None], infinite.astype(float), delta)
        weights = delta / np.where(wins, delta.sum(axis=1), 1.0)[:, None]
        f, cr = self.f_used, self.cr_used
        lehmer_f = np.sum(weights * f * f, axis=1) / np.maximum(np.sum(weights * f, axis=1),
                                                                1e-300)
        cr_den = np.sum(weights * cr, axis=1)
        lehmer_cr = np.where(cr_den == 0, TERMINAL,
                             np.sum(weights * cr * cr, axis=1) / np.where(cr_den == 0, 1, cr_den))
        rows = np.flatnonzero(wins)
        pos = self.memory_pos[rows]
        self.memory_f[rows, pos] = self.merge_memory(lehmer_f[rows], self.memory_f[rows, pos])
        self.memory_cr[rows, pos] = self.merge_memory(lehmer_cr[rows], self.memory_cr[rows, pos])
        self.memory_pos[rows] = (pos + 1) % self.memory_f.shape[1]

    def _reduce(self, nfes: int) -> None:
        """Linear population size reduction (eq 13) after the generation."""
        assert self.fit is not None
        n_min = int(self.p["n_min"])
        plan = c_round((n_min - self.n_init) / self.planned * nfes + self.n_init)
        if self.size <= plan:
            return
        keep = self.size - (self.size - max(plan, n_min))
        worst_first = np.argsort(-self.fit, axis=1, kind="stable")
        kept = np.sort(worst_first[:, self.size - keep:], axis=1)
        self.pop = np.take_along_axis(self.pop, kept[:, :, None], axis=1)
        self.fit = np.take_along_axis(self.fit, kept, axis=1)
        self.size = keep
        self.archive_size = int(keep * float(self.p["archive_rate"]))
        self.archive_count = np.minimum(self.archive_count, self.archive_size)
        self.p_num = max(c_round(keep * self.p_after_reduction(nfes)), 2)

    # ---------------------------------------------------------------------------- trials
    def _trials(self, nfes: int) -> None:
        """The next generation's trial vectors, one per individual."""
        assert self.fit is not None
        n, d = self.size, self.d
        H = self.memory_f.shape[1]
        u_slot, u_f, u_best, u_r1, u_r2, u_j = self.rng.random_parts(6, n)
        z_cr = self.rng.normal(n)
        u_cross = self.rng.random(n, d)
        slot = np.minimum((u_slot * H).astype(np.int64), H - 1)
        mu_f = np.take_along_axis(self.memory_f, slot, axis=1)
        mu_cr = np.take_along_axis(self.memory_cr, slot, axis=1)
        mu_f, mu_cr = self.slot_means(slot, mu_f, mu_cr)
        cr = np.where(self.terminal(mu_cr), 0.0, np.clip(mu_cr + 0.1 * z_cr, 0.0, 1.0))
        # Cauchy(mu_f, 0.1) conditioned on F > 0, by its inverse distribution function
        u0 = 0.5 + np.arctan(-mu_f / 0.1) / np.pi
        f = mu_f + 0.1 * np.tan(np.pi * (u0 + (1 - u0) * u_f - 0.5))
        f = np.minimum(np.maximum(f, np.finfo(float).tiny), 1.0)
        f, cr, f_best = self.adjust(f, cr, nfes)
        self.f_used, self.cr_used = f, cr
        ranked = np.argsort(self.fit, axis=1, kind="stable")
        target = np.arange(n)[None, :]
        if self.exclude_target(nfes):
            rank_of = np.argsort(ranked, axis=1)  # each individual's rank
            inside = rank_of < self.p_num
            k = np.floor(u_best * np.where(inside, self.p_num - 1, self.p_num)).astype(np.int64)
            k += inside & (k >= rank_of)
        else:
            k = np.floor(u_best * self.p_num).astype(np.int64)
        best = np.take_along_axis(ranked, np.minimum(k, self.p_num - 1), axis=1)
        r1 = np.floor(u_r1 * (n - 1)).astype(np.int64)
        r1 += r1 >= target
        pool = n + self.archive_count[:, None]
        r2 = np.minimum(np.floor(u_r2 * (pool - 2)).astype(np.int64), pool - 3)
        low, high = np.minimum(target, r1), np.maximum(target, r1)
        r2 += r2 >= low
        r2 += r2 >= high
        rows = self._run_index[:, None]
        x = self.pop
        from_archive = r2 >= n
        x_r2 = np.where(from_archive[:, :, None],
                        self.archive[rows, np.clip(r2 - n, 0, self.archive.shape[1] - 1)],
                        x[rows, np.minimum(r2, n - 1)])
        mutant = (x + f_best[:, :, None] * (x[rows, best] - x)
                  + f[:, :, None] * (x[rows, r1] - x_r2))
        j_rand = np.minimum((u_j * d).astype(np.int64), d - 1)
        cross = (u_cross < cr[:, :, None]) | (np.arange(d)[None, None, :] == j_rand[:, :, None])
        trial = np.where(cross, mutant, x)
        lower, upper = self.full_bounds(n)
        trial = np.where(trial < lower, (lower + x) / 2, trial)
        trial = np.where(trial > upper, (upper + x) / 2, trial)
        self.put(self._run_index, trial)


@register
class LSHADE(SHADEFamily):
    name = "L-SHADE"
    summary = "L-SHADE (Tanabe & Fukunaga, CEC 2014 winner): SHADE with linear population reduction"
    reference = ("Tanabe & Fukunaga, IEEE CEC 2014, 1658-1665, Algorithm 1, eqs 1-13; "
                 "authors' C++ L-SHADE 1.0.1")
    defaults: ClassVar = {"popsize": 0, "r_ninit": 18.0, "n_min": 4, "memory_size": 6,
                          "archive_rate": 2.6, "p_best": 0.11}

    @classmethod
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        super().check_params(p)
        if not float(p["r_ninit"]) > 0:
            raise ParameterError("L-SHADE.r_ninit must be > 0")

    def initial_size(self) -> int:
        """N_init = round(r_Ninit D) (18 D)."""
        return c_round(float(self.p["r_ninit"]) * self.d)
