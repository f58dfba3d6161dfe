"""MFB and HPSO-MFB (Ajeil et al. 2020): the decisions of docs/algorithms.md."""

from functools import partial

import numpy as np
import pytest

from swarmpath.functions import get_function
from swarmpath.optimizers import Problem, RunStreams, create, get_optimizer, minimize

# These tests are about the numpy reference (the default backend, "auto", would run the
# compiled kernels where they exist).
minimize = partial(minimize, backend="numpy")

SPHERE = get_function("F1")


def sphere_problem(runs, dim, seen=None, low=-100.0, high=100.0):
    def objective(X, streams):
        if seen is not None:
            seen.append(X.copy())
        return SPHERE.kernel(X)

    return Problem(objective, np.full((runs, dim), low), np.full((runs, dim), high))


def run(algo, problem, agents, iterations, seed=1, **params):
    opt = create(algo, problem, agents, iterations, RunStreams.for_runs(seed, problem.runs), params)
    opt.initialize()
    return opt


def random_search(function, dim, evaluations, runs, seed):
    f = get_function(function)
    g = np.random.Generator(np.random.PCG64(seed))
    X = g.uniform(f.lower, f.upper, (runs, evaluations, dim))
    return f.kernel(X).min(axis=1)


# ---------------------------------------------------------------------------- velocity sign (eq 11)
def test_literal_velocity_sign_pushes_candidates_onto_the_box():
    """Eq 11 as printed, v += (z - z*) f with f >= 0, diverges: with eq 12 applied literally
    (move="always") the flight candidates end on the box faces, while the pull toward z* keeps
    them inside as long as f <= 4 (the first 40 % of the run with f = 10 t/T)."""
    T = 50
    pinned = {}
    for velocity in ("toward", "literal"):
        seen: list[np.ndarray] = []
        opt = run("MFB", sphere_problem(4, 5, seen), 20, T, velocity=velocity, move="always")
        while not opt.done:
            opt.step()
        C = np.stack(seen[1 : 1 + int(0.4 * T)])  # candidates of iterations 1..0.4T
        pinned[velocity] = float((np.abs(C) == 100.0).mean())
    assert pinned["literal"] > 0.3
    assert pinned["toward"] < pinned["literal"] / 3


def test_literal_velocity_sign_does_worse():
    kw = dict(dim=20, agents=20, iterations=100, runs=10, seed=2)
    for function, factor in (("F1", 4.0), ("F10", 1.5)):  # medians 46 vs 372, 6.0 vs 14.6
        toward = minimize("MFB", function, **kw).best_fitness
        literal = minimize("MFB", function, params={"velocity": "literal"}, **kw).best_fitness
        assert np.median(literal) > factor * np.median(toward), (function, toward, literal)
        assert np.sum(toward < literal) >= 8


# -------------------------------------------------------------------------- eqs 14-15
def test_loudness_decays_and_pulse_rate_rises_every_iteration():
    opt = run("MFB", sphere_problem(3, 4), 10, 30, alpha=0.8, gamma=0.5)
    A0, r0 = opt.A0.copy(), opt.r0.copy()
    assert np.all((A0 >= 1) & (A0 <= 2)) and np.all((r0 >= 0) & (r0 <= 1))
    assert np.all(opt.r == 0)  # eq 15 at t = 0
    for t in range(1, 31):
        opt.step()
        np.testing.assert_allclose(opt.A, A0 * 0.8**t)  # eq 14
        np.testing.assert_allclose(opt.r, r0 * (1 - np.exp(-0.5 * t)))  # eq 15


def test_loudness_and_pulse_rate_change_only_on_acceptance():
    opt = run("MFB", sphere_problem(3, 4), 10, 40, update="accept", accept="own")
    A0, r0 = opt.A0.copy(), opt.r0.copy()
    accepted = np.zeros(A0.shape, dtype=int)
    for t in range(1, 41):
        A_before, r_before, X_before = opt.A.copy(), opt.r.copy(), opt.X.copy()
        opt.step()
        changed = opt.A != A_before
        # refused bats keep position, loudness and pulse rate; accepted ones get eqs 14-15
        assert np.array_equal(opt.X[~changed], X_before[~changed])
        assert np.array_equal(opt.r[~changed], r_before[~changed])
        np.testing.assert_allclose(opt.r[changed], (r0 * (1 - np.exp(-0.9 * t)))[changed])
        assert np.all(opt.r >= r_before)  # the pulse rate only rises
        accepted += changed
    np.testing.assert_allclose(opt.A, A0 * 0.9**accepted)
    assert 0 < accepted.mean() < 40
    assert np.all(opt.r <= r0)


# ----------------------------------------------------------------------- HPSO-MFB layer
def test_pso_layer_changes_alpha_gamma_inside_its_box():
    T, K = 60, 12  # pso_iterations=5 -> epochs of 12 iterations
    opt = run("HPSO-MFB", sphere_problem(4, 6), 20, T, alpha_low=0.5, gamma_high=0.8)
    history = [opt.pos.copy()]
    while not opt.done:
        A_before, alpha = opt.A.copy(), opt.pos[:, opt.group, 0]
        opt.step()
        if opt.t % K:  # inside an epoch the MFB layer decays A with its particle's alpha
            np.testing.assert_allclose(opt.A, A_before * alpha)
        history.append(opt.pos.copy())
    H = np.stack(history)  # (T + 1, R, P, 2)
    assert np.all(H[..., 0] >= 0.5) and np.all(H[..., 0] <= 0.999)
    assert np.all(H[..., 1] >= 0.01) and np.all(H[..., 1] <= 0.8)
    moved = np.any(H[1:] != H[:-1], axis=(1, 2, 3))
    assert np.array_equal(np.flatnonzero(moved) + 1, np.arange(K, T, K))  # only at epoch ends
    assert np.all(np.abs(H[-1] - H[0]).max(axis=(1, 2)) > 0.01)  # every run retuned them
    assert np.all(np.isfinite(opt.gbest_f)) and np.all(opt.gbest_f >= opt.best_fitness)


@pytest.mark.parametrize(
    "params, bats",
    [
        ({}, 20),
        ({"split": "per_particle"}, 100),
        ({"restart": "cold"}, 20),
        ({"particles": 50}, 20),
    ],
)
def test_hpso_counts_every_evaluation(params, bats):
    seen: list[np.ndarray] = []
    opt = run("HPSO-MFB", sphere_problem(2, 3, seen), 20, 23, **params)
    while not opt.done:
        opt.step()
    assert all(x.shape[1] == bats for x in seen) and len(seen) == 24
    assert np.all(opt.evaluations == bats * 24)
    assert opt.G == min(params.get("particles", 5), 20)


def test_cold_restart_redraws_the_bats():
    seen: list[np.ndarray] = []
    opt = run("HPSO-MFB", sphere_problem(2, 3, seen), 20, 20, restart="cold", best="swarm")
    while not opt.done:
        opt.step()
        if opt.t in (5, 9, 13, 17):  # first iterations of epochs 2-5 (epochs of 4 iterations)
            assert np.array_equal(opt.X, seen[-1])  # a fresh population, no MFB move
            assert np.all(np.abs(seen[-1]) < 100)  # uniform draws, not clipped flights
            for g in range(opt.G):  # each sub-swarm's z* is the best of its new bats
                assert np.array_equal(opt.Fb[:, g], opt.F[:, opt.group == g].min(axis=1))
            assert np.array_equal(opt.A, opt.A0) and np.all(opt.V == 0) and np.all(opt.r == 0)


# ----------------------------------------------------------------------- alternatives
def _alternatives(algo):
    cls = get_optimizer(algo)
    for key, values in cls.choices.items():
        for value in values:
            if value != cls.defaults[key]:
                yield algo, {key: value}
    yield algo, {"sigma": 0.1}
    yield algo, {"f_max": 2.0}


@pytest.mark.parametrize(
    "algo, params", [*_alternatives("MFB"), *_alternatives("HPSO-MFB")], ids=str
)
def test_each_alternative_changes_the_search(algo, params):
    f = get_function("F10")

    def candidates(extra):
        seen: list[np.ndarray] = []

        def objective(X, streams):
            seen.append(X.copy())
            return f.kernel(X)

        problem = Problem(objective, np.full((2, 4), f.lower), np.full((2, 4), f.upper))
        opt = run(algo, problem, 12, 30, seed=3, **extra)
        while not opt.done:
            opt.step()
        return seen

    base, alt = candidates({}), candidates(params)
    assert len(base) == len(alt) == 31
    assert any(
        a.shape != b.shape or not np.array_equal(a, b) for a, b in zip(base, alt, strict=True)
    )
    # the alternative keeps the batch contract too
    kw = dict(dim=4, agents=12, iterations=30, seed=3, params=params)
    two, one = minimize(algo, "F10", runs=2, **kw), minimize(algo, "F10", runs=1, **kw)
    assert np.array_equal(one.curve[0], two.curve[0])
    assert np.array_equal(one.best_position[0], two.best_position[0])


def test_span_walk_beats_absolute_walk_on_a_wide_box():
    kw = dict(dim=10, agents=20, iterations=100, runs=6, seed=4)
    span = minimize("MFB", "F1", **kw).best_fitness
    absolute = minimize("MFB", "F1", params={"walk_scale": "absolute"}, **kw).best_fitness
    assert np.max(span) < 1e-3 < np.min(absolute)


# ----------------------------------------------------------------------- convergence
@pytest.mark.parametrize("algo", ["MFB", "HPSO-MFB"])
def test_beats_random_search_with_the_same_budget(algo):
    res = minimize(algo, "F1", dim=10, agents=20, iterations=100, runs=8, seed=11)
    budget = int(res.evaluations[0])
    assert budget == 20 * 101
    rs = random_search("F1", 10, budget, 8, seed=11)
    assert np.median(res.best_fitness) < 0.01 * np.median(rs)
    assert np.max(res.best_fitness) < np.min(rs)
    # and the curve really descends over the run, not only at initialisation
    assert np.all(res.curve[:, -1] < 0.05 * res.curve[:, 0])
