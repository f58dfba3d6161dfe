"""Is a measured cell the published one? The statistics behind ``swarmpath reproduce``'s verdicts.

Pure functions over one cell: the measured runs and the published summary (mean, and where
printed the min and max of the paper's runs and their number), both on the scale the cell is
compared on (benchmark cells: the gap to the optimum raised to the function's floating-point
floor; map cells: the path length). Table-agnostic: any reproduction (the seed papers' tables,
a baseline's published table) judges its cells with :func:`judge`.

**Consistency** (:func:`bootstrap_interval`): the 95 % bootstrap interval of the measured mean
(BCa, ``scipy.stats.bootstrap``, :data:`RESAMPLES` resamples) contains the published mean. The
resampling generator is seeded from the cell's key (:func:`bootstrap_seed`), so the same runs
give the same interval in every process, order and machine.

**Exceedance** (:func:`exceedance`): how many measured runs lie above the published maximum and
below the published minimum, and how likely that many are if the paper's runs and ours come from
one distribution. Derivation: let the paper's n runs and our m runs be exchangeable draws of one
continuous distribution; then every ordering of the pooled N = n + m values is equally likely.
K, the number of our runs above the paper's maximum, is at least k exactly when the k largest
pooled values are all ours, so

    P(K >= k) = C(m, k) / C(N, k) = prod_{i < k} (m - i) / (N - i)

(k = 1, m = 1: 1 / (n + 1), the chance that one new run beats the best of n). The same holds
below the minimum. Ties (two runs at the floor) only make strict exceedances rarer, so the
probability stays an upper bound (the test stays valid, conservatively). The two sides are
tested together, Bonferroni over the sides printed (p = 2 min(p_above, p_below) when both
are): the measurement *departs from the paper's range* when p < :data:`ALPHA`. For n = 1000 and
m = 30 one run beyond an extreme gives p = 0.058 (no departure), two give 1.6e-3.

**Verdict** (:func:`verdict_of`): ``consistent`` when the interval contains the published mean
and the runs do not depart from the published range; else ``matches`` when the log10 ratio of
the means is within the cell's tolerance; else ``better`` (smaller) or ``worse``.
``not comparable`` is decided by the caller (an illegible or self-contradicting print, other
units).
"""

from __future__ import annotations

import inspect
import math
import warnings
import zlib
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

CONSISTENT, MATCHES, BETTER, WORSE, NOT_COMPARABLE = (
    "consistent", "matches", "better", "worse", "not comparable")
VERDICTS = (CONSISTENT, MATCHES, BETTER, WORSE, NOT_COMPARABLE)
#: Verdicts that need a reason (a difference beyond the tolerance).
DIFFERENT = (BETTER, WORSE)
CONFIDENCE = 0.95
RESAMPLES = 9999
ALPHA = 0.05
#: Mixed with the cell key into the bootstrap's seed (a fixed constant: changing it changes the
#: intervals, so it is part of the method).
BOOTSTRAP_ENTROPY = 20210521


def bootstrap_seed(key: str) -> np.random.SeedSequence:
    """The bootstrap's seed for cell ``key``: independent of the study seed, the order of the
    cells and the process."""
    return np.random.SeedSequence([BOOTSTRAP_ENTROPY, zlib.crc32(key.encode("utf-8"))])


def bootstrap_interval(
    values: Sequence[float], key: str, confidence: float = CONFIDENCE,
    resamples: int = RESAMPLES,
) -> tuple[float, float] | None:
    """The ``confidence`` BCa bootstrap interval of the mean of ``values`` (None when a value is
    not finite; [v, v] when every value is v). Falls back to the percentile interval where BCa is
    undefined (a jackknife without spread)."""
    from scipy import stats

    x = np.asarray(values, dtype=float)
    if x.size == 0 or not np.isfinite(x).all():
        return None
    if np.all(x == x[0]):
        return float(x[0]), float(x[0])
    seed_name = "rng" if "rng" in inspect.signature(stats.bootstrap).parameters else "random_state"
    scale = float(np.max(np.abs(x)))  # tiny gaps (1e-300) resample without underflow
    for method in ("BCa", "percentile"):
        seeded: dict[str, Any] = {seed_name: np.random.default_rng(bootstrap_seed(key))}
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore")  # BCa without spread: NaN, then the percentile
            res = stats.bootstrap((x / scale,), np.mean, confidence_level=confidence,
                                  n_resamples=resamples, method=method, vectorized=True,
                                  **seeded)
        lo, hi = float(res.confidence_interval.low), float(res.confidence_interval.high)
        if math.isfinite(lo) and math.isfinite(hi):
            return lo * scale, hi * scale
    return None


def exceedance_probability(k: int, m: int, n: int) -> float:
    """P(K >= k): at least ``k`` of ``m`` new runs beyond the extreme of ``n`` earlier runs of
    the same distribution (exchangeable, continuous): C(m, k) / C(n + m, k)."""
    if not 0 <= k <= m or n < 0:
        raise ValueError(f"need 0 <= k <= m and n >= 0, got k={k}, m={m}, n={n}")
    log_p = sum(math.log(m - i) - math.log(n + m - i) for i in range(k))
    return math.exp(log_p)


@dataclass(frozen=True)
class Exceedance:
    """Measured runs beyond the published extremes of ``n_paper`` runs (None: not printed)."""

    n_paper: int
    runs: int
    above: int | None
    below: int | None

    @property
    def p_above(self) -> float | None:
        return None if self.above is None else exceedance_probability(self.above, self.runs,
                                                                       self.n_paper)

    @property
    def p_below(self) -> float | None:
        return None if self.below is None else exceedance_probability(self.below, self.runs,
                                                                       self.n_paper)

    @property
    def p(self) -> float:
        """Both sides together (Bonferroni over the sides printed)."""
        sides = [p for p in (self.p_above, self.p_below) if p is not None]
        return min(1.0, len(sides) * min(sides)) if sides else 1.0

    def departs(self, alpha: float = ALPHA) -> bool:
        """Too many runs beyond the published range for one distribution."""
        return self.p < alpha

    def side_departs(self, side: str, alpha: float = ALPHA) -> bool:
        """``above`` or ``below`` alone departs (Bonferroni factor of the sides printed)."""
        p = self.p_above if side == "above" else self.p_below
        sides = sum(q is not None for q in (self.p_above, self.p_below))
        return p is not None and sides * p < alpha

    def to_json(self) -> dict[str, Any]:
        return {"paper_runs": self.n_paper, "above_max": self.above, "below_min": self.below,
                "p_above": self.p_above, "p_below": self.p_below, "p": self.p,
                "departs": self.departs()}


def exceedance(values: Sequence[float], low: float | None, high: float | None,
               n_paper: int) -> Exceedance:
    """Count the runs strictly above ``high`` and strictly below ``low`` (same scale)."""
    x = [float(v) for v in values]
    return Exceedance(
        n_paper=int(n_paper), runs=len(x),
        above=None if high is None else sum(v > high for v in x),
        below=None if low is None else sum(v < low for v in x),
    )


Band = tuple[float, float]


def verdict_of(ratio: float | None, tolerance: Band, consistent: bool = False) -> str:
    """``consistent`` first, then ``matches`` when ``ratio`` (log10 measured / published) lies
    in the ``tolerance`` band (low <= 0 <= high, decades), else the sign."""
    if ratio is None or math.isnan(ratio):
        return NOT_COMPARABLE
    if consistent:
        return CONSISTENT
    if tolerance[0] <= ratio <= tolerance[1]:
        return MATCHES
    return BETTER if ratio < 0 else WORSE


@dataclass(frozen=True)
class Judgement:
    """One comparable cell judged: log10 ratio of the means, the measured mean's bootstrap
    interval, the exceedance counts and the verdict."""

    ratio: float
    interval: tuple[float, float] | None
    exceedance: Exceedance | None
    verdict: str

    @property
    def consistent(self) -> bool:
        return self.verdict == CONSISTENT


def judge(
    values: Sequence[float],
    published: float,
    key: str,
    ratio: float,
    tolerance: Band,
    low: float | None = None,
    high: float | None = None,
    n_paper: int | None = None,
    floor: float = 0.0,
) -> Judgement:
    """Judge the measured ``values`` against the ``published`` mean (same scale; ``ratio`` is
    log10 measured mean / published mean as the caller computes it). ``low``/``high``: the
    published min/max of ``n_paper`` runs, when printed. Everything below ``floor`` counts as
    the floor (the interval's ends, the runs and the published extremes)."""
    raised = [max(v, floor) for v in values]
    interval = bootstrap_interval(values, key)
    if interval is not None:
        interval = (max(interval[0], floor), max(interval[1], floor))
    exc = None
    if n_paper and (low is not None or high is not None):
        exc = exceedance(raised, None if low is None else max(low, floor),
                         None if high is None else max(high, floor), n_paper)
    inside = interval is not None and interval[0] <= max(published, floor) <= interval[1]
    consistent = inside and not (exc is not None and exc.departs())
    return Judgement(ratio, interval, exc, verdict_of(ratio, tolerance, consistent))
