"""COOT, mCOOT and ICOOT compiled (``backend="numba"``) against the numpy reference, bit for bit.

``tests/test_compiled.py`` covers every choice parameter on every function at a small size; here
the family's own cases: the numeric parameters, populations where the draws group differently,
the paper's scale (where a last-bit difference has 500 iterations to show), batch splits, and
numpy's power.
"""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from swarmpath.optimizers import ParameterError, minimize, minimize_many
from swarmpath.optimizers.compiled.registry import find_kernel
from swarmpath.optimizers.compiled.ufuncs import power

FAMILY = ("COOT", "mCOOT", "ICOOT")
FIELDS = ("best_fitness", "best_position", "curve", "evaluations", "shifts")


def assert_equal(ref, fast):
    assert (fast.backend, fast.tolerance, ref.backend) == ("numba", 0.0, "numpy")
    for field in FIELDS:
        a, b = getattr(ref, field), getattr(fast, field)
        assert (a is None and b is None) or np.array_equal(a, b), (ref.function, field)


def both(algo, functions, **kw):
    ref = minimize_many(algo, functions, backend="numpy", **kw)
    fast = minimize_many(algo, functions, backend="numba", **kw)
    for a, b in zip(ref, fast, strict=True):
        assert_equal(a, b)


def test_the_family_has_exact_kernels():
    for algo in FAMILY:
        assert find_kernel(algo) is not None and find_kernel(algo).tolerance == 0.0


@pytest.mark.parametrize(
    "algo, params",
    [
        ("COOT", {"leaders": 3}),
        ("COOT", {"leader_fraction": 0.45, "randoms": "vector"}),
        ("mCOOT", {"jump_rate": 1.0, "opposition": "static"}),
        ("mCOOT", {"jump_rate": 0.0, "opposition_init": False}),
        ("ICOOT", {"cell": 0.02, "leader_gain": 1.0}),
        ("ICOOT", {"density_power": 30.0, "random_target": "offset"}),
        ("ICOOT", {"density_power": 1.0, "counter": "paper"}),  # r^-1 is numpy's 1 / r
        ("ICOOT", {"density_power": 0.5, "gbest": "any"}),  # r^0.5 is numpy's sqrt
        ("ICOOT", {"leader_update": "paper", "mirror": "plus", "acc": "one"}),
    ],
)
def test_numeric_parameters(algo, params):
    both(algo, ["F1", "F5", "F7", "F9", "F12"], dim=6, agents=11, iterations=40, runs=2,
         seed=8, params=params, transform="shift")


@pytest.mark.parametrize("algo", FAMILY)
@pytest.mark.parametrize("agents, params", [(2, {}), (4, {"leaders": 2}), (21, {"leaders": 7})])
def test_small_and_odd_populations(algo, agents, params):
    # N = 2 and N = 4 with 2 leaders: as many coots as leaders (ICOOT's two rows of U(0, 2)
    # are then one grouped draw); 21 agents with 7 leaders: 2 coots per leader
    both(algo, ["F1", "F7", "F10"], dim=5, agents=agents, iterations=30, run_ids=[4, 1],
         seed=2, params=params)


def test_mcoot_many_coots():
    # 270 coots jump at a time: their order (ascending picks) decides F7's noise per opposite
    both("mCOOT", ["F7", "F6-floor"], dim=2, agents=300, iterations=6, runs=2, seed=5)


@pytest.mark.parametrize("algo", FAMILY)
def test_the_paper_setting(algo):
    # ICOOT's Table 2 setting: 30-D, 30 agents, 500 iterations; ICOOT's density once used the
    # C library's pow here and left the reference in the last 10% of the iterations
    both(algo, ["F1", "F7", "F10", "F12"], dim=30, agents=30, iterations=500, run_ids=[7, 0],
         seed=1)


@pytest.mark.parametrize("algo", FAMILY)
def test_runs_do_not_depend_on_the_batch(algo):
    kw = dict(dim=7, agents=9, iterations=25, seed=13, transform="shift", backend="numba")
    whole = minimize(algo, "F8", run_ids=[0, 1, 2, 3], **kw)
    for ids in ([2], [3, 0], [1, 2, 0]):
        part = minimize(algo, "F8", run_ids=ids, **kw)
        for i, r in enumerate(ids):
            for field in FIELDS:
                assert np.array_equal(getattr(part, field)[i], getattr(whole, field)[r]), field


@pytest.mark.parametrize("algo", FAMILY)
def test_leaders_must_leave_a_coot(algo):
    with pytest.raises(ParameterError, match=rf"{algo}\.leaders must leave at least one coot"):
        minimize(algo, "F1", dim=2, agents=4, iterations=2, runs=1, params={"leaders": 4},
                 backend="numba")


@njit
def _powers(x, e):
    call = np.zeros(10, dtype=np.int64)
    out = np.empty_like(x)
    for i in range(x.size):
        out[i] = power(x[i], e, call)
    return out


def test_power_is_numpys():
    # on AVX-512 numpy's power is SVML's, which differs from the C library's pow in the last
    # bit for about 5% of these arguments
    rng = np.random.default_rng(0)
    x = np.concatenate([1.0 + rng.random(20_000) * 60.0, rng.random(2_000) * 1e-3, [1.0, 2.0]])
    for e in (2.0, -2.0, -1.0, 0.5, 1.0, 1.5, -30.0, 30.0, 0.0):
        assert np.array_equal(_powers(x, e), x**e), e


def test_the_kernel_cache_is_keyed_by_every_source(tmp_path):
    """numba keys a cached kernel on its own file only; the cache directory is therefore named
    by a hash of all the sources the kernels are compiled from, so that editing, e.g., the
    trigonometry that ``functions.evaluate`` inlines compiles the kernels afresh."""
    import shutil
    from pathlib import Path

    from numba.core import config

    from swarmpath.optimizers import compiled

    assert config.CACHE_DIR == compiled.versioned_cache_dir()
    assert find_kernel("ICOOT").run._cache._cache_path.startswith(config.CACHE_DIR)
    source = Path(compiled.__file__).resolve().parents[2]  # services/swarmpath
    for part in ("optimizers", "functions", "planners", "world"):
        skip = shutil.ignore_patterns("__pycache__")
        shutil.copytree(source / part, tmp_path / part, ignore=skip)
    copy = tmp_path / "optimizers" / "compiled"
    before = compiled.versioned_cache_dir(copy)
    assert Path(before).name == Path(config.CACHE_DIR).name  # the same sources, the same name
    trig = tmp_path / "functions" / "trig.py"
    trig.write_text(trig.read_text() + "\n# edited\n")
    edited = compiled.versioned_cache_dir(copy)
    assert edited != before
    score = tmp_path / "planners" / "compiled_score.py"  # the planners' kernels too
    score.write_text(score.read_text() + "\n# edited\n")
    assert compiled.versioned_cache_dir(copy) != edited
    edited = compiled.versioned_cache_dir(copy)
    path = tmp_path / "world" / "optimum_compiled.py"  # and the shortest path's
    path.write_text(path.read_text() + "\n# edited\n")
    assert compiled.versioned_cache_dir(copy) != edited
