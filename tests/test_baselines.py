"""The strong baselines (RS, CMA-ES, L-SHADE, jSO): behaviour beyond the registry's contract."""

import numpy as np
from scipy import stats

from swarmpath.optimizers import Problem, RunStreams, create


def _recording(fn, runs, dim, lower=-5.0, upper=5.0):
    seen = []

    def objective(X, streams):
        seen.append(X.copy())
        return fn(X)

    problem = Problem(objective, np.full((runs, dim), lower), np.full((runs, dim), upper))
    return problem, seen


def test_random_search_draws_uniform_points_and_reports_their_minimum():
    sphere = lambda X: np.sum(X**2, axis=-1)  # noqa: E731
    problem, seen = _recording(sphere, runs=3, dim=4, lower=-2.0, upper=6.0)
    opt = create("RS", problem, agents=25, iterations=40, streams=RunStreams.for_runs(11, 3))
    while not opt.done:
        opt.step()
    X = np.concatenate(seen, axis=1)  # (3, 25 * 41, 4)
    assert X.shape[1] == 25 * 41 and np.all(opt.evaluations == 25 * 41)
    assert np.allclose(opt.best_fitness, sphere(X).min(axis=1))
    # uniform on [-2, 6] in every coordinate (Kolmogorov-Smirnov, each run and coordinate)
    for r in range(3):
        for j in range(4):
            u = (X[r, :, j] + 2.0) / 8.0
            assert stats.kstest(u, "uniform").pvalue > 1e-4
    # the runs are independent streams: no two runs drew the same points
    assert not np.allclose(X[0], X[1])


def test_cmaes_restarts_leave_each_run_its_own_numbers():
    """IPOP restarts happen at different times in different runs (lambda then differs): a run
    alone, in a batch, reordered and stacked with another function gives the same numbers."""
    from swarmpath.optimizers import minimize, minimize_many

    kw = dict(dim=3, agents=7, iterations=400, seed=4)
    batch = minimize("CMA-ES", "F9", runs=4, **kw)
    for r in (0, 3):
        alone = minimize("CMA-ES", "F9", run_ids=[r], **kw)
        assert np.array_equal(alone.curve[0], batch.curve[r])
    picked = minimize("CMA-ES", "F9", run_ids=[2, 0], **kw)
    assert np.array_equal(picked.curve, batch.curve[[2, 0]])
    stacked = minimize_many("CMA-ES", ["F9", "F10"], runs=4, **kw)[0]
    assert np.array_equal(stacked.curve, batch.curve)
    assert np.all(batch.evaluations == 7 * 401)


def test_cmaes_ipop_restarts_with_doubled_population():
    from swarmpath.functions import get_function
    from swarmpath.optimizers import BenchmarkProblem

    fn = get_function("F9")  # Rastrigin: converges to local minima, so it restarts
    problem = BenchmarkProblem.build(fn, 4, [0, 1, 2], seed=2)
    opt = create("CMA-ES", problem, agents=10, iterations=600, streams=RunStreams.for_runs(2, 3))
    lam0 = 4 + int(3 * np.log(4))
    while not opt.done:
        opt.step()
    assert np.all(opt.restarts >= 1)
    assert np.array_equal(opt.lam, lam0 * 2 ** opt.restarts)
    none = create("CMA-ES", problem, agents=10, iterations=600,
                  streams=RunStreams.for_runs(2, 3), params={"restarts": "none"})
    while not none.done:
        none.step()
    # without restarts a run ends at its first stop: fewer evaluations, the same start
    assert np.all(none.evaluations < 10 * 601) and np.all(none.restarts == 0)


def test_cmaes_solves_rotated_ill_conditioned_functions_where_swarms_stall():
    from swarmpath.optimizers import minimize

    res = minimize("CMA-ES", "bbob:f10", dim=10, agents=10, iterations=1500, runs=3, seed=1)
    assert np.all(res.best_fitness < 1e-8)  # rotated ellipsoid, condition 1e6
    gwo = minimize("GWO", "bbob:f10", dim=10, agents=10, iterations=1500, runs=3, seed=1)
    assert np.all(gwo.best_fitness > 1e2)


def test_the_quantum_does_not_change_the_algorithm():
    """agents is only the evaluation quantum of a generational algorithm: the same planned
    budget cut into other iterations gives the same runs (the curve is sampled elsewhere)."""
    from swarmpath.optimizers import minimize

    for algo in ("CMA-ES", "L-SHADE", "jSO"):
        a = minimize(algo, "F10", dim=5, agents=20, iterations=99, runs=2, seed=3)  # 2,000
        b = minimize(algo, "F10", dim=5, agents=50, iterations=39, runs=2, seed=3)  # 2,000
        assert np.array_equal(a.best_fitness, b.best_fitness), algo
        assert np.array_equal(a.curve[:, 3::5], b.curve[:, 0::2]), algo  # at 100, 200, ...


def test_linear_population_size_reduction_follows_the_evaluations():
    problem, _ = _recording(lambda X: np.sum(X**2, axis=-1), runs=2, dim=10)
    opt = create("L-SHADE", problem, agents=60, iterations=199, streams=RunStreams.for_runs(1, 2))
    sizes = []
    while not opt.done:
        opt.step()
        sizes.append((int(opt.spent[0]), opt.size))
    assert opt.n_init == 180 and opt.planned == 12_000
    assert np.all(opt.evaluations == 12_000)
    for spent, size in sizes[5:]:  # after each generation N = round(180 - 176 NFE / 12,000)
        assert abs(size - (180 - 176 * spent / 12_000)) <= 1 + 176 * 180 / 12_000
    assert opt.size == 4 and np.all(np.diff([s for _, s in sizes]) <= 0)
    jso = create("jSO", problem, agents=60, iterations=199, streams=RunStreams.for_runs(1, 2))
    jso.initialize()
    assert jso.n_init == round(25 * np.log(10) * np.sqrt(10)) == 182


def test_shade_family_bounds_rule_and_archive():
    problem, seen = _recording(lambda X: np.sum((X - 4.9) ** 2, axis=-1), runs=3, dim=6)
    opt = create("L-SHADE", problem, agents=40, iterations=80, streams=RunStreams.for_runs(5, 3))
    while not opt.done:
        opt.step()
    X = np.concatenate(seen, axis=1)
    assert X.min() >= -5 and X.max() <= 5  # midway between parent and bound, never outside
    assert np.all(opt.best_fitness < 1e-3)  # optimum near the upper bound is reached
    assert np.all(opt.archive_count <= opt.archive_size)
    assert opt.archive_size == int(opt.size * 2.6)
