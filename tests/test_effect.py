"""swarmpath.evidence.effect: A12 and the Hodges-Lehmann shift against cases worked by hand and
against scipy's own rank-sum test (the interval is that test inverted)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats
from scipy.stats._mannwhitneyu import _MWU

from swarmpath.evidence import compare, effect


def test_a12_by_hand() -> None:
    # x = {1, 3}, y = {2, 3}: pairs (1<2) (1<3) (3>2) (3=3): P(x<y) + 0.5 P(x=y) = 2/4 + 0.5/4
    assert effect.a12([1, 3], [2, 3]) == pytest.approx(0.625)
    assert effect.a12([1, 3], [2, 3], lower_is_better=False) == pytest.approx(0.375)
    assert effect.a12([0, 0], [0, 0]) == 0.5
    assert effect.a12([1, 2], [5, 6]) == 1.0  # every run beats every reference run
    assert effect.a12([math.inf], [1.0]) == 0.0  # a run without a finite value is the worst
    assert effect.a12([math.nan], [1.0]) is None
    assert effect.a12_magnitude(0.5) == "negligible"
    assert effect.a12_magnitude(0.57) == "small"
    assert effect.a12_magnitude(0.30) == "medium"
    assert effect.a12_magnitude(0.05) == "large"


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a12_is_scipy_u_over_nm_and_counts_pairs(seed: int) -> None:
    rng = np.random.default_rng(seed)
    x = rng.integers(0, 5, size=17).astype(float)
    y = rng.integers(1, 6, size=12).astype(float)
    counted = np.mean(x[:, None] < y[None, :]) + 0.5 * np.mean(x[:, None] == y[None, :])
    u = stats.mannwhitneyu(x, y).statistic
    assert effect.a12(x, y) == pytest.approx(counted)
    assert effect.a12(x, y) == pytest.approx(1 - u / (x.size * y.size))


@pytest.mark.parametrize(("n", "m"), [(3, 4), (5, 8), (2, 30), (8, 8), (8, 300)])
def test_exact_null_distribution_equals_scipy(n: int, m: int) -> None:
    mwu = _MWU(n, m)
    k = np.arange(n * m + 1)
    np.testing.assert_allclose(effect.u_null_cdf(n, m), mwu.cdf(k), rtol=0, atol=1e-12)


def test_shift_by_hand() -> None:
    # differences of {1, 4} - {0, 2}: 1, -1, 4, 2 -> sorted -1, 1, 2, 4: median 1.5. With 2 runs
    # against 2 the exact test never rejects (min p = 1/3): the interval is unbounded.
    s = effect.hodges_lehmann([1, 4], [0, 2])
    assert s is not None and s.estimate == 1.5
    assert (s.low, s.high) == (-math.inf, math.inf)
    # 5 against 5 without ties: P(U <= 2) = 4/252 <= 0.025 < P(U <= 3) = 7/252, so k = 3:
    # the interval is the 3rd smallest and 3rd largest of the 25 differences
    x, y = np.array([10.0, 11, 12, 13, 14]), np.array([0.0, 1, 2, 3, 4])
    s = effect.hodges_lehmann(x, y)
    d = np.sort(np.subtract.outer(x, y).ravel())
    assert s is not None and s.estimate == 10.0
    assert (s.low, s.high) == (d[2], d[-3]) == (7.0, 13.0)
    assert effect.hodges_lehmann([], [1.0]) is None


@pytest.mark.parametrize(("n", "m", "seed"), [(5, 6, 0), (7, 8, 1), (3, 40, 2), (20, 25, 3),
                                              (30, 30, 4), (60, 45, 5)])
def test_shift_interval_is_the_inverted_scipy_test(n: int, m: int, seed: int) -> None:
    """Inside the interval scipy's two-sided test of (x - d, y) does not reject at 0.05, just
    outside it does; the estimate is the median of the pairwise differences."""
    rng = np.random.default_rng(seed)
    x, y = rng.normal(size=n), rng.normal(size=m) + 0.6
    s = effect.hodges_lehmann(x, y)
    assert s is not None
    assert s.estimate == pytest.approx(np.median(np.subtract.outer(x, y)))
    eps = 1e-9

    def p(d: float) -> float:
        return float(stats.mannwhitneyu(x - d, y, alternative="two-sided").pvalue)

    assert p(s.low + eps) > 0.05 and p(s.high - eps) > 0.05
    assert p(s.low - eps) <= 0.05 and p(s.high + eps) <= 0.05


def test_large_samples_bisect_to_the_same_shift(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(9)
    x, y = rng.lognormal(size=300), rng.lognormal(size=250) * 1.3
    direct = effect.hodges_lehmann(x, y)
    monkeypatch.setattr(effect, "_DIRECT_PAIRS", 10)
    bisected = effect.hodges_lehmann(x, y)
    assert direct is not None and bisected is not None
    for a, b in ((direct.estimate, bisected.estimate), (direct.low, bisected.low),
                 (direct.high, bisected.high)):
        assert b == pytest.approx(a, rel=1e-12, abs=1e-15)


def test_comparison_carries_the_effect_sizes() -> None:
    samples = {("F1", 2): {"A": [1.0, 2.0, 3.0, 4.0, 5.0], "B": [3.0, 4.0, 5.0, 6.0, 7.0]}}
    c = compare.compare_samples(samples, ["A", "B"])
    t = c.get(("F1", 2), "A")
    assert t is not None and t.a12 == pytest.approx(effect.a12(samples[("F1", 2)]["A"],
                                                               samples[("F1", 2)]["B"]))
    assert t.shift is not None and t.shift.estimate == -2.0
    doc = c.to_json(("function", "dim"))["tests"][0]
    assert doc["a12"] == t.a12 and doc["shift"] == -2.0
    assert doc["shift_low"] == t.shift.low and doc["a12_magnitude"] == "large"
    # success rates: A12 of the success indicators (higher better): 8/10 against 4/10
    s = compare.compare_success({"m": {"A": (8, 10), "B": (4, 10)}}, ["A", "B"])
    assert s.get("m", "A").a12 == pytest.approx(0.8 * 0.6 + 0.5 * (0.8 * 0.4 + 0.2 * 0.6))  # type: ignore[union-attr]
