"""Statistical comparison of algorithms, as the field reports it: pure functions, no I/O.

Following Derrac, Garcia, Molina and Herrera, "A practical tutorial on the use of nonparametric
statistical tests as a methodology for comparing evolutionary and swarm intelligence algorithms",
Swarm and Evolutionary Computation 1 (2011) 3-18, and Demsar, JMLR 7 (2006) 1-30:

* **Per cell** (one function and dimension, or one map): each algorithm's runs against the
  reference algorithm's runs with the two-sided Wilcoxon rank-sum test (Mann-Whitney U,
  :func:`scipy.stats.mannwhitneyu`, its default ``method="auto"``: exact for small samples without
  ties, otherwise the normal approximation with tie and continuity correction). The p-values of
  every test of the table (cells x algorithms other than the reference) are adjusted together
  with Holm's step-down method; an adjusted p below ``alpha`` gives ``+`` (the algorithm is
  significantly better than the reference) or ``-`` (significantly worse), else ``=``. The
  direction comes from the U statistic itself: with lower values better, U < n m / 2 means the
  algorithm's runs tend to be lower. Success counts are compared with Fisher's exact test
  (:func:`scipy.stats.fisher_exact`, two-sided) the same way (higher rates better).
* **Per dimension** (or over maps): the Friedman test (:func:`scipy.stats.friedmanchisquare`) with
  the functions as blocks and each cell's average as its value, the algorithms' mean ranks (1 =
  best, ties share the average rank), and two post-hoc procedures: the Nemenyi critical difference
  ``q_alpha sqrt(k (k + 1) / (6 N))`` (``q_alpha`` from the studentized range distribution
  divided by sqrt 2, Demsar's Table 5) and Holm-adjusted z tests of every algorithm's mean rank
  against the reference's.

Edge cases, on purpose:

* NaN values are missing runs (a crashed run has no value) and are dropped before a test; an
  infinite value is a real, worst possible result and is ranked as such.
* A cell where either sample is empty is not tested: marker ``None``, left out of Holm's family
  and of the counts. Identical samples (every value equal, e.g. all zeros) give p = 1 and ``=``.
* With fewer than two algorithms there is nothing to test (no tests, empty counts). The Friedman
  test needs at least 3 algorithms and 2 complete blocks; otherwise its statistic and p are None
  and ``note`` says why (mean ranks are still given). Blocks where an algorithm has no finite or
  infinite value (missing cell, or NaN average) are left out of the Friedman test. When every
  block is a complete tie the statistic is 0 and p = 1.
* The reference defaults to the last algorithm listed (the papers list the proposed one last).
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike

# scipy.stats (about 1 s to import) is imported by the functions that test: a coordinator
# imports this module at its start, for summaries it computes only when asked.
from swarmpath.evidence.effect import Shift, a12_from_u, a12_magnitude, hodges_lehmann
from swarmpath.evidence.friedman import Friedman, cliques, friedman, nemenyi_cd
from swarmpath.evidence.markers import ALPHA, BETTER, MARKERS, SAME, WORSE, holm
from swarmpath.evidence.stats import resolve_reference

__all__ = [
    "ALPHA", "BETTER", "MARKERS", "SAME", "WORSE", "Comparison", "Friedman", "PairTest",
    "cliques", "compare_samples", "compare_success", "friedman", "holm", "nemenyi_cd",
    "rank_sum", "rank_sum_many", "resolve_reference",
]

#: A cell or block key: (function, dim), a map name, ...
K = TypeVar("K", bound=Hashable)


def _clean(values: ArrayLike) -> np.ndarray:
    x = np.asarray(values, dtype=float).ravel()
    return x[~np.isnan(x)]


def rank_sum(x: ArrayLike, reference: ArrayLike) -> tuple[float, float] | None:
    """Two-sided Wilcoxon rank-sum test of ``x`` against ``reference``: (U of x, p).

    U counts the pairs (x_i, ref_j) with x_i > ref_j, ties counting half (scipy's U1). NaN values
    are dropped; None when either sample is then empty. Identical samples give (n m / 2, 1.0)."""
    from scipy import stats
    a, b = _clean(x), _clean(reference)
    if a.size == 0 or b.size == 0:
        return None
    pooled = np.concatenate([a, b])
    if np.all(pooled == pooled[0]):
        return a.size * b.size / 2.0, 1.0
    res = stats.mannwhitneyu(a, b, alternative="two-sided")
    return float(res.statistic), float(res.pvalue)


#: Above this many values in both samples scipy's ``method="auto"`` is the normal approximation
#: whatever the ties, so tests of equal sizes can share one vectorized call with the same results.
_EXACT_MAX = 8


def rank_sum_many(
    pairs: Sequence[tuple[ArrayLike, ArrayLike]],
) -> list[tuple[float, float] | None]:
    """:func:`rank_sum` of every (x, reference) pair. Pairs whose samples both have more than 8
    values are tested together, one vectorized ``mannwhitneyu`` call per pair of sizes (the
    normal approximation either way, so the values are those of single calls); the others one
    by one."""
    from scipy import stats
    out: list[tuple[float, float] | None] = [None] * len(pairs)
    batches: dict[tuple[int, int], list[tuple[int, np.ndarray, np.ndarray]]] = {}
    for i, (x, ref) in enumerate(pairs):
        a, b = _clean(x), _clean(ref)
        if a.size > _EXACT_MAX and b.size > _EXACT_MAX and not np.all(
            np.concatenate([a, b]) == a[0]
        ):
            batches.setdefault((a.size, b.size), []).append((i, a, b))
        else:
            out[i] = rank_sum(a, b)
    for group in batches.values():
        res = stats.mannwhitneyu(np.stack([g[1] for g in group]), np.stack([g[2] for g in group]),
                                 alternative="two-sided", axis=1)
        for (i, _, _), u, p in zip(group, np.atleast_1d(res.statistic),
                                   np.atleast_1d(res.pvalue), strict=True):
            out[i] = (float(u), float(p))
    return out


@dataclass(frozen=True)
class PairTest:
    """One algorithm against the reference in one cell."""

    key: Hashable  # the cell: (function, dim), a map name, ...
    algorithm: str
    n: int  # values tested (NaN dropped)
    n_reference: int
    statistic: float | None  # Mann-Whitney U of the algorithm, or Fisher's odds ratio
    p: float | None  # two-sided, unadjusted
    p_holm: float | None = None
    marker: str | None = None  # "+", "=", "-"; None when not tested
    #: Vargha-Delaney A12: P(algorithm's run beats the reference's), ties half (effect.py)
    a12: float | None = None
    #: Hodges-Lehmann shift (algorithm - reference) with its 95 % interval; None for success
    shift: Shift | None = None


@dataclass(frozen=True)
class Comparison:
    """Every algorithm against the reference over a table of cells (one Holm family)."""

    test: str  # "wilcoxon rank-sum" or "fisher exact"
    algorithms: tuple[str, ...]
    reference: str
    alpha: float
    lower_is_better: bool
    tests: tuple[PairTest, ...]
    #: how the markers' error rate is held over the table (a race's: Bonferroni)
    correction: str = "holm"
    _index: dict[tuple[Hashable, str], PairTest] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_index", {(t.key, t.algorithm): t for t in self.tests})

    def get(self, key: Hashable, algorithm: str) -> PairTest | None:
        return self._index.get((key, algorithm))

    def marker(self, key: Hashable, algorithm: str) -> str | None:
        """``+``, ``=``, ``-``; None for the reference itself or an untested cell."""
        t = self._index.get((key, algorithm))
        return None if t is None else t.marker

    def counts(self) -> dict[str, dict[str, int]]:
        """Per algorithm other than the reference: how many cells are ``+``, ``=``, ``-``."""
        out = {a: dict.fromkeys(MARKERS, 0) for a in self.algorithms if a != self.reference}
        for t in self.tests:
            if t.marker is not None:
                out[t.algorithm][t.marker] += 1
        return out

    def to_json(self, key_fields: Sequence[str] = ("key",)) -> dict[str, Any]:
        """JSON-ready: the settings, the counts and one entry per test (tuple keys are spread
        over ``key_fields``)."""

        def key_dict(key: Hashable) -> dict[str, Any]:
            parts = key if isinstance(key, tuple) else (key,)
            return dict(zip(key_fields, parts, strict=True))

        return {
            "test": self.test, "reference": self.reference, "alpha": self.alpha,
            "correction": self.correction, "lower_is_better": self.lower_is_better,
            "counts": self.counts(),
            "tests": [
                {**key_dict(t.key), "algorithm": t.algorithm, "n": t.n,
                 "n_reference": t.n_reference, "statistic": _finite(t.statistic), "p": t.p,
                 "p_holm": t.p_holm, "marker": t.marker, **effect_json(t)}
                for t in self.tests
            ],
        }


def effect_json(t: PairTest) -> dict[str, Any]:
    """A test's effect sizes as JSON fields: a12, a12_magnitude and, for samples, the shift
    with its interval (shift, shift_low, shift_high)."""
    out: dict[str, Any] = {"a12": t.a12, "a12_magnitude": a12_magnitude(t.a12) or None}
    if t.shift is not None:
        out.update(shift=t.shift.estimate, shift_low=t.shift.low, shift_high=t.shift.high)
    return out


def _finite(v: float | None) -> float | None:
    return None if v is None or not math.isfinite(v) else v


def _adjust(
    raw: list[PairTest], alpha: float, direction: Mapping[int, int]
) -> tuple[PairTest, ...]:
    """Holm over the tested entries of ``raw``; ``direction[i]`` is +1 when entry i leans better."""
    tested = [i for i, t in enumerate(raw) if t.p is not None]
    adjusted = holm([float(raw[i].p or 0.0) for i in tested])
    out = list(raw)
    for i, q in zip(tested, adjusted, strict=True):
        q = float(q)
        marker = SAME if q >= alpha else (BETTER if direction[i] > 0 else WORSE)
        out[i] = replace(raw[i], p_holm=q, marker=marker)
    return tuple(out)


def compare_samples(
    samples: Mapping[K, Mapping[str, ArrayLike]],
    algorithms: Sequence[str],
    reference: str | None = None,
    alpha: float = ALPHA,
    lower_is_better: bool = True,
    effects: bool = True,
) -> Comparison:
    """Rank-sum tests of every algorithm against ``reference`` in every cell of ``samples``
    (cell key -> algorithm -> values of its runs), Holm-adjusted over the whole table; with
    ``effects`` each test carries A12 and the Hodges-Lehmann shift with its 1 - ``alpha``
    interval (:mod:`swarmpath.evidence.effect`)."""
    algos = tuple(algorithms)
    ref = resolve_reference(algos, reference) if algos else ""
    entries: list[tuple[K, str, np.ndarray, np.ndarray]] = []
    for key, per_algo in samples.items():
        ref_values = per_algo.get(ref)
        y = _clean(ref_values) if ref_values is not None else np.empty(0)
        for a in algos:
            if a != ref and a in per_algo:
                entries.append((key, a, _clean(per_algo[a]), y))
    raw: list[PairTest] = []
    direction: dict[int, int] = {}
    results = rank_sum_many([(x, y) for _, _, x, y in entries])
    for (cell, a, x, y), res in zip(entries, results, strict=True):
        if res is None:
            raw.append(PairTest(cell, a, x.size, y.size, None, None))
            continue
        u, p = res
        leans_lower = u < x.size * y.size / 2.0
        direction[len(raw)] = 1 if leans_lower == lower_is_better else -1
        a12 = a12_from_u(u, x.size, y.size, lower_is_better)
        shift = hodges_lehmann(x, y, alpha) if effects else None
        raw.append(PairTest(cell, a, x.size, y.size, u, p, a12=a12, shift=shift))
    return Comparison("wilcoxon rank-sum", algos, ref, alpha, lower_is_better,
                      _adjust(raw, alpha, direction))


def compare_success(
    counts: Mapping[K, Mapping[str, tuple[int, int]]],
    algorithms: Sequence[str],
    reference: str | None = None,
    alpha: float = ALPHA,
) -> Comparison:
    """Fisher's exact test (two-sided) of every algorithm's success rate against the reference's
    in every cell (cell key -> algorithm -> (successes, runs)), Holm-adjusted over the table.
    ``+`` = a significantly higher success rate than the reference."""
    from scipy import stats
    algos = tuple(algorithms)
    ref = resolve_reference(algos, reference) if algos else ""
    raw: list[PairTest] = []
    direction: dict[int, int] = {}
    for key, per_algo in counts.items():
        ref_counts = per_algo.get(ref)
        for a in algos:
            if a == ref or a not in per_algo:
                continue
            s, n = (int(v) for v in per_algo[a])
            rs, rn = (int(v) for v in ref_counts) if ref_counts is not None else (0, 0)
            if not (0 <= s <= n and 0 <= rs <= rn):
                raise ValueError(f"{key}: successes must be within [0, runs]")
            if n == 0 or rn == 0:
                raw.append(PairTest(key, a, n, rn, None, None))
                continue
            res = stats.fisher_exact([[s, n - s], [rs, rn - rs]], alternative="two-sided")
            direction[len(raw)] = 1 if s * rn > rs * n else -1
            pa, pr = s / n, rs / rn  # A12 of the success indicators, higher better
            a12 = pa * (1 - pr) + 0.5 * (pa * pr + (1 - pa) * (1 - pr))
            raw.append(PairTest(key, a, n, rn, float(res.statistic), float(res.pvalue),
                                a12=a12))
    return Comparison("fisher exact", algos, ref, alpha, False, _adjust(raw, alpha, direction))


def best_and_similar(
    samples: Mapping[K, Mapping[str, ArrayLike]],
    algorithms: Sequence[str],
    stat: str = "mean",
    alpha: float = ALPHA,
    lower_is_better: bool = True,
) -> tuple[dict[K, set[str]], dict[K, set[str]]]:
    """Per cell, the best algorithms by ``stat`` (mean or median; ties all best) and, second,
    those with every one whose runs do not differ significantly from the best one's: the
    rank-sum test against the first best, Holm-adjusted over every such test of the table (the
    same test and correction as the markers). What a paper prints in bold."""
    from swarmpath.evidence.bayes import point_statistic

    best: dict[K, set[str]] = {}
    pairs: list[tuple[K, str, np.ndarray, np.ndarray]] = []
    for key, per_algo in samples.items():
        present = {a: _clean(per_algo[a]) for a in algorithms if a in per_algo}
        present = {a: v for a, v in present.items() if v.size}
        if not present:
            continue
        sign = 1.0 if lower_is_better else -1.0
        loc = {a: sign * point_statistic(v, stat) for a, v in present.items()}
        low = min(v for v in loc.values() if not math.isnan(v)) if any(
            not math.isnan(v) for v in loc.values()) else math.nan
        winners = [a for a in present if loc[a] == low]
        best[key] = set(winners)
        if winners:
            pairs += [(key, a, present[a], present[winners[0]]) for a in present
                      if a not in winners]
    results = rank_sum_many([(x, y) for _, _, x, y in pairs])
    tested = [(key, a, res[1]) for (key, a, _, _), res in zip(pairs, results, strict=True)
              if res is not None]
    adjusted = holm([p for _, _, p in tested])
    similar = {key: set(names) for key, names in best.items()}
    for (key, a, _), q in zip(tested, adjusted, strict=True):
        if q >= alpha:
            similar[key].add(a)
    return best, similar
