"""The numba backend under an evaluation budget (``max_evaluations``, ``--budget-evals``).

Every kernel gives the numpy reference's numbers under a study's budget (the iterations that
spend it), so ``auto`` runs such a study compiled; a budget that can end a run inside an
iteration runs compiled only where the kernel counts the budget itself (``Kernel.capped``),
and on numpy (``auto``) or refused by name (``numba``) elsewhere.
"""

from __future__ import annotations

import numpy as np
import pytest

from swarmpath.cli import bench, bench_spec
from swarmpath.cli.core import InputError
from swarmpath.optimizers import ParameterError, get_optimizer, list_optimizers, minimize_many
from swarmpath.optimizers.api import resolve_backend
from swarmpath.optimizers.budget import (
    declared_evaluations,
    iterations_for_budget,
    most_evaluations,
)
from swarmpath.optimizers.compiled import find_kernel
from swarmpath.optimizers.compiled import run as compiled_run
from swarmpath.optimizers.compiled.warm import warm
from swarmpath.service.jobspec import parse_job_spec

FIELDS = ("best_fitness", "best_position", "curve", "evaluations", "shifts")
WITH_KERNEL = [a for a in list_optimizers() if find_kernel(a) is not None]
FUNCTIONS = ["F1", "F7", "F9", "bbob:f3", "bbob:f21@i2"]


def assert_same(ref, fast):
    """Every field of the two results equal to the last bit."""
    for field in FIELDS:
        a, b = getattr(ref, field), getattr(fast, field)
        assert (a is None and b is None) or np.array_equal(a, b), (ref.function, field)


def _settings(algo):
    """The default parameters, then each other value of each choice parameter."""
    cls = get_optimizer(algo)
    return [{}] + [{key: value} for key, values in cls.choices.items() for value in values
                   if value != cls.defaults[key]]


@pytest.mark.parametrize("algo", WITH_KERNEL)
def test_auto_runs_a_study_budget_compiled_with_the_reference_numbers(algo):
    budget, agents, dim = 150, 6, 4
    warm([algo], FUNCTIONS)  # auto runs compiled kernels (numpy before: test_compiled_background)
    for k, params in enumerate(_settings(algo)):
        t = iterations_for_budget(algo, budget, agents, dim, params)
        kw = dict(dim=dim, agents=agents, iterations=t, run_ids=[3, 0], seed=5 + k,
                  params=params, max_evaluations=budget)
        compiled = resolve_backend("auto", algo, FUNCTIONS, params=params)  # no budget
        ref = minimize_many(algo, FUNCTIONS, backend="numpy", **kw)
        fast = minimize_many(algo, FUNCTIONS, **kw)  # auto
        assert k or compiled == "numba"  # the defaults have a kernel
        for a, b in zip(ref, fast, strict=True):
            assert (a.backend, b.backend) == ("numpy", compiled), params
            assert b.evaluations.max() <= budget
            assert_same(a, b)


@pytest.mark.parametrize("algo", WITH_KERNEL)
def test_a_budget_that_ends_runs_early_is_compiled_only_where_the_kernel_counts_it(algo):
    agents, dim, iterations = 6, 3, 12
    warm([algo], FUNCTIONS)  # auto runs compiled kernels (numpy before: test_compiled_background)
    kw = dict(dim=dim, agents=agents, iterations=iterations, run_ids=[1, 4], seed=2)
    free = min(r.evaluations.min() for r in minimize_many(algo, FUNCTIONS, backend="numpy",
                                                          **kw))
    for cap in (agents - 1, free // 2, free - 1):
        ref = minimize_many(algo, FUNCTIONS, backend="numpy", max_evaluations=cap, **kw)
        assert {r.evaluations.max() for r in ref} == {cap}  # the cap binds
        auto = minimize_many(algo, FUNCTIONS, max_evaluations=cap, **kw)
        if find_kernel(algo).capped:
            fast = minimize_many(algo, FUNCTIONS, backend="numba", max_evaluations=cap, **kw)
            for a, b, c in zip(ref, fast, auto, strict=True):
                assert (b.backend, c.backend) == ("numba", "numba")
                assert_same(a, b)
                assert_same(a, c)
        else:
            with pytest.raises(ParameterError, match=rf"budget_evals {cap}: {algo}'s kernel"):
                minimize_many(algo, FUNCTIONS, backend="numba", max_evaluations=cap, **kw)
            assert {res.backend for res in auto} == {"numpy"}
            for a, c in zip(ref, auto, strict=True):
                assert_same(a, c)


def test_the_declared_evaluations_are_what_the_reference_counts():
    for algo in WITH_KERNEL:
        for params in _settings(algo):
            for dim in (3, 12):
                res = minimize_many(algo, ["F1", "F9"], dim=dim, agents=7, iterations=9, runs=3,
                                    params=params, backend="numpy")
                key = tuple(sorted(params.items()))
                few, most = declared_evaluations(algo, 7, 9, dim, key)
                assert most == most_evaluations(algo, 7, 9, dim, key)
                counted = {int(e) for r in res for e in r.evaluations}
                assert few <= min(counted) and max(counted) <= most, (algo, params, counted)
                if not find_kernel(algo).capped:  # a fixed count per iteration: reached
                    assert counted == {most}, (algo, params)
    flying = minimize_many("PSO", ["F1"], dim=12, agents=7, iterations=9, runs=3,
                           params={"vmax_mode": "none"}, backend="numpy")[0]
    assert flying.evaluations.max() < 7 * 10  # particles out of the box are not counted


def test_bench_budget_tables_are_the_same_on_numba_and_numpy():
    kw = dict(runs=2, agents=6, seed=4, budget_evals="30xD", instances="1,3")
    cells = {}
    for backend in ("numpy", "numba"):
        spec = bench_spec.make_spec("GWO,FDO,mCOOT", "bbob:f3,bbob:f20", "3", backend=backend,
                                    **kw)
        cells[backend] = bench.run_bench(spec, jobs=1)
    for ref, fast in zip(cells["numpy"], cells["numba"], strict=True):
        assert (ref.best_fitness, ref.curves) == (fast.best_fitness, fast.curves)


def test_a_budget_a_kernel_cannot_count_is_refused_before_the_study(monkeypatch):
    """No registered kernel is in this case (the study's iterations fit the budget, or the
    kernel counts it): a kernel whose runs might spend more than the budget is."""
    spec = {"kind": "benchmark", "algorithms": ["GWO", "FDO"], "functions": ["bbob:f3"],
            "instances": [1], "dims": [3], "runs": 1, "agents": 6, "seed": 3,
            "budget_evals": "40xD", "backend": "numba"}
    assert parse_job_spec(spec).backend == "numba"
    bench_spec.make_spec("GWO,FDO", "bbob:f3", "3", agents=6, backend="numba",
                         budget_evals="40xD")
    monkeypatch.setattr(compiled_run, "most_evaluations", lambda *args: 10**6)
    with pytest.raises(ValueError, match="budget_evals 120: GWO's kernel does not count"):
        parse_job_spec(spec)
    with pytest.raises(InputError, match="GWO's kernel does not count") as err:
        bench_spec.make_spec("GWO,FDO", "bbob:f3", "3", agents=6, backend="numba",
                             budget_evals="40xD")
    assert err.value.field == "--backend"
    assert parse_job_spec({**spec, "backend": "auto"}).backend == "auto"  # runs on numpy
