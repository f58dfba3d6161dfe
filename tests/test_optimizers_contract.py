"""The contract every registered optimizer keeps (parametrized over the registry)."""

from functools import partial

import numpy as np
import pytest

from swarmpath.functions import get_function
from swarmpath.optimizers import (
    ParameterError,
    Problem,
    RunStreams,
    create,
    get_optimizer,
    list_optimizers,
    minimize,
)

# These tests are about the numpy reference (the default backend, "auto", would run the
# compiled kernels where they exist).
minimize = partial(minimize, backend="numpy")

REGISTERED = [
    "PSO", "SSA", "FDO", "GWO", "BA", "MFB", "HPSO-MFB", "COOT", "mCOOT", "ICOOT", "HPO", "IHPO",
    "RFO", "RS", "CMA-ES", "L-SHADE", "jSO",
]


def test_registered_names_are_exactly_the_built_ins():
    assert sorted(list_optimizers()) == sorted(REGISTERED)


@pytest.fixture(scope="module", params=list_optimizers())
def algo(request):
    return request.param


@pytest.mark.parametrize("function", ["F1", "F5", "F8", "F10"])
def test_shapes_finite_bounded_monotone(algo, function):
    res = minimize(algo, function, dim=7, agents=12, iterations=25, runs=3, seed=5)
    f = get_function(function)
    assert res.best_fitness.shape == (3,)
    assert res.best_position.shape == (3, 7)
    assert res.curve.shape == (3, 25)
    assert res.evaluations.shape == (3,)
    assert np.all(np.isfinite(res.best_fitness)) and np.all(np.isfinite(res.curve))
    assert np.all(res.best_position >= f.lower) and np.all(res.best_position <= f.upper)
    assert np.all(np.diff(res.curve, axis=1) <= 0)
    assert np.array_equal(res.curve[:, -1], res.best_fitness)
    # the reported best really is the objective at the reported position
    assert np.allclose(f.evaluate(res.best_position), res.best_fitness, rtol=1e-12, atol=1e-12)
    assert np.all(res.evaluations >= 12 * 25)


def test_positions_stay_in_the_box_every_iteration(algo):
    f = get_function("F2")
    seen: list[np.ndarray] = []

    def objective(X, streams):
        seen.append(X.copy())
        return f.kernel(X)

    problem = Problem(objective, np.full((2, 4), f.lower), np.full((2, 4), f.upper))
    opt = create(algo, problem, agents=10, iterations=30, streams=RunStreams.for_runs(3, 2))
    while not opt.done:
        opt.step()
    X = np.concatenate([x.reshape(2, -1, 4) for x in seen], axis=1)
    assert np.all(X >= f.lower) and np.all(X <= f.upper)
    # Counted evaluations are the points whose values the algorithm used: never more than the
    # objective computed (masked trials are computed for the whole batch but not all are used),
    # at least the initial population, and exactly all of them for single-trial algorithms.
    computed = sum(x.shape[1] for x in seen) * 2
    used = int(opt.evaluations.sum())
    assert 2 * 10 <= used <= computed
    if not getattr(opt, "masked_evaluation", False):
        assert used == computed


def test_same_seed_same_numbers_other_seed_differs(algo):
    kw = dict(dim=6, agents=10, iterations=20, runs=3)
    a = minimize(algo, "F9", seed=7, **kw)
    b = minimize(algo, "F9", seed=7, **kw)
    c = minimize(algo, "F9", seed=8, **kw)
    assert np.array_equal(a.curve, b.curve) and np.array_equal(a.best_position, b.best_position)
    assert not np.array_equal(a.curve, c.curve)


def test_batch_prefix_and_order_invariance(algo):
    kw = dict(dim=5, agents=10, iterations=15, seed=7)
    five = minimize(algo, "F7", runs=5, **kw)  # noisy: the noise is per-run too
    two = minimize(algo, "F7", runs=2, **kw)
    assert np.array_equal(five.curve[:2], two.curve)
    assert np.array_equal(five.best_position[:2], two.best_position)
    picked = minimize(algo, "F7", run_ids=[4, 1], **kw)
    assert np.array_equal(picked.curve, five.curve[[4, 1]])


def test_shifted_is_reproducible_and_shift_shared_across_algorithms(algo):
    a = minimize(algo, "F1", dim=4, agents=8, iterations=5, runs=2, seed=3, shifted=True)
    b = minimize("GWO", "F1", dim=4, agents=8, iterations=5, runs=2, seed=3, shifted=True)
    assert a.shifts is not None and np.array_equal(a.shifts, b.shifts)


def test_converges_on_2d_sphere(algo):
    res = minimize(algo, "F1", dim=2, agents=20, iterations=200, runs=4, seed=1)
    if algo == "RS":  # does not converge: the least of 4,020 uniform points (P(f > 100) ~ e^-31)
        assert np.all(res.best_fitness < 100), res.best_fitness
        return
    # F1 starts around 1e3-1e4 on [-100, 100]^2; every algorithm must get close to 0.
    assert np.all(res.best_fitness < 1e-2), res.best_fitness


def test_bad_parameter_names_the_valid_ones(algo):
    cls = get_optimizer(algo)
    with pytest.raises(ParameterError, match="no parameter 'bogus'"):
        minimize(algo, "F1", dim=2, agents=10, iterations=2, runs=1, params={"bogus": 1})
    for key, default in cls.defaults.items():
        if isinstance(default, bool | str):
            continue
        with pytest.raises(ParameterError, match=key):
            minimize(algo, "F1", dim=2, agents=10, iterations=2, runs=1, params={key: "x"})


def test_steppable_equals_minimize(algo):
    res = minimize(algo, "F3", dim=3, agents=9, iterations=6, runs=2, seed=4)
    f = get_function("F3")
    problem = Problem(lambda X, s: f.kernel(X), np.full((2, 3), f.lower), np.full((2, 3), f.upper))
    opt = create(algo, problem, agents=9, iterations=6, streams=RunStreams.for_runs(4, 2))
    opt.initialize()
    curve = []
    while not opt.done:
        opt.step()
        curve.append(opt.best_fitness.copy())
    assert np.array_equal(np.array(curve).T, res.curve)


def test_unknown_names_list_valid_ones():
    with pytest.raises(KeyError, match=r"valid: .*GWO"):
        minimize("NOPE", "F1")
    with pytest.raises(KeyError, match="valid: F1"):
        minimize("GWO", "F99")
    with pytest.raises(ParameterError, match="dim"):
        minimize("GWO", "F1", dim=0)
    with pytest.raises(ParameterError, match="agents"):
        minimize("GWO", "F1", agents=5000)


def test_buffered_streams_deliver_each_runs_unbuffered_sequence():
    from swarmpath.optimizers.streams import run_generator

    buffered = RunStreams.for_runs(9, [0, 3, 5], block=64)
    draws = [buffered.random(3, 7), buffered.random(50), buffered.random(100), buffered.random(2)]
    for i, r in enumerate([0, 3, 5]):
        alone = run_generator(9, r).random(21 + 50 + 100 + 2)
        assert np.array_equal(np.concatenate([d[i].ravel() for d in draws]), alone)
    # the same run in another batch, with normals interleaved, gives the same numbers
    a, b = RunStreams.for_runs(9, [3]), RunStreams.for_runs(9, [5, 3, 0])
    for s in (a, b):
        s.draws = [s.random(40, 30), s.normal(31, 30), s.random(9000), s.normal(5)]
    for x, y in zip(a.draws, b.draws, strict=True):
        assert np.array_equal(x[0], y[1]) and x.flags.c_contiguous


def test_stream_parts_are_consecutive_draws():
    for block in (0, 50):
        for kind in ("random", "normal"):
            a = RunStreams.for_runs(4, [1, 2], block=block)
            b = RunStreams.for_runs(4, [1, 2], block=block)
            parts = getattr(a, f"{kind}_parts")(3, 4, 5)
            singles = [getattr(b, kind)(4, 5) for _ in range(3)]
            for x, y in zip(parts, singles, strict=True):
                assert np.array_equal(x, y) and x.flags.c_contiguous


def test_chunked_batches_give_the_same_runs(algo, monkeypatch):
    import swarmpath.optimizers.api as api

    kw = dict(dim=4, agents=10, iterations=8, seed=2, shifted=True)
    whole = minimize(algo, "F7", runs=5, **kw)
    calls = []
    monkeypatch.setattr(api, "CHUNK_ELEMENTS", 2 * 10 * 4)  # chunks of two runs
    chunked = minimize(algo, "F7", runs=5, on_iteration=calls.append, **kw)
    assert len(calls) == 8
    for field in ("curve", "best_fitness", "best_position", "evaluations", "shifts"):
        assert np.array_equal(getattr(whole, field), getattr(chunked, field)), field


@pytest.mark.parametrize("shifted", [False, True])
def test_stacked_functions_give_each_functions_own_runs(algo, shifted, monkeypatch):
    import swarmpath.optimizers.api as api
    from swarmpath.optimizers import minimize_many
    from swarmpath.optimizers.problem import StackedProblem

    functions = ["F1", "F9", "F7", "F12", "F8"]  # F7 (noisy) is never stacked with another
    kw = dict(dim=4, agents=10, iterations=8, seed=3, shifted=shifted, run_ids=[4, 0, 2],
              backend="numpy")
    alone = [minimize(algo, f, **kw) for f in functions]
    built = []
    original = StackedProblem.of
    monkeypatch.setattr(StackedProblem, "of", lambda parts: built.append(parts) or original(parts))
    monkeypatch.setattr(api, "CHUNK_ELEMENTS", 5 * 10 * 4)  # chunks of five rows: mixed blocks
    stacked = minimize_many(algo, functions, **kw)
    assert built and all("F7" not in [p.function.name for p in parts] for parts in built)
    assert [r.function for r in stacked] == functions
    whole = minimize_many(algo, functions, chunk_elements=0, **kw)  # F7 still alone
    for one, many, unsplit in zip(alone, stacked, whole, strict=True):
        assert many.run_ids == [4, 0, 2]
        for field in ("curve", "best_fitness", "best_position", "evaluations", "shifts"):
            assert np.array_equal(getattr(one, field), getattr(many, field)), field
            assert np.array_equal(getattr(one, field), getattr(unsplit, field)), field


def test_stacked_functions_with_their_own_runs(algo, monkeypatch):
    """``function_runs`` (a worker stacking leases of several cells): each entry gives the runs
    of ``minimize`` with its own run ids, a function named twice included."""
    import swarmpath.optimizers.api as api
    from swarmpath.optimizers import minimize_many

    functions = ["F1", "F9", "F7", "F1", "F12"]
    runs = [[3, 0], [5], [1, 2, 7], [6, 9], [0, 4, 8]]
    kw = dict(dim=4, agents=10, iterations=8, seed=3, transform="shift", backend="numpy")
    monkeypatch.setattr(api, "CHUNK_ELEMENTS", 4 * 10 * 4)  # chunks of four rows: mixed blocks
    stacked = minimize_many(algo, functions, function_runs=runs, **kw)
    assert sum(r.seconds for r in stacked) > 0
    for f, ids, many in zip(functions, runs, stacked, strict=True):
        one = minimize(algo, f, run_ids=ids, **kw)
        assert many.function == f and many.run_ids == ids
        for field in ("curve", "best_fitness", "best_position", "evaluations", "shifts"):
            assert np.array_equal(getattr(one, field), getattr(many, field)), field


def test_function_runs_must_match_the_functions():
    from swarmpath.optimizers import minimize_many

    with pytest.raises(ParameterError, match="function_runs"):
        minimize_many("PSO", ["F1", "F2"], dim=2, agents=5, iterations=2, function_runs=[[0]])
    with pytest.raises(ParameterError, match="runs"):
        minimize_many("PSO", ["F1"], dim=2, agents=5, iterations=2, function_runs=[[]])


@pytest.mark.parametrize("bad", [-1, 1.5, True, "10"])
def test_bad_chunk_elements_is_named(bad):
    with pytest.raises(ParameterError, match="chunk_elements"):
        minimize("PSO", "F1", dim=2, agents=5, iterations=2, runs=2, chunk_elements=bad)


def test_a_noisy_function_is_refused_in_a_stack():
    from swarmpath.optimizers.problem import BenchmarkProblem, StackedProblem

    parts = [BenchmarkProblem.build(get_function(f), 3, [0, 1], 1, False) for f in ("F1", "F7")]
    with pytest.raises(ValueError, match="noisy"):
        StackedProblem.of(parts)
