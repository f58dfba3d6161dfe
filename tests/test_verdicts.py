"""The statistics behind reproduction verdicts (swarmpath.evidence.verdicts): the exceedance
test against an exhaustive count and scipy's hypergeometric law, the seeded bootstrap interval,
and verdicts on hand-worked cells."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy import stats

from swarmpath.evidence import verdicts as v
from swarmpath.evidence.verdicts import (
    BETTER,
    CONSISTENT,
    MATCHES,
    NOT_COMPARABLE,
    WORSE,
)


@pytest.mark.parametrize(("n", "m"), [(3, 2), (4, 3), (2, 4), (5, 1)])
def test_exceedance_probability_counts_every_ordering(n, m):
    """All orderings of n paper runs (P) and m new runs (N) are equally likely; K = new runs
    above every paper run. Count them exhaustively."""
    orderings = set(itertools.permutations("P" * n + "N" * m))
    for k in range(m + 1):
        # an ordering read from the largest value down: K >= k when its first k are all new
        hits = sum(all(c == "N" for c in o[:k]) for o in orderings)
        assert v.exceedance_probability(k, m, n) == pytest.approx(hits / len(orderings))


@pytest.mark.parametrize(("k", "m", "n"), [(1, 1, 1000), (1, 30, 1000), (2, 30, 1000),
                                            (13, 30, 1000), (6, 30, 1000), (3, 10, 10)])
def test_exceedance_probability_is_the_hypergeometric_all_new_draw(k, m, n):
    """P(K >= k) = P(the k largest of N = n + m are all new) = hypergeom(N, m, k).pmf(k)."""
    expected = stats.hypergeom(n + m, m, k).pmf(k)
    assert v.exceedance_probability(k, m, n) == pytest.approx(expected, rel=1e-9)


def test_exceedance_hand_worked():
    assert v.exceedance_probability(1, 1, 1000) == pytest.approx(1 / 1001)  # beat the best
    assert v.exceedance_probability(0, 30, 1000) == 1.0
    # the audit's numbers: ICOOT F12 6 of 30 above the max of 1000; ICOOT F5 13 of 30
    assert v.exceedance_probability(6, 30, 1000) == pytest.approx(3.6e-10, rel=0.05)
    assert v.exceedance_probability(13, 30, 1000) == pytest.approx(5.5e-22, rel=0.05)
    with pytest.raises(ValueError):
        v.exceedance_probability(31, 30, 1000)


def test_one_run_beyond_a_published_extreme_is_no_departure_two_are():
    one = v.exceedance([0.5] * 29 + [2.0], low=0.1, high=1.0, n_paper=1000)
    assert (one.above, one.below) == (1, 0)
    assert one.p == pytest.approx(2 * 30 / 1030) and not one.departs()  # 0.058
    two = v.exceedance([0.5] * 28 + [2.0, 0.01], low=0.1, high=1.0, n_paper=1000)
    assert two.p == pytest.approx(2 * 30 / 1030) and not two.departs()  # one each side
    above = v.exceedance([0.5] * 28 + [2.0, 3.0], low=0.1, high=1.0, n_paper=1000)
    assert above.departs() and above.side_departs("above") and not above.side_departs("below")
    # one side not printed: no Bonferroni factor for it, and nothing counted there
    half = v.exceedance([2.0] + [0.5] * 29, low=None, high=1.0, n_paper=1000)
    assert half.below is None and half.p == pytest.approx(30 / 1030)
    # ties at the extreme are not beyond it
    assert v.exceedance([1.0, 1.0], low=1.0, high=1.0, n_paper=10).p == 1.0


def test_bootstrap_interval_is_seeded_by_the_cell_and_covers_the_mean():
    rng = np.random.default_rng(5)
    x = list(rng.lognormal(0.0, 2.0, 30))
    a = v.bootstrap_interval(x, "t/A/F1/30")
    assert a == v.bootstrap_interval(list(x), "t/A/F1/30")  # same key, same interval
    assert a != v.bootstrap_interval(x, "t/A/F2/30")  # another cell resamples differently
    assert a is not None and a[0] < float(np.mean(x)) < a[1]
    # the BCa interval of scipy with the same generator (the library's own value)
    ref = stats.bootstrap((np.asarray(x),), np.mean, n_resamples=v.RESAMPLES,
                          rng=np.random.default_rng(v.bootstrap_seed("t/A/F1/30")))
    assert a == pytest.approx((ref.confidence_interval.low, ref.confidence_interval.high),
                              rel=1e-9)
    assert v.bootstrap_interval([3.0] * 5, "k") == (3.0, 3.0)
    assert v.bootstrap_interval([1.0, math.inf], "k") is None
    # gaps near the smallest floats resample without underflow
    tiny = v.bootstrap_interval([1e-310, 3e-310, 2e-310, 5e-310], "k")
    assert tiny is not None and 0 < tiny[0] <= tiny[1] <= 5e-310


@pytest.mark.parametrize(("ratio", "consistent", "verdict"), [
    (None, False, NOT_COMPARABLE), (math.nan, True, NOT_COMPARABLE),
    (3.0, True, CONSISTENT), (0.9, False, MATCHES), (-0.05, False, MATCHES),
    (-0.2, False, BETTER), (1.2, False, WORSE), (math.inf, False, WORSE),
])
def test_verdict_order_consistent_then_band_then_sign(ratio, consistent, verdict):
    band = (-0.1, 1.0)  # asymmetric on purpose: the band is what decides
    assert v.verdict_of(ratio, band, consistent) == verdict


def test_judge_needs_both_the_interval_and_the_range():
    runs = [0.9, 1.1, 1.0, 1.2, 0.8, 1.0]
    inside = v.judge(runs, 1.0, "k", 0.0, (-1, 1), low=0.5, high=2.0, n_paper=1000)
    assert inside.verdict == CONSISTENT and inside.interval[0] < 1.0 < inside.interval[1]
    # same runs, the published mean outside their interval: within a decade only
    assert v.judge(runs, 1.5, "k", -0.17, (-1, 1), low=0.5, high=2.0,
                   n_paper=1000).verdict == MATCHES
    # the interval contains it, but three runs lie above the published max of 1000 runs
    wide = [0.01] * 27 + [5.0, 5.0, 5.0]
    j = v.judge(wide, 0.5, "k", 0.0, (-1, 1), low=0.001, high=1.0, n_paper=1000)
    assert j.interval[0] <= 0.5 <= j.interval[1]
    assert j.exceedance.above == 3 and j.exceedance.departs() and j.verdict == MATCHES
    # below the floor counts as the floor: runs and published both below it are equal
    floor = v.judge([0.0, 1e-320], 1e-300, "k", 0.0, (-1, 1), low=0.0, high=1e-290,
                    n_paper=1000, floor=1e-200)
    assert floor.verdict == CONSISTENT and floor.interval == (1e-200, 1e-200)
