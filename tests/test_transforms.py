"""Function transforms (none, shift, rotate, shift+rotate): per-run draws, the optimum kept, the
reproducibility contract for every transform and optimizer."""

from functools import partial

import numpy as np
import pytest

from swarmpath.functions import get_function, list_functions
from swarmpath.functions.transforms import TRANSFORMS, random_rotation
from swarmpath.optimizers import ParameterError, RunStreams, list_optimizers, minimize
from swarmpath.optimizers.problem import BenchmarkProblem

# These tests are about the numpy reference (the default backend, "auto", would run the
# compiled kernels where they exist).
minimize = partial(minimize, backend="numpy")


@pytest.mark.parametrize("transform", TRANSFORMS)
@pytest.mark.parametrize("algorithm", list_optimizers())
def test_run_alone_equals_run_in_a_batch(algorithm, transform):
    kw = dict(dim=5, agents=10, iterations=8, seed=3, transform=transform)
    batch = minimize(algorithm, "F9", runs=4, **kw)
    alone = minimize(algorithm, "F9", run_ids=[2], **kw)
    assert np.array_equal(batch.curve[2:3], alone.curve)
    assert np.array_equal(batch.best_position[2:3], alone.best_position)
    assert batch.transform == transform


@pytest.mark.parametrize("transform", TRANSFORMS)
@pytest.mark.parametrize("name", list_functions())
def test_the_minimum_stays_where_the_transform_puts_it(name, transform):
    f = get_function(name)
    dim = 6
    problem = BenchmarkProblem.build(f, dim, [0, 5, 9], seed=2, transform=transform)
    m = problem.optimum()
    assert np.all((m >= f.lower) & (m <= f.upper))
    value = problem.objective(m[:, None, :], RunStreams.for_runs(2, [0, 5, 9]))[:, 0]
    f_min = f.f_min_for(dim)
    if f.noisy:  # plus U[0, 1) noise
        assert np.all((value >= f_min) & (value < f_min + 1.0))
    else:
        assert np.allclose(value, f_min, rtol=0, atol=1e-9 * (1 + abs(f_min)))
    # and nothing in the box is lower (random points; F7's noise is non-negative)
    x = np.random.default_rng(0).uniform(f.lower, f.upper, (3, 200, dim))
    others = problem.objective(x, RunStreams.for_runs(2, [0, 5, 9]))
    assert np.all(others >= f_min - 1e-9 * (1 + abs(f_min)))


def test_rotations_are_orthogonal_per_run_and_shared_between_transforms():
    f = get_function("F9")
    rot = BenchmarkProblem.build(f, 7, [0, 1, 2], seed=4, transform="rotate")
    both = BenchmarkProblem.build(f, 7, [2, 0], seed=4, transform="shift+rotate")
    shift = BenchmarkProblem.build(f, 7, [2, 0], seed=4, transform="shift")
    assert rot.rotations is not None and both.rotations is not None
    for q in rot.rotations:
        assert np.allclose(q @ q.T, np.eye(7), atol=1e-12)
    assert not np.allclose(rot.rotations[0], rot.rotations[1])
    assert np.array_equal(both.rotations, rot.rotations[[2, 0]])
    assert both.shifts is not None and np.array_equal(both.shifts, shift.shifts)
    assert rot.shifts is None and shift.rotations is None
    other_seed = BenchmarkProblem.build(f, 7, [0], seed=5, transform="rotate")
    assert other_seed.rotations is not None
    assert not np.allclose(other_seed.rotations[0], rot.rotations[0])


def test_rotation_turns_a_separable_function_and_leaves_a_sphere_alone():
    x = np.random.default_rng(1).uniform(-5, 5, (1, 50, 10))
    streams = RunStreams.for_runs(1, 1)

    def values(name, transform):
        problem = BenchmarkProblem.build(get_function(name), 10, [0], 1, transform)
        return problem.objective(x * get_function(name).upper / 5, streams)

    assert np.allclose(values("F1", "rotate"), values("F1", "none"), rtol=1e-12)
    assert not np.allclose(values("F9", "rotate"), values("F9", "none"), rtol=1e-3)


def test_haar_rotation_has_determinant_of_both_signs():
    dets = [np.linalg.det(random_rotation(3, np.random.default_rng(s))) for s in range(40)]
    assert np.allclose(np.abs(dets), 1.0)
    assert min(dets) < 0 < max(dets)


def test_shifted_is_an_alias_and_contradictions_are_refused():
    kw = dict(dim=4, agents=8, iterations=5, runs=2, seed=1)
    a = minimize("GWO", "F1", shifted=True, **kw)
    b = minimize("GWO", "F1", transform="shift", **kw)
    assert np.array_equal(a.curve, b.curve) and a.transform == "shift"
    with pytest.raises(ParameterError, match="transform"):
        minimize("GWO", "F1", shifted=True, transform="rotate", **kw)
    with pytest.raises(ParameterError, match="transform must be one of"):
        minimize("GWO", "F1", transform="spin", **kw)


def test_a_function_shifted_by_the_caller_keeps_its_shift():
    f = get_function("F1").shifted(np.full(4, 30.0))
    res = minimize("GWO", f, dim=4, agents=20, iterations=100, runs=2, seed=1)
    assert np.allclose(res.best_position, 30.0, atol=1.0)
