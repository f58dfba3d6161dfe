"""swarmpath.evidence.compare: against scipy's values and small cases worked by hand."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats

from swarmpath.evidence import compare


# ------------------------------------------------------------------------------------- holm
def test_holm_step_down_by_hand() -> None:
    # sorted: 0.005*4 = 0.02, 0.01*3 = 0.03, 0.03*2 = 0.06, 0.04*1 = 0.04 -> running max 0.06
    adjusted = compare.holm([0.01, 0.04, 0.03, 0.005])
    np.testing.assert_allclose(adjusted, [0.03, 0.06, 0.06, 0.02])


def test_holm_caps_at_one_and_keeps_order() -> None:
    rng = np.random.default_rng(3)
    p = rng.uniform(size=50)
    q = compare.holm(p)
    assert np.all(q >= p) and np.all(q <= 1.0)
    order = np.argsort(p)
    assert np.all(np.diff(q[order]) >= 0)
    assert compare.holm([]).size == 0
    assert compare.holm([0.7, 0.8]).tolist() == [1.0, 1.0]


# ---------------------------------------------------------------------------------- rank-sum
def test_rank_sum_by_hand() -> None:
    # x below y in every pair: U = 0; exact two-sided p = 2 / C(6, 3) = 0.1
    u, p = compare.rank_sum([1, 2, 3], [4, 5, 6])  # type: ignore[misc]
    assert u == 0.0 and p == pytest.approx(0.1)
    u, p = compare.rank_sum([4, 5, 6], [1, 2, 3])  # type: ignore[misc]
    assert u == 9.0 and p == pytest.approx(0.1)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rank_sum_equals_scipy_with_ties_and_inf(seed: int) -> None:
    rng = np.random.default_rng(seed)
    x = rng.integers(0, 6, size=30).astype(float)
    y = rng.integers(1, 7, size=25).astype(float)
    x[:3] = np.inf  # runs that never found a finite value: ranked worst
    ref = stats.mannwhitneyu(x, y, alternative="two-sided")
    assert compare.rank_sum(x, y) == (pytest.approx(ref.statistic), pytest.approx(ref.pvalue))


def test_rank_sum_drops_nan_and_handles_identical_and_empty() -> None:
    x = [1.0, math.nan, 2.0, 3.0]
    ref = stats.mannwhitneyu([1.0, 2.0, 3.0], [4.0, 5.0], alternative="two-sided")
    assert compare.rank_sum(x, [4.0, 5.0, math.nan]) == (ref.statistic, ref.pvalue)
    assert compare.rank_sum(np.zeros(30), np.zeros(30)) == (450.0, 1.0)
    assert compare.rank_sum([math.nan], [1.0]) is None
    assert compare.rank_sum([], [1.0]) is None


# ---------------------------------------------------------------------------- compare_samples
def _separated(n_cells: int, lower: bool = True) -> dict[object, dict[str, list[float]]]:
    """Cells where A's 5 runs all lie below (or above) the reference B's 5 runs: exact p = 2/252."""
    a, b = [1.0, 2, 3, 4, 5], [6.0, 7, 8, 9, 10]
    return {("F1", d): {"A": a if lower else b, "B": b if lower else a} for d in range(n_cells)}


def test_markers_direction_for_minimization() -> None:
    better = compare.compare_samples(_separated(1), ["A", "B"])
    assert better.reference == "B"  # default: the last algorithm listed
    assert better.marker(("F1", 0), "A") == compare.BETTER
    assert better.marker(("F1", 0), "B") is None  # the reference itself
    worse = compare.compare_samples(_separated(1, lower=False), ["A", "B"])
    assert worse.marker(("F1", 0), "A") == compare.WORSE
    # higher is better (e.g. a success measure): the same data reads the other way round
    flipped = compare.compare_samples(_separated(1), ["A", "B"], lower_is_better=False)
    assert flipped.marker(("F1", 0), "A") == compare.WORSE


def test_holm_over_the_table_by_hand() -> None:
    raw = 2 / 252  # exact p of two completely separated samples of 5
    six = compare.compare_samples(_separated(6), ["A", "B"])  # 6 * raw = 0.0476 < 0.05
    assert all(t.p == pytest.approx(raw) for t in six.tests)
    assert all(t.p_holm == pytest.approx(6 * raw) for t in six.tests)
    assert six.counts() == {"A": {"+": 6, "=": 0, "-": 0}}
    seven = compare.compare_samples(_separated(7), ["A", "B"])  # 7 * raw = 0.0556 > 0.05
    assert all(t.p_holm == pytest.approx(7 * raw) for t in seven.tests)
    assert seven.counts() == {"A": {"+": 0, "=": 7, "-": 0}}


def test_counts_reference_choice_and_untested_cells() -> None:
    samples = {
        "m1": {"A": [1.0, 2, 3, 4, 5], "B": [6.0, 7, 8, 9, 10], "C": [0.0] * 5},
        "m2": {"A": [0.0] * 5, "B": [0.0] * 5, "C": [math.nan] * 5},
    }
    c = compare.compare_samples(samples, ["A", "B", "C"], reference="b")
    assert c.reference == "B"
    assert c.marker("m1", "A") == "+" and c.marker("m1", "C") == "+"
    assert c.marker("m2", "A") == "=" and c.get("m2", "A").p == 1.0  # type: ignore[union-attr]
    assert c.marker("m2", "C") is None  # every run missing: not tested, not counted
    assert c.counts() == {"A": {"+": 1, "=": 1, "-": 0}, "C": {"+": 1, "=": 0, "-": 0}}
    doc = c.to_json(key_fields=("map",))
    assert doc["reference"] == "B" and doc["correction"] == "holm"
    assert {t["map"] for t in doc["tests"]} == {"m1", "m2"}


def test_fewer_than_two_algorithms_and_bad_reference() -> None:
    only = compare.compare_samples({"m": {"A": [1.0, 2.0]}}, ["A"])
    assert only.tests == () and only.counts() == {}
    with pytest.raises(ValueError, match="'Z' is not one of"):
        compare.compare_samples({}, ["A", "B"], reference="Z")


# ---------------------------------------------------------------------------------- fisher
def test_fisher_success_by_hand_and_against_scipy() -> None:
    counts = {"m1": {"A": (10, 10), "B": (0, 10)}, "m2": {"A": (3, 10), "B": (6, 10)}}
    c = compare.compare_success(counts, ["A", "B"])
    t1, t2 = c.get("m1", "A"), c.get("m2", "A")
    assert t1 is not None and t2 is not None
    assert t1.p == pytest.approx(2 / math.comb(20, 10))  # the two extreme tables of 20 choose 10
    assert t2.p == pytest.approx(stats.fisher_exact([[3, 7], [6, 4]]).pvalue)
    assert t1.marker == "+" and t2.marker == "="
    assert compare.compare_success({"m": {"A": (0, 10), "B": (10, 10)}}, ["A", "B"]).marker(
        "m", "A") == "-"
    with pytest.raises(ValueError, match="successes"):
        compare.compare_success({"m": {"A": (11, 10), "B": (1, 10)}}, ["A", "B"])


# --------------------------------------------------------------------------------- friedman
def test_friedman_by_hand() -> None:
    # A best on every block, then B, then C: ranks 1, 2, 3; chi2 = 12N/(k(k+1)) (sum R^2 -
    # k(k+1)^2/4) = 12*4/12 * (14 - 12) = 8; p = exp(-8/2) for 2 degrees of freedom.
    values = {f"F{i}": {"A": 0.1 * i, "B": 1.0 + i, "C": 10.0 + i} for i in range(4)}
    f = compare.friedman(values, ["A", "B", "C"])
    assert f.mean_ranks == {"A": 1.0, "B": 2.0, "C": 3.0}
    assert f.statistic == pytest.approx(8.0) and f.p == pytest.approx(math.exp(-4.0))
    ref = stats.friedmanchisquare(*np.array([[v["A"], v["B"], v["C"]] for v in values.values()]).T)
    assert f.p == pytest.approx(ref.pvalue)
    assert f.cd == pytest.approx(2.343 * math.sqrt(3 * 4 / (6 * 4)), abs=1e-3)  # Demsar q = 2.343
    # Holm vs the reference C: z = (R - 3) / sqrt(12/24)
    za, zb = -2 / math.sqrt(0.5), -1 / math.sqrt(0.5)
    pa, pb = 2 * stats.norm.sf(-za), 2 * stats.norm.sf(-zb)
    assert f.posthoc["A"]["p_holm"] == pytest.approx(2 * pa) and f.posthoc["A"]["marker"] == "+"
    assert f.posthoc["B"]["p_holm"] == pytest.approx(pb) and f.posthoc["B"]["marker"] == "="
    assert compare.cliques(f.mean_ranks, f.cd) == [("A", "B"), ("B", "C")]  # type: ignore[arg-type]


def test_friedman_ties_maximization_and_incomplete_blocks() -> None:
    values = {
        "F1": {"A": 0.0, "B": 0.0, "C": 1.0},
        "F2": {"A": 2.0, "B": 1.0, "C": 3.0},
        "F3": {"A": 1.0, "B": math.nan, "C": 0.0},  # B missing: block left out
        "F4": {"A": 5.0, "C": 0.0},
    }
    f = compare.friedman(values, ["A", "B", "C"])
    assert f.blocks == ("F1", "F2")
    assert f.mean_ranks == {"A": (1.5 + 2) / 2, "B": (1.5 + 1) / 2, "C": 3.0}
    ref = stats.friedmanchisquare([0.0, 2.0], [0.0, 1.0], [1.0, 3.0])
    assert f.statistic == pytest.approx(ref.statistic) and f.p == pytest.approx(ref.pvalue)
    up = compare.friedman(values, ["A", "B", "C"], lower_is_better=False)
    assert up.mean_ranks["C"] == 1.0


def test_friedman_degenerate_cases() -> None:
    ties = compare.friedman({f"F{i}": {"A": 0.0, "B": 0.0, "C": 0.0} for i in range(3)},
                            ["A", "B", "C"])
    assert (ties.statistic, ties.p) == (0.0, 1.0)
    two = compare.friedman({"F1": {"A": 1.0, "B": 2.0}, "F2": {"A": 1.0, "B": 2.0}}, ["A", "B"])
    assert two.p is None and "3 algorithms" in two.note and two.mean_ranks == {"A": 1.0, "B": 2.0}
    one = compare.friedman({"F1": {"A": 1.0, "B": 2.0, "C": 3.0}}, ["A", "B", "C"])
    assert one.p is None and "2 blocks" in one.note
    empty = compare.friedman({}, ["A", "B", "C"])
    assert empty.p is None and empty.cd is None


@pytest.mark.parametrize(
    ("k", "q"),
    [(2, 1.960), (3, 2.343), (4, 2.569), (5, 2.728), (6, 2.850), (7, 2.949), (8, 3.031),
     (9, 3.102), (10, 3.164)],
)
def test_nemenyi_cd_matches_demsar_table(k: int, q: float) -> None:
    n = 13
    assert compare.nemenyi_cd(k, n) == pytest.approx(q * math.sqrt(k * (k + 1) / (6 * n)),
                                                     abs=2e-3)


def test_rank_sum_many_equals_single_scipy_calls() -> None:
    rng = np.random.default_rng(5)
    pairs = [(rng.integers(0, 4, size=n).astype(float), rng.integers(1, 5, size=m).astype(float))
             for n, m in [(30, 30), (30, 30), (5, 6), (30, 25), (12, 12), (9, 3)]]
    pairs.append((np.zeros(20), np.zeros(20)))  # identical: p = 1, not scipy's NaN
    pairs.append((np.full(10, np.nan), np.ones(10)))  # nothing left to test
    got = compare.rank_sum_many(pairs)
    for (x, y), res in zip(pairs[:-2], got[:-2], strict=True):
        ref = stats.mannwhitneyu(x, y, alternative="two-sided")
        assert res == (pytest.approx(ref.statistic), pytest.approx(ref.pvalue, rel=1e-12))
    assert got[-2] == (200.0, 1.0) and got[-1] is None


def test_friedman_from_json_gives_back_the_test() -> None:
    values = {f"F{i}": {"A": 0.1 * i, "B": 1.0 + i, "C": 10.0 - i} for i in range(5)}
    f = compare.friedman(values, ["A", "B", "C"], reference="B")
    back = compare.Friedman.from_json(json.loads(json.dumps(f.to_json())))
    assert back.mean_ranks == f.mean_ranks and back.reference == "B"
    assert (back.statistic, back.p, back.cd) == (f.statistic, f.p, f.cd)
    assert back.posthoc == f.posthoc and len(back.blocks) == 5
    empty = compare.Friedman.from_json({**compare.friedman({}, ["A", "B"]).to_json(),
                                        "mean_ranks": {"A": "nan", "B": "nan"}})
    assert empty.cd is None and math.isnan(empty.mean_ranks["A"])
