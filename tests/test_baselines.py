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
