"""HPO/IHPO's sequential update (the authors' agent-by-agent sweep, the default since issue 10)."""

from functools import partial

import numpy as np
import pytest

from swarmpath.optimizers import Problem, RunStreams, create, get_optimizer, minimize
from swarmpath.optimizers.registry import list_optimizers
from swarmpath.optimizers.streams import OPTIMIZER, run_generator

# These tests are about the numpy reference (the default backend, "auto", would run the
# compiled kernels where they exist).
minimize = partial(minimize, backend="numpy")


@pytest.mark.parametrize("algorithm", ["HPO", "IHPO"])
def test_sequential_is_reproducible_batch_invariant_and_counted(algorithm):
    kw = dict(dim=5, agents=10, iterations=15, seed=4, params={"update": "sequential"})
    five = minimize(algorithm, "F7", runs=5, **kw)
    two = minimize(algorithm, "F7", runs=2, **kw)
    assert np.array_equal(five.curve[:2], two.curve)
    assert np.all(five.evaluations == 10 * (15 + 1))
    default = minimize(algorithm, "F7", runs=2, dim=5, agents=10, iterations=15, seed=4)
    assert np.array_equal(default.curve, two.curve)
    sync = minimize(algorithm, "F7", runs=2, dim=5, agents=10, iterations=15, seed=4,
                    params={"update": "synchronous"})
    assert not np.array_equal(sync.curve, two.curve)


def test_sequential_reaches_what_the_synchronous_update_misses():
    """F6 at 30 dims: the published HPO column (1.5e-11) needs the immediate target update."""
    kw = dict(dim=30, agents=30, iterations=500, runs=4, seed=1)
    sync = minimize("HPO", "F6", params={"update": "synchronous"}, **kw)
    seq = minimize("HPO", "F6", **kw)
    assert np.median(seq.best_fitness) < 1e-6 < 1.0 < np.median(sync.best_fitness)


def test_sequential_is_not_origin_bound():
    kw = dict(dim=30, agents=30, iterations=500, runs=4, seed=1, shifted=True)
    seq = minimize("HPO", "F1", **kw)
    sync = minimize("HPO", "F1", params={"update": "synchronous"}, **kw)
    assert np.median(seq.best_fitness) < 1e-2 < 1e2 < np.median(sync.best_fitness)


# --------------------------------------------------------------------- the batched sweep (R = 1)
SEQUENTIAL = [name for name in list_optimizers()
              if "sequential" in get_optimizer(name).choices.get("update", ())]


def _bumpy(X, streams):
    """A multimodal objective of plain arithmetic (rowwise to the last bit)."""
    frac = X * 3.0 - np.floor(X * 3.0)
    return ((X - 0.3) ** 2 * (1.0 + frac)).sum(axis=-1)


def _counted(calls):
    def objective(X, streams):
        calls.append(X.shape[1])
        return _bumpy(X, streams)
    return objective


def _sweep_pair(name, params, agents=30, iterations=12, dim=3, seed=7):
    out = []
    for rowwise in (False, True):
        calls: list[int] = []
        problem = Problem(_counted(calls), np.full((1, dim), -2.0), np.full((1, dim), 3.0),
                          rowwise=rowwise)
        opt = create(name, problem, agents, iterations,
                     RunStreams([run_generator(seed, 0, OPTIMIZER)]), params)
        trace = []
        while not opt.done:
            opt.step()
            trace.append((opt.X.copy(), opt.best_fitness.copy(), opt.best_position.copy(),
                          opt.evaluations.copy()))
        out.append((trace, calls))
    return out


@pytest.mark.parametrize("name", SEQUENTIAL)
@pytest.mark.parametrize("params", [
    {}, {"beta": 0.6}, {"hunter": "centre", "beta": 0.4}, {"hunter": "relative", "beta": 0.3},
    {"prey_step": "2Z", "prey_angle": "from_z"},
])
def test_batched_sweep_gives_the_loops_values(name, params):
    """A rowwise objective lets one run's sweep evaluate blocks of agents at once; every
    iteration's population, best point and evaluation count equal the agent-by-agent loop's,
    bit for bit, with fewer objective calls."""
    if name != "HPO":
        params = {**params, "alpha_on": "literal" if len(params) % 2 else "displacement"}
    (loop, loop_calls), (batched, batched_calls) = _sweep_pair(name, params)
    for a, b in zip(loop, batched, strict=True):
        for x, y in zip(a, b, strict=True):
            assert np.array_equal(x, y)
    assert len(loop_calls) == 1 + 12 * 30  # the loop: the first population, then agent by agent
    assert len(batched_calls) < len(loop_calls) and max(batched_calls[1:]) > 1


def test_several_runs_keep_the_loop():
    """The batched sweep is for one run; a batch of runs steps agent by agent (a block would be
    cut at the first improvement of any run)."""
    calls: list[int] = []
    problem = Problem(_counted(calls), np.full((2, 2), -2.0), np.full((2, 2), 3.0), rowwise=True)
    streams = RunStreams([run_generator(3, r, OPTIMIZER) for r in range(2)])
    opt = create("HPO", problem, 10, 2, streams)
    opt.step()
    assert calls == [10] + [1] * 10
