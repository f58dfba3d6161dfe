"""PSO, SSA, FDO, BA: the published order of magnitude and each algorithm's own mechanics.

The published values are the PSO, SSA and FDO columns of Table 2 of the seeds (000_*, ICOOT, and
001_*, IHPO, which repeats them): 30 dims, 30 agents, 500 iterations, mean of the best over 1000
runs. Where our faithful implementation differs by more than the tolerance, the difference is a
documented exception (docs/algorithms.md) and the test asserts its direction.
"""

import math
from functools import partial

import numpy as np
import pytest

from swarmpath.optimizers import Problem, RunStreams, create, minimize
from swarmpath.optimizers.ssa import SSA

# These tests are about the numpy reference (the default backend, "auto", would run the
# compiled kernels where they exist).
minimize = partial(minimize, backend="numpy")

# Seeds, Table 2 (30 dims): published mean of the best fitness.
# fmt: off
PUBLISHED = {
    "PSO": {
        "F1": 2.2965e-06, "F2": 1.4400e-03, "F3": 1.2401e02, "F4": 2.0211e00, "F5": 3.0213e01,
        "F6": 1.2411e-06, "F8": -5.2250e03, "F9": 3.8604e01, "F10": 1.0174e00, "F11": 1.1840e-02,
    },
    "SSA": {
        "F1": 1.3651e-07, "F2": 1.3328e00, "F3": 1.2921e03, "F4": 9.5648e00, "F5": 2.0168e02,
        "F6": 1.6204e-07, "F8": -5.9466e03, "F9": 4.7476e01, "F10": 2.0904e00, "F11": 1.3520e-02,
    },
    "FDO": {  # the slowest (up to three evaluations per bee): a subset
        "F1": 6.3139e03, "F4": 3.2439e01, "F5": 4.9340e06, "F9": 1.6083e02, "F10": 1.0321e01,
        "F11": 5.5598e01,
    },
}
# fmt: on
# F7 (noisy), F12 and F13 are left out for time (their kernels cost 10-100x F1's); the docs
# give all thirteen for the four algorithms.

# Tolerance: |log10(our mean) - log10(published mean)| <= 1 decade. Best-fitness distributions
# are heavy-tailed (the published std exceeds the mean for PSO F1/F6, SSA F1/F5...), so a 10-run
# mean can sit a factor of several from a 1000-run mean; one decade absorbs that and still
# catches a wrong update rule, which moves these numbers by several decades.
DECADES = 1.0
# F8 is negative with a narrow spread (std ~ 10 % of the mean): compare relative values.
F8_REL = 0.25

# Documented exceptions: (algorithm, function) -> sign of log10(ours / published) beyond the
# tolerance (+1: we are worse, -1: we are better). See docs/algorithms.md.
EXCEPTIONS = {
    # No PSO setting reproduces the seeds' 30-D sphere-like F1/F6 together with their F7
    # (docs/algorithms.md, PSO; services/swarmpath/evidence/reference/reasons.yaml).
    ("PSO", "F1"): +1,
    ("PSO", "F6"): +1,
    # Velocity clamped to 0.1 of the box lets PSO search F8's wide box better than the seeds'
    # (-7.1e3 vs -5.2e3; the gap to F8's minimum is 0.13 decades smaller: same decade).
    ("PSO", "F8"): -1,
    # SSA.m as coded is ~25 % better on F8 than the seeds' SSA (-7.3e3 vs -5.9e3 over 30 runs).
    ("SSA", "F8"): -1,
    # The published FDO column is far worse than FDO (ours, the author's rules, and mealpy's
    # OriginalFDO alike) on everything but F4, F9 and F10.
    ("FDO", "F1"): -1,
    ("FDO", "F5"): -1,
    ("FDO", "F11"): -1,
}
RUNS = 10

CASES = [(a, f) for a, table in PUBLISHED.items() for f in table]


@pytest.mark.parametrize(("algorithm", "function"), CASES)
def test_published_order_of_magnitude(algorithm, function):
    res = minimize(algorithm, function, dim=30, agents=30, iterations=500, runs=RUNS, seed=1)
    ours, published = float(np.mean(res.best_fitness)), PUBLISHED[algorithm][function]
    expected = EXCEPTIONS.get((algorithm, function))
    if function == "F8":
        rel = (ours - published) / abs(published)  # > 0: ours is worse (less negative)
        if expected is None:
            assert abs(rel) <= F8_REL, (ours, published)
        else:
            assert np.sign(rel) == expected and abs(rel) > F8_REL, (ours, published)
        return
    diff = math.log10(ours) - math.log10(published)
    if expected is None:
        assert abs(diff) <= DECADES, (ours, published)
    else:
        assert np.sign(diff) == expected and abs(diff) > DECADES, (ours, published)


# ------------------------------------------------------------------------------------------ PSO
def _sphere_problem(runs, dim, low=-100.0, high=100.0):
    return Problem(
        lambda X, s: np.sum(X * X, axis=-1), np.full((runs, dim), low), np.full((runs, dim), high)
    )


@pytest.mark.parametrize(("mode", "bound"), [("absolute", 6.0), ("range", 0.1 * 200.0)])
def test_pso_velocity_clamp(mode, bound):
    opt = create(
        "PSO",
        _sphere_problem(3, 5),
        agents=10,
        iterations=40,
        streams=RunStreams.for_runs(1, 3),
        params={"vmax_mode": mode},
    )
    peak = 0.0
    while not opt.done:
        opt.step()
        peak = max(peak, float(np.abs(opt.V).max()))
        assert np.all(np.abs(opt.V) <= bound)
    assert peak == bound  # far from the optimum the clamp is active


def test_pso_without_clamp_exceeds_vmax():
    opt = create(
        "PSO",
        _sphere_problem(3, 5),
        agents=10,
        iterations=10,
        streams=RunStreams.for_runs(1, 3),
        params={"vmax_mode": "none"},
    )
    while not opt.done:
        opt.step()
    assert np.abs(opt.V).max() > 6.0


@pytest.mark.parametrize("t0", [0, 99])
def test_pso_inertia_weight_schedule(t0):
    """One particle at its own pbest = gbest: the update is v <- w v, w = 0.9 - (t-1) 0.7 / T."""
    T = 100
    opt = create(
        "PSO", _sphere_problem(2, 3), agents=1, iterations=T, streams=RunStreams.for_runs(0, 2)
    )
    opt.initialize()
    opt.t = t0
    opt.V[:] = 0.5
    opt.step()
    w = 0.9 - t0 * 0.7 / T
    assert np.allclose(opt.V, 0.5 * w, rtol=0, atol=1e-15)


def test_pso_fly_lets_particles_leave_but_records_only_points_of_the_box():
    """bounds = "fly": positions are never clipped, outside particles are neither counted nor
    remembered as pbest, and every point the objective sees is in the box."""
    seen = []

    def objective(X, streams):
        seen.append(X.copy())
        return np.sum(X * X, axis=-1)

    R, N, d, T = 3, 10, 4, 40
    problem = Problem(objective, np.full((R, d), 1.0), np.full((R, d), 5.0))  # optimum on a face
    opt = create("PSO", problem, agents=N, iterations=T, streams=RunStreams.for_runs(4, R))
    left = False
    while not opt.done:
        opt.step()
        outside = (opt.X < 1.0) | (opt.X > 5.0)
        left = left or bool(outside.any())
        assert np.all((opt.pbest >= 1.0) & (opt.pbest <= 5.0))
    assert left
    assert all(np.all((x >= 1.0) & (x <= 5.0)) for x in seen)
    assert np.all(opt.evaluations < N * (T + 1))  # the outside points were not counted
    assert np.all((opt.best_position >= 1.0) & (opt.best_position <= 5.0))


@pytest.mark.parametrize("bounds", ["fly", "clip"])
def test_pso_clip_pins_coordinates_on_the_bounds_fly_does_not(bounds):
    """The former rule (clip, keep the velocity, absolute Vmax = 6) ends 30-D F2 runs with
    coordinates exactly on +-10; free flight never does (issue 10, audit item 1)."""
    res = minimize(
        "PSO", "F2", dim=30, agents=30, iterations=300, runs=10, seed=1,
        params={"bounds": bounds, "vmax_mode": "absolute"},
    )
    pinned = np.count_nonzero(np.any(np.abs(res.best_position) == 10.0, axis=1))
    if bounds == "clip":
        assert pinned >= 3 and np.median(res.best_fitness) > 1.0
    else:
        assert pinned == 0 and np.median(res.best_fitness) < 1.0


# ------------------------------------------------------------------------------------------ SSA
def test_ssa_c1_schedule():
    T = 500
    c = np.array([SSA.c1(t, T) for t in range(1, T + 1)])
    assert c[0] == pytest.approx(2 * math.exp(-((4 / T) ** 2)))
    assert c[-1] == pytest.approx(2 * math.exp(-16))
    assert np.all(np.diff(c) < 0)
    assert SSA.c1(T // 4, T) == pytest.approx(2 * math.exp(-1))


def test_ssa_leaders_within_c1_of_the_food_and_followers_chain_in_place():
    """Leaders move to F +- c1 ((ub - lb) c2 + lb); followers replay SSA.m's in-place sweep."""
    R, N, d, T = 3, 11, 4, 100
    opt = create(
        "SSA", _sphere_problem(R, d), agents=N, iterations=T, streams=RunStreams.for_runs(2, R)
    )
    opt.initialize()
    opt.t = T // 2 - 1  # the step runs t = T/2: c1 = 2 exp(-4), leaders stay inside the box
    opt.best_position[:] = 0.0
    old = opt.X.copy()
    opt.step()
    c1 = SSA.c1(T // 2, T)
    NL = N // 2
    leaders = opt.X[:, :NL]
    assert np.all(np.abs(leaders) <= c1 * 100.0 + 1e-12)
    assert np.all(np.abs(leaders) < 100.0)  # not clipped: the chain saw them as they are
    expected = old.copy()
    expected[:, :NL] = leaders
    for i in range(NL, N):  # SSA.m, literally
        expected[:, i] = (expected[:, i] + expected[:, i - 1]) / 2
    assert np.allclose(opt.X, expected, rtol=1e-12, atol=1e-12)


def test_ssa_single_leader_alternative_differs():
    kw = dict(dim=10, agents=20, iterations=50, runs=2, seed=3)
    half = minimize("SSA", "F1", **kw)
    one = minimize("SSA", "F1", params={"leaders": "one"}, **kw)
    assert not np.array_equal(half.curve, one.curve)
    assert np.all(half.evaluations == 20 * 51)


# ------------------------------------------------------------------------------------------ FDO
def test_fdo_counts_only_the_tried_points():
    """Iteration 1: no bee has a pace yet, so after a failed trial 1 the later code stops (nested)
    and the 2019 code tries x + x r (split): N + number of failures."""
    R, N, d = 4, 15, 6
    for trials in ("nested", "split"):
        opt = create(
            "FDO",
            _sphere_problem(R, d),
            agents=N,
            iterations=20,
            streams=RunStreams.for_runs(5, R),
            params={"trials": trials},
        )
        opt.initialize()
        assert np.all(opt.evaluations == N)
        opt.step()
        failed = N - opt.accepted[:, 0]
        extra = 0 if trials == "nested" else failed
        assert np.all(opt.evaluations == N + N + extra)
        seen = opt.evaluations.copy()
        while not opt.done:
            before = opt.accepted.copy()
            opt.step()
            assert np.all(opt.evaluations - seen >= N)
            assert np.all(opt.evaluations - seen <= (3 if trials == "nested" else 2) * N)
            seen = opt.evaluations.copy()
            assert np.all(opt.accepted >= before)
        assert np.all(opt.has_pace.sum(axis=1) > 0)


def test_fdo_is_greedy_and_reports_the_best_bee():
    opt = create(
        "FDO", _sphere_problem(3, 5), agents=12, iterations=30, streams=RunStreams.for_runs(7, 3)
    )
    opt.initialize()
    F = opt.F.copy()
    while not opt.done:
        opt.step()
        assert np.all(opt.F <= F)
        F = opt.F.copy()
    assert np.array_equal(opt.F.min(axis=1), opt.best_fitness)


def test_fdo_author_bound_rule_sends_violators_toward_the_origin():
    R, N, d = 2, 50, 8
    for bound in ("clip", "author"):
        opt = create(
            "FDO",
            _sphere_problem(R, d),
            agents=N,
            iterations=5,
            streams=RunStreams.for_runs(1, R),
            params={"bound": bound},
        )
        opt.initialize()
        C = opt._bound(np.full((R, N, d), 150.0))
        assert np.all(np.abs(C) <= 100.0)
        if bound == "clip":
            assert np.all(C == 100.0)
        else:  # ub * Levy: median |Levy| ~ 0.01, so most land within a few units of 0
            assert np.median(np.abs(C)) < 5.0


def test_fdo_weight_rules():
    opt = create(
        "FDO", _sphere_problem(1, 2), agents=4, iterations=5, streams=RunStreams.for_runs(1, 1)
    )
    opt.initialize()
    opt.F = np.array([[1.0, 2.0, 40.0, 1.0]])
    fw, _ = opt._weights(np.array([1.0]))
    # default "threshold": 0.2 when f* < 0.05 f_i, the ratio f*/f_i otherwise (wf = 0)
    assert np.allclose(fw, [[1.0, 0.5, 0.2, 1.0]])
    opt.p["weight_rule"] = "ratio"
    fw, _ = opt._weights(np.array([1.0]))
    assert np.allclose(fw, [[1.0, 0.5, 0.025, 1.0]])


# ------------------------------------------------------------------------------------------- BA
def test_ba_velocity_moves_toward_the_best():
    R, N, d = 2, 8, 3
    for velocity, (lo, hi) in (("toward", (0.0, 2.0)), ("away", (-2.0, 0.0))):
        opt = create(
            "BA",
            _sphere_problem(R, d),
            agents=N,
            iterations=3,
            streams=RunStreams.for_runs(4, R),
            params={"velocity": velocity},
        )
        opt.initialize()
        X0, best = opt.X.copy(), opt.best_position[:, None, :].copy()
        opt.step()  # v0 = 0, so v = (x* - x) f
        gap = best - X0
        ok = np.abs(gap) > 1e-9
        ratio = opt.V[ok] / gap[ok]
        assert np.all((ratio >= lo) & (ratio <= hi))
        # the frequency is one number per bat
        per_bat = opt.V / np.where(ok, gap, 1.0)
        high = np.where(ok, per_bat, -np.inf).max(axis=2)
        low = np.where(ok, per_bat, np.inf).min(axis=2)
        some = ok.any(axis=2)
        assert np.allclose(high[some], low[some])


@pytest.mark.parametrize(("walk", "radius"), [("paper", 0.5), ("demo", 0.01)])
def test_ba_local_walk_around_the_best(walk, radius):
    """pulse_rate = 0: every bat walks; paper: eps A_mean, eps in [-1, 1]; demo: 1e-3 N(0, 1)."""
    seen = []

    def objective(X, s):
        seen.append(X.copy())
        return np.sum(X * X, axis=-1)

    problem = Problem(objective, np.full((2, 3), -100.0), np.full((2, 3), 100.0))
    opt = create(
        "BA",
        problem,
        agents=6,
        iterations=2,
        streams=RunStreams.for_runs(0, 2),
        params={"pulse_rate": 0.0, "local_walk": walk},
    )
    opt.initialize()
    best = opt.best_position[:, None, :].copy()
    opt.step()
    assert np.all(np.abs(seen[-1] - best) <= radius)


def test_ba_demo_keeps_loudness_and_pulse_rate_constant():
    opt = create(
        "BA", _sphere_problem(2, 4), agents=10, iterations=30, streams=RunStreams.for_runs(3, 2)
    )
    while not opt.done:
        opt.step()
    assert np.all(opt.A == 0.5) and np.all(opt.r == 0.5)
    assert np.all(opt.evaluations == 10 * 31)


def test_ba_paper_updates_loudness_and_pulse_rate_on_acceptance():
    """Eq (6): A_i <- 0.9 A_i and r_i <- r0 (1 - exp(-0.9 t)) each time bat i accepts a move.

    A bat that moved has accepted; one that did not move may still have accepted its own
    position (the best bat with v = 0 re-evaluates x_i, and the demo's test is f_new <= f_i)."""
    R, N, T = 2, 10, 25
    opt = create(
        "BA",
        _sphere_problem(R, 4),
        agents=N,
        iterations=T,
        streams=RunStreams.for_runs(3, R),
        params={"updates": "paper", "loudness": 1.0},
    )
    opt.initialize()
    total = np.zeros((R, N), dtype=int)
    while not opt.done:
        X, A, r = opt.X.copy(), opt.A.copy(), opt.r.copy()
        opt.step()
        moved = np.any(opt.X != X, axis=2)
        accepted = opt.A < A
        assert np.all(accepted[moved])
        assert np.allclose(opt.A[accepted], 0.9 * A[accepted])
        assert np.all(opt.A[~accepted] == A[~accepted])
        assert np.allclose(opt.r[accepted], 0.5 * (1 - np.exp(-0.9 * opt.t)))
        assert np.all(opt.r[~accepted] == r[~accepted])
        assert np.all(opt.X[~accepted] == X[~accepted])
        total += accepted
    assert total.min() > 0
