"""swarmpath.evidence.stats: the papers' summary statistics and ranks."""

import math
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import rankdata

from swarmpath.evidence.stats import describe, rank

finite = st.floats(min_value=-1e150, max_value=1e150, allow_nan=False, allow_infinity=False)


def test_describe_matches_numpy_with_sample_std():
    x = [3.0, 1.0, 4.0, 1.0, 5.0, 9.0]
    d = describe(x)
    assert list(d) == ["min", "max", "avg", "std", "median", "q1", "q3", "iqr"]
    assert d["min"] == 1.0 and d["max"] == 9.0
    assert d["avg"] == pytest.approx(np.mean(x))
    assert d["std"] == pytest.approx(np.std(x, ddof=1))  # MATLAB's std, not ddof=0
    assert d["std"] != pytest.approx(np.std(x))
    assert d["median"] == 3.5
    # quartiles as numpy's default (linear between order statistics): sorted 1 1 3 4 5 9
    assert (d["q1"], d["q3"]) == (np.quantile(x, 0.25), np.quantile(x, 0.75)) == (1.5, 4.75)
    assert d["iqr"] == 3.25
    assert all(type(v) is float for v in d.values())


def test_describe_any_shape_and_sequence():
    assert describe(np.array([[1.0, 2.0], [3.0, 4.0]])) == describe([1, 2, 3, 4])
    assert describe((2,))["avg"] == 2.0


def test_single_value_has_zero_std():
    assert describe([7.5]) == {"min": 7.5, "max": 7.5, "avg": 7.5, "std": 0.0, "median": 7.5,
                               "q1": 7.5, "q3": 7.5, "iqr": 0.0}


def test_identical_values_are_exact():
    d = describe([0.1] * 7)
    assert d["avg"] == 0.1 and d["std"] == 0.0


def test_infinite_values_without_nan_or_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        d = describe([1.0, 2.0, math.inf])
        assert d == {"min": 1.0, "max": math.inf, "avg": math.inf, "std": math.inf, "median": 2.0,
                     "q1": 1.5, "q3": math.inf, "iqr": math.inf}
        d = describe([math.inf, math.inf])
        assert d["avg"] == math.inf and d["std"] == 0.0
        d = describe([-math.inf, 0.0, 0.0])
        assert d["avg"] == -math.inf and d["std"] == math.inf and d["median"] == 0.0
        # only +inf with -inf has no mean
        assert math.isnan(describe([-math.inf, math.inf])["avg"])


def test_huge_values_do_not_overflow():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        d = describe([1e308, 1.7e308, 1e307, 1.5e308])
    assert d["avg"] == pytest.approx(1.075e308)
    assert d["std"] == pytest.approx(np.std(np.array([1.0, 1.7, 0.1, 1.5]), ddof=1) * 1e308)
    assert d["median"] == pytest.approx(1.25e308)


def test_describe_rejects_empty_and_nan():
    with pytest.raises(ValueError, match="at least one"):
        describe([])
    with pytest.raises(ValueError, match="NaN"):
        describe([1.0, math.nan])


@settings(max_examples=60, deadline=None)
@given(st.lists(finite, min_size=1, max_size=40))
def test_describe_property(xs):
    d = describe(xs)
    a = np.array(xs)
    assert d["min"] == a.min() and d["max"] == a.max()
    assert d["min"] <= d["median"] <= d["max"]
    assert d["avg"] == pytest.approx(np.mean(a), rel=1e-12, abs=1e-300)
    # identical values give exactly 0 (numpy may leave rounding noise there)
    expected_std = np.std(a, ddof=1) if len(set(xs)) > 1 else 0.0
    assert d["std"] == pytest.approx(expected_std, rel=1e-9, abs=1e-300)


def test_rank_lowest_is_first_and_ties_share_the_smaller_rank():
    assert rank({"A": 3.0, "B": 1.0, "C": 2.0}) == {"A": 3, "B": 1, "C": 2}
    assert rank({"A": 1.0, "B": 2.0, "C": 2.0, "D": 5.0}) == {"A": 1, "B": 2, "C": 2, "D": 4}
    assert rank({"A": 0.0, "B": 0.0}) == {"A": 1, "B": 1}


def test_rank_keeps_key_order_and_handles_inf_and_nan():
    r = rank({"z": math.nan, "y": math.inf, "x": -math.inf, "w": 0.0})
    assert list(r) == ["z", "y", "x", "w"]
    assert r == {"z": 4, "y": 3, "x": 1, "w": 2}
    assert rank({}) == {}
    assert rank({"only": 42}) == {"only": 1}


@settings(max_examples=60, deadline=None)
@given(st.lists(st.sampled_from([0.0, 1e-30, 0.5, 2.0, 7.0, math.inf]), min_size=1, max_size=12))
def test_rank_equals_competition_ranking(values):
    avgs = {f"A{i}": v for i, v in enumerate(values)}
    assert list(rank(avgs).values()) == rankdata(values, method="min").astype(int).tolist()
