"""The kernels of HPO, IHPO, BA, MFB, HPSO-MFB and RFO beyond the registry-wide test
(tests/test_compiled.py, which tries each choice value alone): combinations of the choices that
meet in one code path, the Table 2 shape (30 agents: numpy's pairwise sums past 8 numbers),
and the edge sizes of each algorithm."""

from __future__ import annotations

from itertools import product

import numpy as np
import pytest

from swarmpath.functions import list_functions
from swarmpath.optimizers import get_optimizer, minimize_many
from swarmpath.optimizers.compiled import find_kernel

FIELDS = ("best_fitness", "best_position", "curve", "evaluations", "shifts")
ALGORITHMS = ["HPO", "IHPO", "BA", "MFB", "HPSO-MFB", "RFO"]


def both(algo, functions, **kw):
    ref = minimize_many(algo, functions, backend="numpy", **kw)
    fast = minimize_many(algo, functions, backend="numba", **kw)
    for a, b in zip(ref, fast, strict=True):
        assert (a.backend, b.backend, b.tolerance) == ("numpy", "numba", 0.0)
        for field in FIELDS:
            x, y = getattr(a, field), getattr(b, field)
            assert (x is None and y is None) or np.array_equal(x, y), (algo, a.function, field)


def grid(algo, keys):
    """Every combination of the choice parameters ``keys`` of ``algo``."""
    choices = get_optimizer(algo).choices
    for values in product(*(choices[k] for k in keys)):
        yield dict(zip(keys, values, strict=True))


COMBINATIONS = {
    "IHPO": ("alpha_on", "alpha_branches", "beta_draw", "hunter"),
    "HPO": ("prey_step", "prey_angle", "hunter", "update"),
    "BA": ("updates", "local_walk", "acceptance", "velocity"),
    "MFB": ("beta_time", "beta_r", "beta_per", "accept", "move", "update"),
    "HPSO-MFB": ("split", "restart", "best", "walk_scale"),
    "RFO": ("alpha_draw", "kappa_draw", "reproduction"),
}
FLAGS = {"RFO": [{"local_greedy": False}, {"local_greedy": True}]}


@pytest.mark.parametrize("algo", ALGORITHMS)
def test_combinations_of_choices_are_the_reference(algo):
    assert find_kernel(algo) is not None
    settings = product(grid(algo, COMBINATIONS[algo]), FLAGS.get(algo, [{}]))
    for k, (params, flags) in enumerate(settings):
        both(algo, ["F1", "F7", "F8"], dim=4, agents=7, iterations=9, seed=30 + k,
             params={**params, **flags}, transform=("none", "shift")[k % 2], run_ids=[3, 1])


@pytest.mark.parametrize("algo", ALGORITHMS)
def test_table2_shape_over_every_function(algo):
    """30 dims, 30 agents (the ICOOT paper's Table 2), fewer iterations."""
    both(algo, list_functions(), dim=30, agents=30, iterations=12, seed=1, run_ids=[0, 999])


def test_edge_sizes():
    both("RFO", ["F1", "F7"], dim=1, agents=2, iterations=8, seed=3, runs=2)  # d = 1, no births
    both("RFO", ["F5"], dim=2, agents=40, iterations=6, seed=4, runs=1,
         params={"replace_fraction": 0.0, "notice": 1.0})  # nobody moves, nobody is replaced
    both("HPSO-MFB", ["F1", "F10"], dim=3, agents=3, iterations=11, seed=5, runs=2,
         params={"particles": 7, "pso_iterations": 4})  # more particles than bats
    both("HPSO-MFB", ["F9"], dim=3, agents=4, iterations=10, seed=6, runs=2,
         params={"split": "per_particle", "restart": "cold", "pso_iterations": 3})
    both("MFB", ["F1"], dim=2, agents=1, iterations=5, seed=7, runs=2)  # one bat
    both("MFB", ["F11"], dim=5, agents=140, iterations=3, seed=8, runs=1)  # pairwise halves
    both("BA", ["F12"], dim=5, agents=130, iterations=3, seed=9, runs=1)
    both("IHPO", ["F1"], dim=2, agents=1, iterations=6, seed=10, runs=2, params={"beta": 1.0})
    both("HPO", ["F13"], dim=6, agents=5, iterations=7, seed=11, runs=2,
         params={"beta": 1.0, "hunter": "relative"})  # every agent hunts


def test_four_sub_swarms_give_a_run_its_numbers_in_any_batch():
    """The reference's mean loudness per sub-swarm was a matmul whose order changed with the
    batch at 4 sub-swarms (2 runs on); the kernel runs one run at a time."""
    kw = dict(dim=3, agents=4, iterations=10, seed=6, backend="numpy",
              params={"split": "per_particle", "restart": "cold", "pso_iterations": 3})
    whole = minimize_many("HPSO-MFB", ["F9"], run_ids=[0, 1, 2], **kw)[0]
    for r in range(3):
        alone = minimize_many("HPSO-MFB", ["F9"], run_ids=[r], **kw)[0]
        for field in FIELDS[:4]:
            assert np.array_equal(getattr(alone, field)[0], getattr(whole, field)[r]), field


def test_pairwise_sum_is_numpys_sum_at_every_size():
    from swarmpath.optimizers.compiled.functions import pairwise_sum

    rng = np.random.default_rng(1)
    for n in [*range(1, 300), 513, 1000, 1024, 5000]:
        a = rng.standard_normal(n + 3) * 10.0 ** rng.uniform(-6, 6, n + 3)
        assert pairwise_sum(a, 3, n) == np.sum(a[3:]), n
