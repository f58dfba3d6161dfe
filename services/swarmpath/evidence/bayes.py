"""Bayesian comparison with a region of practical equivalence (rope): pure numpy, no I/O.

Following Benavoli, Corani, Demsar and Zaffalon, "Time for a change: a tutorial for comparing
multiple classifiers through Bayesian analysis", JMLR 18 (2017) 1-36: instead of a p-value, the
posterior probabilities that the algorithm is better than the reference by more than the rope,
practically equivalent to it (within the rope), or worse.

* **Per cell** (one function and dimension, or one map and measure), the runs of the two
  algorithms are independent samples, so the paired tests of ``baycomp`` (the correlated t-test
  and the signed-rank test pair their inputs) do not apply. Each sample gets the Bayesian
  bootstrap (Rubin, Ann. Stat. 9 (1981) 130-134): the Dirichlet-process posterior of its
  distribution with a vanishing prior, i.e. Dirichlet(1, ..., 1) weights on the observed runs,
  the same nonparametric model as baycomp's tests (Benavoli et al., ICML 2014). Each posterior
  draw gives each sample's weighted mean (``stat="mean"``) or weighted median (``"median"``);
  their difference d = s(algorithm) - s(reference) falls below -rope (better, with lower values
  better), inside [-rope, rope] (equivalent) or above (worse). The probabilities are the shares
  of :data:`CELL_DRAWS` draws from ``numpy.random.default_rng(seed)`` (for the mean of cells
  above 419 runs, 2^22 / n draws, at least :data:`MIN_DRAWS`; the median is drawn exactly from
  its Beta form, any n): the same inputs give the same numbers, in any order, on any machine.
* **Across functions (or maps)**, the Bayesian signed-rank test (Benavoli et al. 2014; section 4
  of the 2017 tutorial) on the per-block differences of the cell statistic, the same difference
  and rope as per cell. :func:`signed_rank` is baycomp's ``SignedRankTest`` (prior strength 0.5
  on a pseudo-observation at 0, ``numpy.random.RandomState(seed).dirichlet`` weights,
  :data:`ACROSS_DRAWS` draws, the winner of each draw counted) vectorized over the draws:
  baycomp loops over them in Python (about 2 s per pair here); ``tests/test_bayes.py`` checks
  that both give the same probabilities.

**The rope** is declared, never implied (:class:`Rope`, ``--rope``): an absolute width in the
measure's units (``--rope 1e-8``), or relative with a ``%`` suffix (``--rope 1%``, the default):
then the difference is divided by the larger of the two statistics' distances to the optimum
(f - f* for a benchmark function, the value itself for a path length, gap or time), so 1 % means
"within 1 % of the worse of the two". A verdict is declared when one probability reaches
:data:`DECISION` (0.95, the tutorial's threshold); otherwise the cell is ``undecided``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "ACROSS_DRAWS", "CELL_DRAWS", "DECISION", "DEFAULT_ROPE", "STATS", "BayesComparison",
    "BayesTest", "Posterior", "Rope", "cell_posterior", "compare_bayes", "parse_rope",
    "signed_rank",
]

K = TypeVar("K", bound=Hashable)
STATS = ("mean", "median")
CELL_DRAWS = 10_000
ACROSS_DRAWS = 50_000  # baycomp's default
#: Prior strength of the signed-rank test's pseudo-observation at 0 (baycomp's default).
PRIOR = 0.5
DECISION = 0.95
BETTER, EQUIVALENT, WORSE, UNDECIDED = "better", "equivalent", "worse", "undecided"
#: Elements per block of Dirichlet weights (memory bound for cells of thousands of runs).
_BLOCK = 1 << 21
#: Exponentials per sample of a mean posterior: above 419 runs the draws shrink to keep it,
#: down to MIN_DRAWS (a summary of 1000-run cells stays within seconds).
_MEAN_WORK = 1 << 22
MIN_DRAWS = 2000


@dataclass(frozen=True)
class Rope:
    """A region of practical equivalence: ``width`` absolute, or a fraction when ``relative``."""

    width: float
    relative: bool = False

    def __post_init__(self) -> None:
        if not (math.isfinite(self.width) and self.width >= 0):
            raise ValueError(f"the rope must be a finite number >= 0, got {self.width!r}")
        if self.relative and self.width >= 1:
            raise ValueError(f"a relative rope must be below 100%, got {100 * self.width:g}%")

    def __str__(self) -> str:
        return f"{100 * self.width:g}%" if self.relative else f"{self.width:g}"

    def describe(self) -> str:
        return (f"rope {self} of the larger distance to the optimum" if self.relative
                else f"rope {self} in the measure's units")


DEFAULT_ROPE = Rope(0.01, relative=True)


def parse_rope(text: str | float | Rope | None) -> Rope:
    """``"1%"`` (relative), ``"0.5"`` or ``1e-8`` (absolute), a Rope, or None (the default).
    ValueError says what is wrong."""
    if text is None:
        return DEFAULT_ROPE
    if isinstance(text, Rope):
        return text
    if isinstance(text, int | float) and not isinstance(text, bool):
        return Rope(float(text))
    s = str(text).strip()
    relative = s.endswith("%")
    try:
        value = float(s[:-1] if relative else s)
    except ValueError:
        raise ValueError(f"{text!r} is not a number or a percentage (e.g. 1e-8 or 1%)") from None
    return Rope(value / 100.0 if relative else value, relative)


@dataclass(frozen=True)
class Posterior:
    """P(better), P(equivalent), P(worse) of an algorithm against the reference."""

    p_better: float
    p_equivalent: float
    p_worse: float

    @property
    def verdict(self) -> str:
        for name, p in ((BETTER, self.p_better), (EQUIVALENT, self.p_equivalent),
                        (WORSE, self.p_worse)):
            if p >= DECISION:
                return name
        return UNDECIDED

    def short(self) -> str:
        """``0.97/0.02/0.01`` (better/equivalent/worse)."""
        return f"{self.p_better:.2f}/{self.p_equivalent:.2f}/{self.p_worse:.2f}"

    def to_json(self) -> dict[str, Any]:
        return {"p_better": self.p_better, "p_equivalent": self.p_equivalent,
                "p_worse": self.p_worse, "verdict": self.verdict}


def _clean(values: ArrayLike) -> np.ndarray:
    x = np.asarray(values, dtype=float).ravel()
    return x[~np.isnan(x)]


def _bootstrap(x: np.ndarray, stat: str, rng: np.random.Generator, draws: int) -> np.ndarray:
    """``draws`` Bayesian-bootstrap draws of the mean or median of ``x``.

    The median is drawn exactly from its distribution: with sorted values and Dirichlet(1, ...,
    1) weights, the sum of the k smallest weights is Beta(k, n - k), so the weighted median (the
    first value whose cumulative weight reaches 1/2) is x_(k) with probability
    P(S_k >= 1/2) - P(S_(k-1) >= 1/2); a uniform per draw picks k. The mean needs the weights
    themselves: n exponentials per draw, at most :data:`_BLOCK` per block."""
    out = np.empty(draws)
    if np.all(x == x[0]):  # one value (or all equal): every weighting gives it
        out[:] = x[0]
        return out
    order = np.sort(x)
    n = order.size
    if stat == "median":
        from scipy import stats

        k = np.arange(1, n)
        cdf = np.concatenate([stats.beta.sf(0.5, k, n - k), [1.0]])
        return order[np.minimum(np.searchsorted(cdf, rng.random(draws)), n - 1)]
    if not np.isfinite(order).all():  # every weight is > 0: an infinite value decides
        out[:] = _infinite_mean(order)
        return out
    per = max(1, _BLOCK // n)
    for start in range(0, draws, per):
        k_rows = min(per, draws - start)
        w = rng.standard_exponential((k_rows, n))  # normalised: Dirichlet(1, ..., 1)
        out[start:start + k_rows] = (w @ order) / w.sum(axis=1)
    return out


def _infinite_mean(values: np.ndarray) -> float:
    has_pos, has_neg = bool(np.any(values == np.inf)), bool(np.any(values == -np.inf))
    return math.nan if has_pos and has_neg else (math.inf if has_pos else -math.inf)


def _classify(d: np.ndarray, rope: float, lower_is_better: bool) -> Posterior:
    """Shares of differences below -rope, within, above (NaN: inf - inf, counted equivalent)."""
    d = np.where(np.isnan(d), 0.0, d)
    below = float(np.mean(d < -rope))
    above = float(np.mean(d > rope))
    within = float(np.mean(np.abs(d) <= rope))
    return (Posterior(below, within, above) if lower_is_better
            else Posterior(above, within, below))


def relative_difference(a: np.ndarray, b: np.ndarray, offset: float = 0.0) -> np.ndarray:
    """(a - b) / max(|a - offset|, |b - offset|), 0 where both are at the offset."""
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.maximum(np.abs(np.asarray(a) - offset), np.abs(np.asarray(b) - offset))
        diff = np.asarray(a) - np.asarray(b)
        rel = np.where(scale > 0, diff / np.where(scale > 0, scale, 1.0), 0.0)
    return np.asarray(rel, dtype=float)


def cell_posterior(
    x: ArrayLike,
    reference: ArrayLike,
    rope: Rope = DEFAULT_ROPE,
    stat: str = "mean",
    offset: float = 0.0,
    lower_is_better: bool = True,
    draws: int = CELL_DRAWS,
    seed: int = 0,
) -> Posterior | None:
    """The per-cell posterior (module doc) of ``x`` against ``reference``; ``offset``: the
    optimum the relative rope measures distances from. None when a sample is empty."""
    if stat not in STATS:
        raise ValueError(f"stat must be one of {', '.join(STATS)}, got {stat!r}")
    a, b = _clean(x), _clean(reference)
    if a.size == 0 or b.size == 0:
        return None
    rng = np.random.default_rng(seed)
    if stat == "mean":  # n exponentials per draw: fewer draws for very large cells
        draws = max(MIN_DRAWS, min(draws, _MEAN_WORK // max(a.size, b.size)))
    sa = _bootstrap(a, stat, rng, draws)
    sb = _bootstrap(b, stat, rng, draws)
    with np.errstate(invalid="ignore"):
        d = relative_difference(sa, sb, offset) if rope.relative else sa - sb
    return _classify(d, rope.width, lower_is_better)


def signed_rank(
    differences: ArrayLike,
    rope: float = 0.0,
    lower_is_better: bool = True,
    draws: int = ACROSS_DRAWS,
    seed: int = 0,
    prior: float = PRIOR,
) -> Posterior:
    """The Bayesian signed-rank test of the per-block ``differences`` (algorithm - reference)
    against 0 with a rope of half-width ``rope``: baycomp's ``SignedRankTest`` vectorized (same
    draws, same counting; see the module doc)."""
    d = np.asarray(differences, dtype=float).ravel()
    if d.size == 0 or np.isnan(d).any():
        raise ValueError("signed_rank needs at least one difference and no NaN")
    z = np.concatenate([[0.0], d])
    with np.errstate(invalid="ignore"):
        sums = z[:, None] + z[None, :]
    sums = np.where(np.isnan(sums), 0.0, sums)

    def heaviside(a: np.ndarray, threshold: float) -> np.ndarray:
        return (a > threshold).astype(float) + 0.5 * (a == threshold).astype(float)

    below, above = heaviside(-sums, 2 * rope), heaviside(sums, 2 * rope)
    weights = np.ones(z.size)
    weights[0] = prior
    w = np.random.RandomState(seed).dirichlet(weights, draws)
    p_below = np.einsum("si,ij,sj->s", w, below, w)
    p_above = np.einsum("si,ij,sj->s", w, above, w)
    sample = np.stack([p_below, 1.0 - p_below - p_above, p_above], axis=1)
    counts = np.bincount(np.argmax(sample, axis=1), minlength=3) / draws
    pb, pe, pa = (float(v) for v in counts)
    return Posterior(pb, pe, pa) if lower_is_better else Posterior(pa, pe, pb)


@dataclass(frozen=True)
class BayesTest:
    """One algorithm against the reference in one cell."""

    key: Hashable
    algorithm: str
    n: int
    n_reference: int
    posterior: Posterior | None  # None: a sample is empty


@dataclass(frozen=True)
class BayesComparison:
    """Every algorithm against the reference, per cell and per group of cells (a dimension of a
    benchmark study, or all the maps), with the declared rope and statistic."""

    algorithms: tuple[str, ...]
    reference: str
    rope: Rope
    stat: str
    lower_is_better: bool
    tests: tuple[BayesTest, ...]
    #: group -> algorithm -> {"blocks": n, **posterior} (the signed-rank test over the cells)
    across: dict[Hashable, dict[str, dict[str, Any]]]

    def get(self, key: Hashable, algorithm: str) -> Posterior | None:
        for t in self.tests:
            if t.key == key and t.algorithm == algorithm:
                return t.posterior
        return None

    def index(self) -> dict[tuple[Hashable, str], Posterior | None]:
        return {(t.key, t.algorithm): t.posterior for t in self.tests}

    def verdict_counts(self) -> dict[str, dict[str, int]]:
        """Per algorithm other than the reference: cells per verdict."""
        names = (BETTER, EQUIVALENT, WORSE, UNDECIDED)
        out = {a: dict.fromkeys(names, 0) for a in self.algorithms if a != self.reference}
        for t in self.tests:
            if t.posterior is not None:
                out[t.algorithm][t.posterior.verdict] += 1
        return out

    def to_json(self, key_fields: Sequence[str] = ("key",),
                group_field: str = "group") -> dict[str, Any]:
        def key_dict(key: Hashable) -> dict[str, Any]:
            parts = key if isinstance(key, tuple) else (key,)
            return dict(zip(key_fields, parts, strict=True))

        return {
            "test": "bayesian bootstrap per cell, bayesian signed-rank across cells",
            "reference": self.reference, "rope": str(self.rope),
            "rope_relative": self.rope.relative, "rope_width": self.rope.width,
            "stat": self.stat, "decision": DECISION, "lower_is_better": self.lower_is_better,
            "verdict_counts": self.verdict_counts(),
            "tests": [{**key_dict(t.key), "algorithm": t.algorithm, "n": t.n,
                       "n_reference": t.n_reference,
                       **(t.posterior.to_json() if t.posterior else
                          {"p_better": None, "p_equivalent": None, "p_worse": None,
                           "verdict": None})}
                      for t in self.tests],
            "across": [{group_field: g, "algorithm": a, **v}
                       for g, per in self.across.items() for a, v in per.items()],
        }


def point_statistic(values: np.ndarray, stat: str) -> float:
    """The cell's mean or median (of non-NaN values; inf kept)."""
    if stat == "median":
        return float(np.median(values))
    with np.errstate(invalid="ignore", over="ignore"):
        return float(np.mean(values))


def compare_bayes(
    samples: Mapping[K, Mapping[str, ArrayLike]],
    algorithms: Sequence[str],
    reference: str | None = None,
    rope: Rope = DEFAULT_ROPE,
    stat: str = "mean",
    offsets: Mapping[K, float] | None = None,
    group: Callable[[K], Hashable] | None = None,
    lower_is_better: bool = True,
    seed: int = 0,
) -> BayesComparison:
    """Per cell of ``samples`` (cell -> algorithm -> runs) every algorithm against ``reference``
    (:func:`cell_posterior`), and per group of cells (``group(key)``; default: one group) the
    signed-rank test over the cells' statistics. ``offsets``: per cell the optimum of the
    relative rope (default 0)."""
    from swarmpath.evidence.stats import resolve_reference

    algos = tuple(algorithms)
    ref = resolve_reference(algos, reference) if algos else ""
    tests: list[BayesTest] = []
    diffs: dict[Hashable, dict[str, list[float]]] = {}
    for key, per_algo in samples.items():
        y = _clean(per_algo[ref]) if ref in per_algo else np.empty(0)
        offset = float((offsets or {}).get(key, 0.0))
        for a in algos:
            if a == ref or a not in per_algo:
                continue
            x = _clean(per_algo[a])
            post = cell_posterior(x, y, rope, stat, offset, lower_is_better, seed=seed)
            tests.append(BayesTest(key, a, x.size, y.size, post))
            if post is None:
                continue
            sa, sb = point_statistic(x, stat), point_statistic(y, stat)
            d = (relative_difference(np.array([sa]), np.array([sb]), offset)[0]
                 if rope.relative else sa - sb)
            g = group(key) if group is not None else ""
            diffs.setdefault(g, {}).setdefault(a, []).append(0.0 if math.isnan(d) else float(d))
    across: dict[Hashable, dict[str, dict[str, Any]]] = {}
    for g, per in diffs.items():
        for a, ds in per.items():
            post = signed_rank(ds, rope.width, lower_is_better, seed=seed)
            across.setdefault(g, {})[a] = {"blocks": len(ds), **post.to_json()}
    return BayesComparison(algos, ref, rope, stat, lower_is_better, tuple(tests), across)
