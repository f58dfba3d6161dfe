"""SSA's and FDO's compiled kernels beyond the registry-wide test (tests/test_compiled.py):
parameter combinations, the Table 2 shape, the shapes where OpenBLAS adds out of index order,
and numpy's own loops (compiled/ufuncs.py) that make them equal to the last bit."""

from __future__ import annotations

from itertools import product

import numpy as np
import pytest

from swarmpath.functions import list_functions
from swarmpath.optimizers import ParameterError, get_optimizer, minimize, minimize_many
from swarmpath.optimizers.compiled import find_kernel
from swarmpath.optimizers.compiled.ssa import sweep_is_matmul
from swarmpath.optimizers.compiled.ufuncs import cbrt_inplace, matmul_into, numpy_loop

FIELDS = ("best_fitness", "best_position", "curve", "evaluations", "shifts")


def assert_equal_runs(ref, fast):
    assert (ref.backend, fast.backend, fast.tolerance) == ("numpy", "numba", 0.0)
    for field in FIELDS:
        a, b = getattr(ref, field), getattr(fast, field)
        assert (a is None and b is None) or np.array_equal(a, b), (ref.function, field)


def both(algo, functions, **kw):
    ref = minimize_many(algo, functions, backend="numpy", **kw)
    fast = minimize_many(algo, functions, backend="numba", **kw)
    for a, b in zip(ref, fast, strict=True):
        assert_equal_runs(a, b)


def combinations(algo):
    """Every combination of the algorithm's choice parameters, from its registry entry."""
    choices = get_optimizer(algo).choices
    for values in product(*choices.values()):
        yield dict(zip(choices, values, strict=True))


@pytest.mark.parametrize("algo", ["SSA", "FDO"])
def test_every_combination_of_choices_is_the_reference(algo):
    assert find_kernel(algo).tolerance == 0.0
    for k, params in enumerate(combinations(algo)):
        both(algo, ["F1", "F7", "F8", "F10"], dim=6, agents=7, iterations=15, seed=20 + k,
             params=params, transform=("none", "shift")[k % 2], run_ids=[4, 1])


def test_fdo_weight_factor_is_the_reference():
    for wf, rule in ((0.3, "threshold"), (1.0, "ratio")):
        both("FDO", ["F1", "F5", "F9"], dim=5, agents=6, iterations=15, seed=2, runs=2,
             params={"weight_factor": wf, "weight_rule": rule})


@pytest.mark.parametrize("algo", ["SSA", "FDO"])
def test_table2_shape_over_every_function(algo):
    """30 dims, 30 agents (the ICOOT paper's Table 2), fewer iterations."""
    both(algo, list_functions(), dim=30, agents=30, iterations=25, seed=1, run_ids=[0, 999])


@pytest.mark.parametrize("dim", [2, 30, 34, 100])
def test_ssa_followers_where_blas_adds_out_of_index_order(dim):
    """OpenBLAS adds the last 1-4 columns past a multiple of 8 out of index order here: the
    literal sweep would differ in the last bits; the kernel then calls numpy's matmul loop."""
    if dim in (34, 100):
        assert not sweep_is_matmul(15, dim)  # the shapes that keep the matmul path tested
    for leaders in get_optimizer("SSA").choices["leaders"]:
        both("SSA", ["F1", "F12"], dim=dim, agents=30, iterations=20, seed=5, runs=2,
             params={"leaders": leaders}, transform="shift")


def test_fdo_runs_are_the_same_alone_and_in_any_batch():
    kw = dict(dim=4, agents=5, iterations=30, seed=8, backend="numba",
              params={"bound": "author"})
    whole = minimize("FDO", "F7", run_ids=[0, 1, 2, 3], **kw)
    for ids in ([2], [3, 0]):
        part = minimize("FDO", "F7", run_ids=ids, **kw)
        for i, r in enumerate(ids):
            assert np.array_equal(part.curve[i], whole.curve[r])
    for seed in (8, 9):
        both("FDO", ["F7"], dim=4, agents=5, iterations=30, seed=seed, run_ids=[3, 0],
             params={"bound": "author"})


def test_unsupported_values_are_refused_by_name():
    for algo, params, name in (("SSA", {"leaders": "all"}, "leaders"),
                               ("FDO", {"trials": "three"}, "trials"),
                               ("FDO", {"weight_factor": 2.0}, "weight_factor")):
        with pytest.raises(ParameterError, match=name):
            minimize(algo, "F1", dim=2, agents=4, iterations=2, runs=1, params=params,
                     backend="numba")


def test_numpy_cbrt_loop_is_np_cbrt_bit_for_bit():
    rng = np.random.default_rng(3)
    x = np.concatenate([rng.standard_normal(20_000) ** 2, rng.standard_normal(1000) * 1e300,
                        [0.0, -0.0, 5e-324, 1e-310, np.inf, -np.inf, np.nan, 8.0, -27.0]])
    for n in (1, 7, 8, 9, 33, x.size):
        got = x[:n].copy()
        cbrt_inplace(got, np.empty(5, dtype=np.int64))
        np.testing.assert_array_equal(got, np.cbrt(x[:n]))


def test_numpy_matmul_loop_is_np_matmul_bit_for_bit():
    rng = np.random.default_rng(4)
    call = np.empty(16, dtype=np.int64)
    for n, k, m in ((15, 16, 30), (15, 16, 34), (1, 3, 2), (29, 30, 100), (4, 1, 5)):
        A = rng.standard_normal((n, k))
        B = rng.standard_normal((k + 3, m))[2:-1]  # rows of a larger array
        out = np.empty((n, m))
        matmul_into(A, B, out, call)
        assert np.array_equal(out, np.matmul(A, B)), (n, k, m)


def test_numpy_loop_refuses_what_it_cannot_find():
    with pytest.raises(RuntimeError, match="no ii loop"):
        numpy_loop(np.cbrt, "ii")
    with pytest.raises(RuntimeError, match="cbrt takes 2 types"):
        numpy_loop(np.cbrt, "ddd")
