"""swarmpath.evidence.bayes: the per-cell Bayesian bootstrap against cases worked by hand and
scipy's normal limit; the signed-rank test against baycomp's own values."""

from __future__ import annotations

import math

import baycomp
import numpy as np
import pytest
from scipy import stats

from swarmpath.evidence import bayes


def test_parse_rope() -> None:
    assert bayes.parse_rope("1%") == bayes.Rope(0.01, relative=True)
    assert bayes.parse_rope("1e-8") == bayes.Rope(1e-8)
    assert bayes.parse_rope(None) == bayes.DEFAULT_ROPE
    assert str(bayes.parse_rope("2.5%")) == "2.5%"
    for bad in ("x", "-1", "inf", "150%"):
        with pytest.raises(ValueError):
            bayes.parse_rope(bad)


def test_cell_posterior_two_runs_against_a_constant_by_hand() -> None:
    """x = {0, 1}: the Bayesian bootstrap mean is w ~ U(0, 1); against a reference whose runs
    all equal 0.5 with a rope of 0.1: P(better) = P(w < 0.4) = 0.4, P(equivalent) = 0.2."""
    post = bayes.cell_posterior([0.0, 1.0], [0.5, 0.5, 0.5], bayes.Rope(0.1), draws=200_000)
    assert post is not None
    assert post.p_better == pytest.approx(0.4, abs=0.004)
    assert post.p_equivalent == pytest.approx(0.2, abs=0.004)
    assert post.p_worse == pytest.approx(0.4, abs=0.004)
    assert post.verdict == bayes.UNDECIDED
    # the median of {0, 1} under Dirichlet(1, 1) weights is 0 when w0 >= 1/2: half the draws
    med = bayes.cell_posterior([0.0, 1.0], [0.5], bayes.Rope(0.1), "median", draws=200_000)
    assert med is not None and med.p_better == pytest.approx(0.5, abs=0.004)
    assert med.p_equivalent == 0.0


def test_cell_posterior_relative_rope_and_direction() -> None:
    # every weighting gives 100 against 101: 1 % of the larger distance to 0 -> equivalent
    same = bayes.cell_posterior([100.0] * 5, [101.0] * 5, bayes.Rope(0.01, relative=True))
    assert same is not None and same.verdict == bayes.EQUIVALENT
    # distances to the optimum -1000: 1100 against 1101 -> within 1 %
    shifted = bayes.cell_posterior([100.0], [101.0], bayes.Rope(0.001, True), offset=-1000.0)
    assert shifted is not None and shifted.verdict == bayes.EQUIVALENT
    apart = bayes.cell_posterior([1e-30] * 3, [1e-10] * 3, bayes.Rope(0.01, True))
    assert apart is not None and apart.verdict == bayes.BETTER
    up = bayes.cell_posterior([5.0] * 3, [1.0] * 3, bayes.Rope(0.1), lower_is_better=False)
    assert up is not None and up.p_better == 1.0
    inf = bayes.cell_posterior([math.inf, 1.0], [1.0, 2.0], bayes.Rope(0.1))
    assert inf is not None and inf.p_worse == 1.0
    assert bayes.cell_posterior([], [1.0]) is None


def test_cell_posterior_is_seeded_and_matches_the_normal_limit() -> None:
    """Var of the Bayesian bootstrap mean = sum (x - mean)^2 / (n (n + 1)); for 400 runs the
    posterior of the difference is close to normal (scipy's norm gives the probabilities)."""
    rng = np.random.default_rng(4)
    x, y = rng.normal(0.0, 1.0, 400), rng.normal(0.12, 1.0, 400)
    rope = 0.05
    post = bayes.cell_posterior(x, y, bayes.Rope(rope), draws=40_000, seed=3)
    again = bayes.cell_posterior(x, y, bayes.Rope(rope), draws=40_000, seed=3)
    assert post == again
    var = sum(float(np.sum((v - v.mean()) ** 2)) / (v.size * (v.size + 1)) for v in (x, y))
    dist = stats.norm(x.mean() - y.mean(), math.sqrt(var))
    assert post is not None
    assert post.p_better == pytest.approx(dist.cdf(-rope), abs=0.01)
    assert post.p_worse == pytest.approx(dist.sf(rope), abs=0.01)


@pytest.mark.parametrize("n", [1, 3, 13])
@pytest.mark.parametrize("rope", [0.0, 0.1, 0.5])
def test_signed_rank_equals_baycomp(n: int, rope: float) -> None:
    """Same draws, same counting: baycomp's SignedRankTest on x = differences, y = 0 (its
    'left' is x higher, i.e. worse with lower values better)."""
    d = np.random.default_rng(n).normal(size=n) * 0.5
    mine = bayes.signed_rank(d, rope, draws=4000, seed=11)
    theirs = baycomp.SignedRankTest.probs(d, np.zeros(n), rope, nsamples=4000, random_state=11)
    if rope > 0:
        assert (mine.p_worse, mine.p_equivalent, mine.p_better) == pytest.approx(theirs,
                                                                                abs=1e-12)
    else:
        assert (mine.p_worse, mine.p_better) == pytest.approx(theirs, abs=1e-12)
        assert mine.p_equivalent == 0.0


def test_signed_rank_one_block_by_hand() -> None:
    """One difference d < -2 rope: the draw's P(below) = 1 - w0^2 with w0 ~ Beta(0.5, 1), so
    'better' wins when w0^2 < 1/2: probability (1/2)^(1/4) = 0.8409."""
    post = bayes.signed_rank([-1.0], 0.1, draws=200_000, seed=1)
    assert post.p_better == pytest.approx(0.5 ** 0.25, abs=0.003)
    assert post.p_worse == 0.0


def test_compare_bayes_table() -> None:
    rng = np.random.default_rng(0)
    samples = {(f"F{i}", 10): {"A": rng.normal(0, 1, 20), "B": rng.normal(3, 1, 20),
                               "C": rng.normal(1.5, 1, 20)} for i in range(1, 6)}
    out = bayes.compare_bayes(samples, ["A", "B", "C"], rope=bayes.Rope(0.2),
                              group=lambda key: key[1])
    assert out.reference == "C"
    assert all(out.get(k, "A").verdict == bayes.BETTER for k in samples)  # type: ignore[union-attr]
    assert all(out.get(k, "B").verdict == bayes.WORSE for k in samples)  # type: ignore[union-attr]
    assert out.verdict_counts()["A"]["better"] == 5
    across = out.across[10]
    assert across["A"]["blocks"] == 5 and across["A"]["p_better"] > 0.9
    assert across["B"]["p_worse"] > 0.9
    doc = out.to_json(("function", "dim"), "dim")
    assert doc["rope"] == "0.2" and doc["stat"] == "mean"
    assert {t["algorithm"] for t in doc["tests"]} == {"A", "B"}
    assert doc["across"][0]["dim"] == 10


def test_median_is_drawn_exactly_from_its_beta_form() -> None:
    """The weighted median under Dirichlet(1, ..., 1) weights, drawn from P(S_k >= 1/2) with
    S_k ~ Beta(k, n - k), has the distribution of the brute-force one (weights drawn, cumulated,
    the first value reaching 1/2)."""
    rng = np.random.default_rng(5)
    a = rng.lognormal(size=7)
    ref = np.full(3, float(np.median(a)))
    fast = bayes.cell_posterior(a, ref, bayes.Rope(0.05), "median", draws=200_000)
    w = rng.standard_exponential((200_000, 7))
    cum = np.cumsum(w / w.sum(axis=1, keepdims=True), axis=1)
    d = np.sort(a)[(cum < 0.5).sum(axis=1)] - ref[0]
    assert fast is not None
    assert fast.p_better == pytest.approx(np.mean(d < -0.05), abs=0.005)
    assert fast.p_equivalent == pytest.approx(np.mean(np.abs(d) <= 0.05), abs=0.005)


def test_large_mean_cells_use_fewer_draws_but_the_same_model() -> None:
    rng = np.random.default_rng(6)
    x, y = rng.normal(0.0, 1.0, 3000), rng.normal(0.05, 1.0, 3000)
    post = bayes.cell_posterior(x, y, bayes.Rope(0.02), draws=10_000)  # 2^22 / 3000 = 1398
    var = sum(float(np.sum((v - v.mean()) ** 2)) / (v.size * (v.size + 1)) for v in (x, y))
    dist = stats.norm(x.mean() - y.mean(), math.sqrt(var))
    assert post is not None
    assert post.p_better == pytest.approx(dist.cdf(-0.02), abs=0.03)
    assert (post.p_better * bayes.MIN_DRAWS) == pytest.approx(round(post.p_better
                                                                    * bayes.MIN_DRAWS))
