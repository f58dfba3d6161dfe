"""The numba backend against the numpy reference (swarmpath.optimizers.compiled).

Every algorithm of the optimizer registry either has a kernel, which must give the reference's
numbers run for run (to the last bit, or within the tolerance it declares and records), or
refuses ``backend="numba"`` with an error naming the algorithm.
"""

from __future__ import annotations

import re
import subprocess
import sys
from itertools import product

import numpy as np
import pytest

from swarmpath.functions import get_function, list_functions
from swarmpath.optimizers import (
    ParameterError,
    get_optimizer,
    list_optimizers,
    minimize,
    minimize_many,
)
from swarmpath.optimizers.api import BACKENDS, check_backend, resolve_backend
from swarmpath.optimizers.compiled import find_kernel, kernel_names
from swarmpath.optimizers.compiled.objectives import evaluate, objective_for, work_for
from swarmpath.optimizers.compiled.streams import (
    normal_into,
    open_stream,
    random_into,
)
from swarmpath.optimizers.compiled.warm import warm
from swarmpath.optimizers.problem import BenchmarkProblem
from swarmpath.optimizers.streams import RunStreams, run_generator

FIELDS = ("best_fitness", "best_position", "curve", "evaluations", "shifts")
WITH_KERNEL = [a for a in list_optimizers() if find_kernel(a) is not None]
WITHOUT_KERNEL = [a for a in list_optimizers() if find_kernel(a) is None]
UNCAPPED = next(a for a in WITH_KERNEL if not find_kernel(a).capped)  # counts no budget


def assert_same(ref, fast, tolerance):
    for field in FIELDS:
        a, b = getattr(ref, field), getattr(fast, field)
        if a is None or tolerance == 0.0 or field == "evaluations":
            assert (a is None and b is None) or np.array_equal(a, b), (ref.function, field)
        else:
            np.testing.assert_allclose(b, a, rtol=tolerance, atol=0, err_msg=field)


def test_kernel_names_come_from_the_optimizer_registry():
    assert kernel_names() == WITH_KERNEL
    assert {"PSO", "GWO"} <= set(kernel_names())


def test_stream_emulation_draws_the_reference_numbers():
    sizes = [("r", 900), ("n", 300), ("r", 1800), ("n", 5000), ("r", 7000), ("n", 9000),
             ("r", 9100), ("r", 5), ("n", 100)] * 3
    for seed, run in [(1, 0), (7, 3)]:
        ref = RunStreams.for_runs(seed, [run + 1, run])
        stream = open_stream(run_generator(seed, run), 9100, True)
        for kind, n in sizes:
            expected = (ref.random if kind == "r" else ref.normal)(n)[1]
            got = np.empty(n)
            (random_into if kind == "r" else normal_into)(stream, got)
            assert np.array_equal(expected, got), (kind, n)


@pytest.mark.parametrize("kind", ["r", "n"])
def test_a_direct_stream_draws_the_reference_numbers_of_one_kind(kind):
    sizes = [900, 5, 9100, 7000, 300, 8192, 1]
    ref = RunStreams.for_runs(4, [2, 5])
    stream = open_stream(run_generator(4, 5), 9100, False)
    fill = random_into if kind == "r" else normal_into
    for n in sizes:
        expected = (ref.random if kind == "r" else ref.normal)(n)[1]
        got = np.empty(n)
        fill(stream, got)
        assert np.array_equal(expected, got), n
    with pytest.raises(ValueError, match="one kind"):
        (normal_into if kind == "r" else random_into)(stream, np.empty(3))
    with pytest.raises(ValueError, match="capacity"):
        fill(stream, np.empty(9101))


@pytest.mark.parametrize("name", list_functions())
def test_compiled_functions_equal_the_reference_bit_for_bit(name):
    fn = get_function(name)
    rng = np.random.default_rng(5)
    for dim, transform in product((2, 7, 9, 16, 30, 33), ("none", "shift")):
        problem = BenchmarkProblem.build(fn, dim, [0, 1], 4, transform)
        X = rng.uniform(fn.lower, fn.upper, (2, 20, dim))
        X[:, :3] = np.round(X[:, :3])  # integral points: exact zeros of the trigonometry
        ref = problem.objective(X, RunStreams.for_runs(9, [0, 1]))
        ref = np.where(np.isnan(ref), np.inf, ref)
        for r in range(2):
            F = np.empty(20)
            shifted = problem.shifts is not None
            shift = problem.shifts[r] if shifted else np.zeros(dim)
            evaluate(open_stream(run_generator(9, r), 20, False), objective_for(fn), shifted, shift,
                     problem.lower[r], problem.upper[r], np.ascontiguousarray(X[r]), F,
                     np.ones(20, dtype=bool), work_for(20, dim))
            assert np.array_equal(F, ref[r]), (dim, transform)


def _settings(algo):
    """The default parameters, then each value of each choice parameter."""
    cls = get_optimizer(algo)
    yield {}
    for key, values in cls.choices.items():
        for value in values:
            if value != cls.defaults[key]:
                yield {key: value}


@pytest.mark.parametrize("algo", WITH_KERNEL)
def test_kernel_equals_the_reference(algo):
    tolerance = find_kernel(algo).tolerance
    functions = list_functions()
    for k, params in enumerate(_settings(algo)):
        for dim, transform in ((3, "none"), (9, "shift")):
            kw = dict(dim=dim, agents=6, iterations=12, seed=3 + k, params=params,
                      transform=transform, run_ids=[2, 0])
            ref = minimize_many(algo, functions, backend="numpy", **kw)
            fast = minimize_many(algo, functions, backend="numba", **kw)
            for a, b in zip(ref, fast, strict=True):
                assert (b.backend, b.tolerance, a.backend) == ("numba", tolerance, "numpy")
                assert b.params == a.params and b.function == a.function
                assert_same(a, b, tolerance)


@pytest.mark.parametrize("algo", WITH_KERNEL)
def test_kernel_runs_do_not_depend_on_the_batch(algo):
    kw = dict(dim=5, agents=7, iterations=10, seed=11, transform="shift")
    whole = minimize(algo, "F7", run_ids=[0, 1, 2, 3, 4], backend="numba", **kw)
    assert whole.backend == "numba"
    ref = minimize(algo, "F7", run_ids=[0, 1, 2, 3, 4], chunk_elements=2 * 7 * 5,
                   backend="numpy", **kw)
    for ids in ([3], [4, 0, 2], [1, 3]):
        part = minimize(algo, "F7", run_ids=ids, backend="numba", **kw)
        for i, r in enumerate(ids):
            for field in FIELDS:
                assert np.array_equal(getattr(part, field)[i], getattr(whole, field)[r]), field
    assert_same(ref, whole, find_kernel(algo).tolerance)


@pytest.mark.parametrize("algo", WITHOUT_KERNEL)
def test_algorithms_without_a_kernel_refuse_numba(algo):
    with pytest.raises(ParameterError, match=rf"algorithm '{algo}' has no numba kernel"):
        minimize(algo, "F1", dim=2, agents=5, iterations=2, runs=1, backend="numba")


def test_what_has_no_kernel_is_refused_by_name():
    algo = WITH_KERNEL[0]
    kw = dict(dim=3, agents=5, iterations=2, runs=1)
    with pytest.raises(ParameterError, match="backend must be one of auto, numpy, numba"):
        minimize(algo, "F1", backend="cuda", **kw)
    for transform in ("rotate", "shift+rotate"):
        with pytest.raises(ParameterError, match=re.escape(f"transform '{transform}'")):
            minimize(algo, "F1", transform=transform, backend="numba", **kw)
    hand_made = get_function("F1").__class__(name="F1", kernel=lambda x: x[..., 0], lower=-1,
                                            upper=1, optimum_coordinate=0.0)
    with pytest.raises(ParameterError, match="function 'F1' has no numba kernel"):
        minimize(algo, hand_made, backend="numba", **kw)
    with pytest.raises(ParameterError, match="agents"):
        minimize(algo, "F1", dim=3, agents=0, iterations=2, runs=1, backend="numba")


def test_missing_numba_is_a_parameter_error(monkeypatch):
    monkeypatch.setitem(sys.modules, "swarmpath.optimizers.compiled.run", None)
    with pytest.raises(ParameterError, match="backend 'numba' needs numba"):
        minimize(WITH_KERNEL[0], "F1", dim=2, agents=5, iterations=2, runs=1, backend="numba")


def test_progress_hook_is_called_once_per_iteration_in_all():
    calls = []
    minimize_many(WITH_KERNEL[0], ["F1", "F9"], dim=2, agents=4, iterations=7, runs=3,
                  backend="numba", on_iteration=calls.append)
    assert calls == [None] * 7


@pytest.mark.parametrize("algo", WITH_KERNEL)
def test_function_runs_with_numba_give_each_functions_own_runs(algo):
    """A worker's stack of leases (``function_runs``) on the numba backend: each function's
    runs as ``minimize`` alone, and progress still ``iterations`` calls in all."""
    kw = dict(dim=3, agents=6, iterations=9, seed=2, backend="numba")
    functions, runs = ["F1", "F7", "F1"], [[4, 1], [0], [2, 3, 5]]
    calls: list[object] = []
    stacked = minimize_many(algo, functions, function_runs=runs, on_iteration=calls.append, **kw)
    assert calls == [None] * 9
    for f, ids, got in zip(functions, runs, stacked, strict=True):
        alone = minimize(algo, f, run_ids=ids, **kw)
        assert got.run_ids == ids and got.backend == "numba"
        assert_same(alone, got, 0.0)


def test_the_numpy_backend_never_imports_numba():
    code = ("import sys; from swarmpath.optimizers import minimize; "
            "[minimize(a, 'F10', dim=2, agents=4, iterations=2, runs=1, backend='numpy') for a in "
            f"{list_optimizers()!r}]; print('numba' in sys.modules)")
    path = ":".join(p for p in sys.path if p)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={"PYTHONPATH": path})
    assert out.stdout.strip() == "False"
    assert "numpy" in BACKENDS


def test_auto_runs_the_kernels_where_the_study_has_them_and_numpy_elsewhere(monkeypatch):
    kw = dict(dim=3, agents=5, iterations=6, run_ids=[2, 0], seed=4)
    algo = WITH_KERNEL[0]
    warm([algo], ["F8"])  # compiled: auto runs them (numpy before, test_compiled_background.py)
    auto = minimize(algo, "F8", transform="shift", **kw)  # the default backend
    assert (auto.backend, auto.tolerance) == ("numba", 0.0)
    assert_same(minimize(algo, "F8", transform="shift", backend="numpy", **kw), auto, 0.0)
    hand_made = get_function("F1").__class__(name="F1", kernel=lambda x: x[..., 0], lower=-1,
                                            upper=1, optimum_coordinate=0.0)
    numpy_only = [
        dict(algorithm=WITHOUT_KERNEL[0], function="F1") if WITHOUT_KERNEL else None,
        dict(algorithm=algo, function="F1", transform="rotate"),
        dict(algorithm=algo, function=hand_made),
        dict(algorithm=algo, function="cec2017:F1@centre", dim=10),  # no compiled objective
        dict(algorithm=UNCAPPED, function="F1", max_evaluations=12),  # a budget that binds
    ]
    for case in filter(None, numpy_only):
        res = minimize(**{**kw, **case})
        assert res.backend == "numpy", case
        assert_same(minimize(**{**kw, **case, "backend": "numpy"}), res, 0.0)
    check_backend("auto", list_optimizers(), "rotate", None, ["F1", "bbob:f1"])  # never refuses
    assert resolve_backend("auto", algo, ["F1", "F7"]) == "numba"
    assert resolve_backend("numpy", algo, ["F1"]) == "numpy"
    monkeypatch.setitem(sys.modules, "swarmpath.optimizers.compiled.run", None)  # no numba
    assert minimize(algo, "F1", **kw).backend == "numpy"
    assert resolve_backend("auto", algo, ["F1"]) == "numpy"


def test_bench_with_the_numba_backend_gives_the_reference_tables_numbers():
    from swarmpath.cli import bench, bench_spec

    kw = dict(runs=3, agents=5, iterations=6, seed=2, transform="shift")
    cells = {}
    for backend in BACKENDS:
        spec = bench_spec.make_spec(",".join(WITH_KERNEL), "F1,F7,F8", "3", backend=backend, **kw)
        assert spec.settings()["backend"] == backend
        cells[backend] = bench.run_bench(spec, jobs=1)
    for ref, fast in zip(cells["numpy"], cells["numba"], strict=True):
        assert (ref.best_fitness, ref.curves) == (fast.best_fitness, fast.curves)


def test_reproduce_puts_the_backend_in_the_setting():
    from swarmpath.cli import reproduce
    from swarmpath.cli.core import InputError
    from swarmpath.evidence import reference

    table = next(t for t in map(reference.load, reference.TABLES)
                 if isinstance(t, reference.BenchmarkTable))
    assert "backend" not in reproduce.study_setting(table, 2, 1)  # auto
    assert reproduce.study_setting(table, 2, 1, "numpy")["backend"] == "numpy"
    if all(find_kernel(a) is not None for a in table.algorithms):
        assert reproduce.study_setting(table, 2, 1, "numba")["backend"] == "numba"
    else:
        with pytest.raises(InputError, match="has no numba kernel"):
            reproduce.study_setting(table, 2, 1, "numba")
    assert "--backend numba" in reproduce.command_line(table.name, 2, 1, "table", "numba")
