"""Group-sequential boundaries (evidence.group_sequential): the published Pocock-type values,
the crossing probability against scipy's multivariate normal, and rank-sum looks simulated under
the null: the spent allocation holds its level, an allocation that ignores the looks does not."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy import stats

from swarmpath.evidence import group_sequential as gs
from swarmpath.evidence.compare import rank_sum_many


def test_pocock_type_boundaries_are_the_published_ones():
    """Lan-DeMets Pocock-type spending, 5 equally spaced looks, two-sided 0.05: Jennison and
    Turnbull (2000) / gsDesign's sfLDPocock give 2.438, 2.427, 2.410, 2.397, 2.386."""
    levels = gs.nominal_levels([1, 2, 3, 4, 5], 0.05, "pocock")
    z = [stats.norm.isf(p / 2) for p in levels]
    assert z == pytest.approx([2.438, 2.427, 2.410, 2.397, 2.386], abs=1.5e-3)


@pytest.mark.parametrize("kind", gs.SPENDING)
def test_the_boundaries_spend_the_level_on_the_looks_correlation(kind):
    """P(some |Z_k| >= c_k) with corr(Z_i, Z_j) = sqrt(n_i / n_j), by scipy's multivariate
    normal (Genz's integration, independent of the recursion here), is the level; the union
    bound's allocation (level / K per look) spends less, and each look at the whole level
    spends far more."""
    looks = [20, 50, 90, 140, 200]
    level = 0.01
    p = gs.nominal_levels(looks, level, kind)
    n = np.asarray(looks, dtype=float)
    cov = np.sqrt(np.minimum.outer(n, n) / np.maximum.outer(n, n))
    c = stats.norm.isf(np.asarray(p) / 2)
    inside = stats.multivariate_normal(np.zeros(5), cov, seed=1).cdf(c, lower_limit=-c)
    assert 1 - inside == pytest.approx(level, rel=0.02)
    assert gs.crossing_probabilities(looks, p) == pytest.approx(level, rel=1e-6)
    assert gs.crossing_probabilities(looks, [level / 5] * 5) < 0.8 * level
    assert gs.crossing_probabilities(looks, [level] * 5) > 2 * level
    # O'Brien-Fleming type keeps nearly all of it for the last looks, Pocock type spreads it
    assert list(p) == sorted(p)
    assert (p[0] < 1e-6 * p[-1]) if kind == "obrien-fleming" else (p[0] > 0.4 * p[-1])


def test_the_grid_is_fine_enough_at_a_race_level():
    looks = list(range(20, 600, 10))
    level = 0.05 * 0.8 / 65
    coarse = gs.nominal_levels(looks, level, "pocock")
    old = gs.GRID
    try:
        gs.GRID = 2001
        gs._bounds.cache_clear()
        fine = gs.nominal_levels(looks, level, "pocock")
    finally:
        gs.GRID = old
        gs._bounds.cache_clear()
    assert np.allclose(coarse, fine, rtol=1e-3, atol=0)


def _null_rejections(levels, looks, samples):
    """Per null pair of samples: whether the rank-sum test at look k, on the first looks[k]
    runs of both, is below levels[k] at some look."""
    hit = np.zeros(len(samples), dtype=bool)
    for n, level in zip(looks, levels, strict=True):
        tests = rank_sum_many([(a[:n], b[:n]) for a, b in samples])
        hit |= np.asarray([t is not None and t[1] < level for t in tests])
    return hit


def test_rank_sum_looks_under_the_null_hold_the_spent_level_and_fail_without_spending():
    """1500 null comparisons (two samples of one distribution), the rank-sum test at 6 looks
    with 0.1 spent (Pocock type): false differences at most 0.1 within 3 standard errors
    (measured 0.097). The same looks each at 0.1 (the allocation that ignores the looks) break
    that bound (measured 0.27): the check can fail."""
    rng = np.random.default_rng(5)
    looks = [10, 20, 40, 60, 80, 100]
    samples = [(rng.normal(size=100), rng.normal(size=100)) for _ in range(1500)]
    bound = 0.1 + 3 * math.sqrt(0.1 * 0.9 / len(samples))
    spent = _null_rejections(gs.nominal_levels(looks, 0.1, "pocock"), looks, samples)
    assert spent.mean() <= bound
    assert spent.mean() >= 0.1 - 3 * math.sqrt(0.1 * 0.9 / len(samples))  # it is spent
    assert _null_rejections([0.1] * len(looks), looks, samples).mean() > bound


@pytest.mark.parametrize(("looks", "level", "kind"), [
    ([], 0.05, "pocock"), ([10, 10], 0.05, "pocock"), ([0, 10], 0.05, "pocock"),
    ([10, 20], 0.0, "pocock"), ([10, 20], 0.05, "linear")])
def test_bad_designs_are_refused(looks, level, kind):
    with pytest.raises(ValueError):
        gs.nominal_levels(looks, level, kind)


@pytest.mark.parametrize("kind", gs.SPENDING)
def test_a_larger_level_lowers_the_boundary_at_every_look(kind):
    """What recycling a share within a race's block relies on (docs/statistics.md, Racing): a
    comparison tested at levels that rise from look to look, each at most L, crosses only where
    the boundary of level L is crossed too, since every look's nominal level grows with the
    level. Checked on the looks of Table 2's race (every round, 98) from the level of one of its
    comparisons to a recycled block's share."""
    looks = tuple(range(20, 1000, 10))
    levels = [gs.nominal_levels(looks, level, kind) for level in (6e-5, 6e-4, 1.5e-3, 3e-3, 0.05)]
    for lower, higher in itertools.pairwise(levels):
        assert all(h > lo for lo, h in zip(lower, higher, strict=True) if lo > 0)
