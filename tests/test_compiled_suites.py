"""The suites' compiled objectives give the numpy suites' numbers to the last bit.

Values of every function on random points, at the optimum and next to it, for several
dimensions and instances (a population and a single point: numpy's matmul takes another
BLAS path for one row); the sum orders they copy against numpy's own calls; every kernel's
optimizer on the suites against the numpy backend; the registry's view (instances by base
name, centred copies refused, ``auto`` choosing numba).
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("numba")

from swarmpath.functions import get_function
from swarmpath.functions.suites.cec import data
from swarmpath.optimizers.api import minimize_many, resolve_backend
from swarmpath.optimizers.base import ParameterError
from swarmpath.optimizers.compiled import functions, objectives, suite_ops
from swarmpath.optimizers.compiled.registry import kernel_names
from swarmpath.optimizers.compiled.run import check_function

BBOB = [f"bbob:f{k}" for k in range(1, 25)]
CEC2022 = [f"cec2022:F{k}" for k in range(1, 13)]
CEC2017 = [f"cec2017:F{k}" for k in range(1, 31)]  # F2 too: excluded from the set, named
CEC = CEC2022 + CEC2017


def _points(fn, d, rng):
    """17 points over and beyond the box, the optimum, a point 1e-9 from it, a corner."""
    X = rng.uniform(-5.5, 5.5, (20, d))
    X[0] = fn.x_opt(d)
    X[1] = fn.x_opt(d) + 1e-9
    X[2] = 5.0
    return X


@pytest.mark.parametrize("name", BBOB)
def test_bbob_values_equal_numpy_bit_for_bit(name):
    rng = np.random.default_rng(int(name.split("f")[-1]))
    for d in (2, 3, 7, 10, 20, 40):
        for instance in (1, 2, 71):
            fn = get_function(name).with_instance(instance)
            X = _points(fn, d, rng)
            want = fn.kernel(X[None])[0]
            got = objectives.population_values(fn, X)
            assert np.array_equal(got, want), (fn.name, d, np.flatnonzero(got != want))
            assert got[0] == fn.kernel(X[None, :1])[0, 0]  # the optimum, alone
            one = objectives.population_values(fn, X[5:6])
            assert np.array_equal(one, fn.kernel(X[None, 5:6])[0]), (fn.name, d)


def test_the_comparison_sees_a_wrong_instance():
    # the values above are the instance's: another instance's data gives other numbers
    fn = get_function("bbob:f15@i2")
    X = _points(fn, 5, np.random.default_rng(0))
    other = get_function("bbob:f15@i3")
    assert not np.array_equal(objectives.population_values(other, X), fn.kernel(X[None])[0])


def _cec_points(fn, d, rng):
    """Points over the box [-100, 100]^d (every branch of Schwefel's, every composition
    weight), the optimum, a point 1e-9 from it, a corner, a far point (no composition weight
    left: cf_cal's equal weights) and one component's own optimum."""
    X = rng.uniform(-100.0, 100.0, (24, d))
    X[0] = fn.x_opt(d)
    X[1] = fn.x_opt(d) + 1e-9
    X[2] = 100.0
    X[3] = -3000.0
    X[4] = data(fn.suite)[f"O{fn.number}"][-1, :d]
    return X


@pytest.mark.parametrize("name", CEC)
def test_cec_values_equal_numpy_bit_for_bit(name):
    fn = get_function(name)
    rng = np.random.default_rng(fn.number)
    for d in fn.dimensions:
        X = _cec_points(fn, d, rng)
        want = fn.kernel(X[None])[0]
        got = objectives.population_values(fn, X)
        assert np.array_equal(got, want), (fn.name, d, np.flatnonzero(got != want))
        for row in (0, 3, 5):  # one point alone (numpy's matmul takes another BLAS path)
            one = objectives.population_values(fn, X[row:row + 1])
            assert np.array_equal(one, fn.kernel(X[None, row:row + 1])[0]), (fn.name, d, row)


def test_the_cec_comparison_sees_another_function_and_dimension():
    fn = get_function("cec2022:F11")
    X = _cec_points(fn, 10, np.random.default_rng(0))
    assert not np.array_equal(objectives.population_values(get_function("cec2022:F12"), X),
                              fn.kernel(X[None])[0])
    assert not np.array_equal(objectives.data_for(fn, 10), objectives.data_for(fn, 20))


@pytest.mark.parametrize("n", range(1, 101))
def test_sum_orders_are_numpys(n):
    rng = np.random.default_rng(n)
    a = rng.standard_normal((2, n)) * np.exp(3.0 * rng.standard_normal((2, n)))
    b = rng.standard_normal((2, n))
    assert functions.dot(a[0], b[0], n) == np.einsum("...i,...i->...", a, b)[0]
    assert functions.total(a[0], n) == np.einsum("...i->...", a)[0]
    assert suite_ops.row_sum(a[0], n) == a.sum(axis=-1)[0]


def test_a_plain_order_would_differ():  # the orders above are not a coincidence of the data
    rng = np.random.default_rng(0)
    a = rng.standard_normal((200, 13)) * np.exp(3.0 * rng.standard_normal((200, 13)))
    plain = np.array([sum(row.tolist()) for row in a])
    assert not np.array_equal(plain, np.einsum("...i->...", a))


@pytest.mark.parametrize("k", range(1, 25))
def test_every_kernel_gives_the_numpy_backends_runs(k):
    """Each function with one of the kernels (every kernel in turn), one dimension and instance
    in turn: the same bests and curves as the numpy backend."""
    algorithms = kernel_names()
    algorithm = algorithms[k % len(algorithms)]
    d, instance = (2, 5, 10, 40)[k % 4], (1, 3, 71, 2)[k % 4]
    name = get_function(f"bbob:f{k}").with_instance(instance).name
    kw = dict(dim=d, agents=12, iterations=12, runs=2, seed=3)
    _same_runs_on_both_backends(algorithm, name, kw)


@pytest.mark.parametrize("name", CEC)
def test_every_kernel_gives_the_numpy_backends_runs_on_cec(name):
    """Each CEC function with one of the kernels (each in turn) in one of its dimensions."""
    fn = get_function(name)
    algorithms = kernel_names()
    k = CEC.index(name)
    algorithm = algorithms[k % len(algorithms)]
    d = fn.dimensions[k % len(fn.dimensions)]
    kw = dict(dim=d, agents=10, iterations=8, runs=2, seed=5)
    _same_runs_on_both_backends(algorithm, name, kw)


def test_instances_share_their_functions_objective_and_centred_copies_have_none():
    fn = get_function("bbob:f3@i7")
    assert objectives.has_objective(fn)
    assert objectives.has_objective(get_function("bbob:f3"))
    centred = get_function("bbob:f3").centred_copy()
    assert not objectives.has_objective(centred)
    with pytest.raises(ParameterError, match="no numba kernel"):
        check_function(centred)
    # the data differ per instance and dimension
    assert not np.array_equal(objectives.data_for(fn, 5), objectives.data_for(
        get_function("bbob:f3"), 5))


def test_auto_runs_bbob_compiled():
    assert resolve_backend("auto", "GWO", ["bbob:f1", "bbob:f24@i3"]) == "numba"


def test_auto_runs_cec_compiled_and_the_cec_functions_share_one_objective():
    assert resolve_backend("auto", "GWO", CEC) == "numba"
    first, last = (get_function(name) for name in (CEC[0], CEC[-1]))
    assert objectives.objective_for(first)[0] == objectives.objective_for(last)[0]
    assert not objectives.has_objective(first.centred_copy())


def _same_runs_on_both_backends(algorithm, name, kw):
    """The numba backend's runs of ``name`` equal the numpy backend's: bests, curves, positions."""
    (ref,) = minimize_many(algorithm, [name], backend="numpy", **kw)
    (out,) = minimize_many(algorithm, [name], backend="numba", **kw)
    assert out.backend == "numba"
    assert np.array_equal(out.best_fitness, ref.best_fitness), (algorithm, name)
    assert np.array_equal(out.curve, ref.curve), (algorithm, name)
    assert np.array_equal(out.best_position, ref.best_position), (algorithm, name)


def test_every_objective_auto_may_run_is_compared_with_its_reference_bit_for_bit():
    """Backend "auto" runs a compiled objective or the numpy function as their compile allows
    (tests/test_compiled_background.py): each registered objective is one of those compared
    above (BBOB, CEC) or in test_compiled.py (the registry's built-in functions)."""
    from swarmpath.functions import list_functions

    assert set(objectives.compiled_names()) == set(list_functions()) | set(BBOB) | set(CEC)
