"""F1-F13: optima, vectorization, shifts, documented bounds."""

import numpy as np
import pytest

from swarmpath.functions import expand_function_names, get_function, list_functions

# Bounds and minimiser coordinate as documented in docs/functions.md (GWO 2014 code).
DOCUMENTED = {
    "F1": (100, 0.0), "F2": (10, 0.0), "F3": (100, 0.0), "F4": (100, 0.0), "F5": (30, 1.0),
    "F6": (100, -0.5), "F6-floor": (100, 0.0), "F7": (1.28, 0.0), "F8": (500, 420.968746),
    "F9": (5.12, 0.0), "F10": (32, 0.0), "F11": (600, 0.0), "F12": (50, -1.0), "F13": (50, 1.0),
}


def test_registry_lists_the_documented_set():
    assert list_functions() == list(DOCUMENTED)


@pytest.mark.parametrize("name", list_functions())
def test_bounds_and_optimum_as_documented(name):
    f = get_function(name)
    bound, coord = DOCUMENTED[name]
    assert (f.lower, f.upper) == (-bound, bound)
    assert f.optimum(7) == pytest.approx(np.full(7, coord))


@pytest.mark.parametrize("name", list_functions())
@pytest.mark.parametrize("dim", [2, 30])
def test_value_at_optimum_is_f_min(name, dim):
    f = get_function(name)
    value = f.evaluate(f.optimum(dim))  # F7 without rng: its deterministic part
    assert value == pytest.approx(f.f_min_for(dim), abs=1e-9 * max(1.0, abs(f.f_min_for(dim))))


@pytest.mark.parametrize("name", list_functions())
def test_optimum_is_a_local_minimum(name):
    f = get_function(name)
    rng = np.random.default_rng(3)
    x0 = f.optimum(10)
    around = np.clip(x0 + rng.normal(scale=1e-3, size=(200, 10)), f.lower, f.upper)
    assert np.all(f.evaluate(around) >= f.evaluate(x0) - 1e-9)


@pytest.mark.parametrize("name", list_functions())
def test_vectorized_equals_row_by_row(name):
    f = get_function(name)
    rng = np.random.default_rng(0)
    X = rng.uniform(f.lower, f.upper, size=(4, 5, 6))
    batched = f.evaluate(X)
    assert batched.shape == (4, 5)
    for i in range(4):
        for j in range(5):
            assert batched[i, j] == pytest.approx(float(f.evaluate(X[i, j])), rel=1e-12)


def test_f7_noise_comes_from_the_generator():
    f = get_function("F7")
    x = np.zeros((1000, 5))
    a = f.evaluate(x, rng=np.random.default_rng(1))
    b = f.evaluate(x, rng=np.random.default_rng(1))
    c = f.evaluate(x, rng=np.random.default_rng(2))
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    assert a.min() >= 0.0 and a.max() < 1.0 and 0.4 < a.mean() < 0.6


def test_known_values_from_the_gwo_code():
    # Hand-computed from the formulas of Get_Functions_details.m.
    x = np.array([1.0, -2.0, 3.0])
    assert get_function("F1").evaluate(x) == pytest.approx(14.0)
    assert get_function("F2").evaluate(x) == pytest.approx(6.0 + 6.0)
    assert get_function("F3").evaluate(x) == pytest.approx(1.0 + 1.0 + 4.0)
    assert get_function("F4").evaluate(x) == pytest.approx(3.0)
    assert get_function("F5").evaluate(x) == pytest.approx(100 * 9 + 0 + 100 * 1 + 9)
    assert get_function("F6").evaluate(x) == pytest.approx(2.25 + 2.25 + 12.25)
    assert get_function("F6-floor").evaluate(np.array([1.4, -2.6, 0.2])) == pytest.approx(1 + 9)
    assert get_function("F7").evaluate(x) == pytest.approx(1 + 2 * 16 + 3 * 81)
    # F12 first term squares 10 sin(pi y1): at x = 1 (y1 = 1.5) it is 10, not 10 sin(pi y1) = -10
    f12 = get_function("F12").evaluate(np.array([1.0, -1.0]))
    assert f12 == pytest.approx(np.pi / 2 * (10.0 + 0.25 * (1 + 0) + 0.0))


@pytest.mark.parametrize("name", list_functions())
def test_shifted_optimum_moves_with_the_shift(name):
    f = get_function(name)
    rng = np.random.default_rng(11)
    o = f.random_shift(8, rng)
    g = f.shifted(o)
    moved = g.optimum(8)
    centre, half = 0.5 * (f.lower + f.upper), 0.4 * (f.upper - f.lower)
    assert np.all(np.abs(moved - centre) <= half + 1e-12)  # inside the central 80% of the box
    assert (g.lower, g.upper) == (f.lower, f.upper)
    f_min = f.f_min_for(8)
    assert g.evaluate(moved) == pytest.approx(f_min, abs=1e-8 * max(1, abs(f_min)))
    probe = rng.uniform(f.lower, f.upper, size=(500, 8))
    assert np.all(g.evaluate(probe) >= f.f_min_for(8) - 1e-6)


def test_shift_outside_box_is_rejected():
    with pytest.raises(ValueError, match="outside its box"):
        get_function("F1").shifted(np.full(3, 150.0))


def test_name_expansion_and_errors():
    assert expand_function_names("F1-F13") == [f"F{i}" for i in range(1, 14)]
    assert expand_function_names("F2,F6-floor,F9-F10") == ["F2", "F6-floor", "F9", "F10"]
    with pytest.raises(KeyError, match="valid: F1, F2"):
        expand_function_names("F14")


def test_trig_kernels_match_the_c_library():
    from swarmpath.functions.trig import cospi, sinpi, sinpi_squared

    rng = np.random.default_rng(5)
    for q in (rng.uniform(-0.5, 0.5, 20000), rng.uniform(-700.0, 700.0, 20000)):
        # reference: the C library on the exactly reduced argument, sign restored by parity
        n = np.rint(q)
        r = q - n
        sign = np.where(np.mod(n, 2.0) == 0.0, 1.0, -1.0)
        sin_ref, cos_ref = sign * np.sin(np.pi * r), sign * np.cos(np.pi * r)
        assert np.max(np.abs(sinpi(q) - sin_ref)) < 4e-16
        assert np.max(np.abs(cospi(q) - cos_ref)) < 4e-16
        assert np.max(np.abs(sinpi_squared(q) - sin_ref**2)) < 8e-16
    k = np.arange(-6.0, 7.0)
    assert np.all(sinpi(k) == 0.0) and np.all(sinpi_squared(k) == 0.0)
    assert np.array_equal(cospi(k), np.where(np.mod(k, 2.0) == 0.0, 1.0, -1.0))
    assert np.all(cospi(k + 0.5) == 0.0)
    assert np.array_equal(sinpi(k + 0.5), np.where(np.mod(k, 2.0) == 0.0, 1.0, -1.0))
    # shapes, including 0-d
    assert sinpi(np.float64(0.25)).shape == () and cospi(np.zeros((2, 3))).shape == (2, 3)


@pytest.mark.parametrize("name", list_functions())
def test_batch_rows_are_bit_identical_to_single_runs(name):
    # the reproducibility contract needs this: run r alone or in any batch, the same bits
    f = get_function(name)
    rng = np.random.default_rng(2)
    X = rng.uniform(f.lower, f.upper, size=(37, 30, 30))
    whole = f.kernel(X)
    for r in (0, 5, 36):
        assert np.array_equal(f.kernel(X[r : r + 1])[0], whole[r])
        assert np.array_equal(f.kernel(X[r : r + 3])[0], whole[r])
