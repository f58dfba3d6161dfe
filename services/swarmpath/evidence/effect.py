"""Effect sizes of one algorithm's runs against another's: pure numpy/scipy, no I/O.

A marker says *whether* two samples differ; these say *by how much*:

* **Vargha-Delaney A12** (Vargha and Delaney, J. Educ. Behav. Stat. 25 (2000) 101-132): the
  probability that a run of the algorithm beats a run of the reference, ties counting half. With
  lower values better, A12 = P(X < Y) + 0.5 P(X = Y) (X: the algorithm, Y: the reference); 0.5
  is no effect, 1 means every run beats every reference run. It is the Mann-Whitney U of the
  rank-sum test divided by n m (:func:`a12_from_u`), so it always agrees with the marker's
  direction. Vargha and Delaney's thresholds on |A12 - 0.5|: 0.06 small, 0.14 medium, 0.21 large
  (:func:`a12_magnitude`).
* **Hodges-Lehmann shift** (Hodges and Lehmann, Ann. Math. Stat. 34 (1963) 598-611): the median
  of the n m differences x_i - y_j, in the function's units (negative: the algorithm's runs are
  lower). Its confidence interval is the rank-sum test inverted (Lehmann, "Nonparametrics", 1975,
  section 2.6; Bauer, JASA 67 (1972) 687-690): the shifts d for which the two-sided test of
  x - d against y does not reject, whose ends are order statistics of the differences,
  ``[D_(k), D_(nm + 1 - k)]``. The critical k comes from the same null distribution scipy's
  ``mannwhitneyu(method="auto")`` uses for the test: exact when a sample has at most 8 values and
  there are no ties, else the normal approximation with continuity and tie correction. When even
  the most extreme difference cannot reject (k < 1, e.g. 2 runs against 2) the interval is
  unbounded.

Missing runs (NaN) are dropped; an infinite value is a real, worst result (an infinite difference;
inf - inf counts as 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

# scipy.stats (about 1 s to import) is imported by the functions that test: a coordinator
# imports this module at its start, for summaries it computes only when asked.

__all__ = ["Shift", "a12", "a12_from_u", "a12_magnitude", "hodges_lehmann", "u_null_cdf"]

#: Vargha and Delaney's (2000) thresholds on |A12 - 0.5|: small, medium, large.
A12_THRESHOLDS = (0.06, 0.14, 0.21)
#: Above this many pairwise differences the shift's order statistics are found by bisection on
#: the value (memory stays O(n + m)) instead of from the differences themselves.
_DIRECT_PAIRS = 1 << 22


def _clean(values: ArrayLike) -> np.ndarray:
    x = np.asarray(values, dtype=float).ravel()
    return x[~np.isnan(x)]


def a12_from_u(u: float, n: int, m: int, lower_is_better: bool = True) -> float:
    """A12 from the Mann-Whitney U of the algorithm (pairs with x > y, ties half: scipy's U1)."""
    share_above = u / (n * m)
    return 1.0 - share_above if lower_is_better else share_above


def a12(x: ArrayLike, reference: ArrayLike, lower_is_better: bool = True) -> float | None:
    """Vargha-Delaney A12 of ``x`` against ``reference`` (None when a sample is empty)."""
    from scipy import stats
    a, b = _clean(x), _clean(reference)
    if a.size == 0 or b.size == 0:
        return None
    ranks = stats.rankdata(np.concatenate([a, b]))  # average ranks of ties; inf ranks last
    u = float(ranks[: a.size].sum()) - a.size * (a.size + 1) / 2.0
    return a12_from_u(u, a.size, b.size, lower_is_better)


def a12_magnitude(value: float | None) -> str:
    """negligible / small / medium / large, by Vargha and Delaney's thresholds."""
    if value is None or math.isnan(value):
        return ""
    d = abs(value - 0.5)
    small, medium, large = A12_THRESHOLDS
    return ("large" if d >= large else "medium" if d >= medium else "small" if d >= small
            else "negligible")


@dataclass(frozen=True)
class Shift:
    """The Hodges-Lehmann shift of x against y with its confidence interval."""

    estimate: float
    low: float
    high: float
    confidence: float

    def contains(self, value: float) -> bool:
        return self.low <= value <= self.high


def u_null_cdf(n: int, m: int) -> np.ndarray:
    """P(U <= u) for u = 0 .. n m under the null hypothesis without ties (exact).

    The counts of U are the coefficients of the Gaussian binomial coefficient
    prod_{i=1..s} (1 - q^(l+i)) / (1 - q^i) (s, l: the smaller and larger size); each factor is
    a shifted subtraction, each division a strided cumulative sum."""
    s, big = min(n, m), max(n, m)
    counts = np.zeros(n * m + 1)
    counts[0] = 1.0
    for i in range(1, s + 1):
        shift = big + i
        if shift < counts.size:
            counts[shift:] -= counts[:-shift].copy()
        for r in range(i):
            counts[r::i] = np.cumsum(counts[r::i])
    cdf = np.cumsum(counts)
    return cdf / cdf[-1]


def _critical_k(a: np.ndarray, b: np.ndarray, alpha: float) -> int:
    """The largest k with P(U <= k - 1) <= alpha / 2 (scipy's choice of exact or normal)."""
    from scipy import stats
    n, m = a.size, b.size
    pooled = np.concatenate([a, b])
    _, tie_counts = np.unique(pooled, return_counts=True)
    ties = bool(np.any(tie_counts > 1))
    if (n > 8 and m > 8) or ties:
        total = n + m
        tie_term = float(np.sum(tie_counts.astype(float) ** 3 - tie_counts)) / (
            total * (total - 1))
        sigma = math.sqrt(n * m / 12.0 * ((total + 1) - tie_term))
        z = float(stats.norm.isf(alpha / 2.0))
        # p of U = u <= n m / 2 with continuity correction: 2 Phi(-(n m / 2 - u - 0.5) / sigma)
        return math.floor(n * m / 2.0 + 0.5 - z * sigma)
    cdf = u_null_cdf(n, m)
    below = np.flatnonzero(cdf <= alpha / 2.0 * (1 + 1e-12))  # P(U <= k - 1), k - 1 = index
    return int(below[-1]) + 1 if below.size else 0


def _differences(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore"):
        d = np.subtract.outer(a, b).ravel()
    d[np.isnan(d)] = 0.0  # inf - inf: two equally bad runs
    return d


def _order_statistics(a: np.ndarray, b: np.ndarray, ks: list[int]) -> list[float]:
    """The k-th smallest (1-based) of the differences a_i - b_j, for each k."""
    total = a.size * b.size
    if total <= _DIRECT_PAIRS or not (np.isfinite(a).all() and np.isfinite(b).all()):
        d = _differences(a, b)
        idx = sorted({k - 1 for k in ks})
        part = np.partition(d, idx)
        return [float(part[k - 1]) for k in ks]
    ys = np.sort(b)

    def count(t: float) -> int:  # how many a_i - b_j <= t, i.e. b_j >= a_i - t
        return int(total - np.searchsorted(ys, a - t, side="left").sum())

    out = []
    lo0, hi0 = float(a.min() - b.max()), float(a.max() - b.min())
    for k in ks:
        lo, hi = lo0, hi0  # count(hi) >= k; bisect down to adjacent floats
        if count(lo) >= k:
            out.append(lo)
            continue
        for _ in range(2000):
            mid = lo + (hi - lo) / 2.0
            if mid <= lo or mid >= hi:
                break
            if count(mid) >= k:
                hi = mid
            else:
                lo = mid
        out.append(hi)
    return out


def hodges_lehmann(x: ArrayLike, reference: ArrayLike, alpha: float = 0.05) -> Shift | None:
    """The Hodges-Lehmann shift of ``x`` against ``reference`` (median of x_i - y_j) and its
    1 - ``alpha`` confidence interval (see the module doc); None when a sample is empty."""
    a, b = _clean(x), _clean(reference)
    if a.size == 0 or b.size == 0:
        return None
    total = a.size * b.size
    k = _critical_k(a, b, alpha)
    middle = [(total + 1) // 2, total // 2 + 1]  # the one or two middle order statistics
    ends = [k, total + 1 - k] if 1 <= k <= total // 2 else []
    values = _order_statistics(a, b, middle + ends)
    lo_mid, hi_mid = values[0], values[1]
    if lo_mid == hi_mid:
        estimate = lo_mid
    elif math.isfinite(lo_mid) and math.isfinite(hi_mid):
        estimate = lo_mid / 2.0 + hi_mid / 2.0
    else:  # an infinite middle: inf, or NaN between -inf and inf
        estimate = lo_mid + hi_mid
    low, high = (values[2], values[3]) if ends else (-math.inf, math.inf)
    return Shift(float(estimate), float(low), float(high), 1.0 - alpha)
