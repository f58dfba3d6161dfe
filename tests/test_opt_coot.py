"""COOT, mCOOT and ICOOT: the authors' sequential sweeps replayed exactly, the parameters'
alternatives, ICOOT's acceleration, and the published Table 2 orders of magnitude."""

import math
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
    minimize,
)
from swarmpath.optimizers.coot import chain_sweep, record_holders

# These tests are about the numpy reference (the default backend, "auto", would run the
# compiled kernels where they exist).
minimize = partial(minimize, backend="numpy")

FAMILY = ("COOT", "mCOOT", "ICOOT")


def sphere_problem(runs, dim, lo=-5.0, hi=5.0, centre=0.0):
    return Problem(
        lambda X, s: np.sum((X - centre) ** 2, axis=-1),
        np.full((runs, dim), lo),
        np.full((runs, dim), hi),
    )


def started(algo, runs=3, dim=4, agents=12, iterations=10, params=None, problem=None, seed=0):
    problem = problem or sphere_problem(runs, dim)
    opt = create(algo, problem, agents, iterations, RunStreams.for_runs(seed, runs), params)
    opt.initialize()
    return opt


def cos2pi(R):
    return np.cos(2.0 * math.pi * R)


# ----------------------------------------------------------------------- exact sweeps (COOT.m)
def test_chain_sweep_equals_sequential_loop():
    rng = np.random.default_rng(3)
    R, N, d = 5, 40, 3
    moved, old = rng.uniform(-1, 1, (R, N, d)), rng.uniform(-1, 1, (R, N, d))
    chain = rng.random((R, N)) < 0.7  # long chains on purpose
    chain[:, 0] = False
    ref = np.empty_like(moved)
    for r in range(R):
        for i in range(N):  # in place: coot i averages with the already moved coot i - 1
            ref[r, i] = (ref[r, i - 1] + old[r, i]) / 2 if chain[r, i] else moved[r, i]
    np.testing.assert_allclose(chain_sweep(moved.copy(), old, chain), ref, rtol=1e-13, atol=1e-15)


@pytest.mark.parametrize("randoms", ["mixed", "vector", "scalar"])
def test_coot_moves_equal_the_matlab_loop(randoms):
    """One coot phase against COOT.m's loop, fed with the same uniforms."""
    opt = started("COOT", runs=3, dim=4, agents=23, params={"randoms": randoms})
    opt.t = 1
    A, _ = opt.schedule()
    u = opt._draw()
    u0 = {k: v.copy() for k, v in u.items()}
    X, LP = opt.CP.copy(), opt.LP.copy()
    opt._move_coots(A, u)
    lb, ub = opt.lb[:, 0], opt.ub[:, 0]
    for r in range(opt.R):
        for i in range(opt.Nc):
            k = (i + 1) % opt.NL  # MATLAB: k = 1 + mod(i, NL) with 1-based i
            scalar = randoms == "scalar" or (randoms == "mixed" and u0["c_flag"][r, i] < 0.5)
            # each coot has two scalars and two vectors: (R, R1) to follow, (R2, Q) at random
            tag = "S" if scalar else "V"
            one, two = u0[f"c_{tag}1"][r, i], u0[f"c_{tag}2"][r, i]
            if u0["c_follow"][r, i] < 0.5:
                Rr, R1 = 2 * one - 1, two
                X[r, i] = 2 * R1 * cos2pi(Rr) * (LP[r, k] - X[r, i]) + LP[r, k]
            elif u0["c_chain"][r, i] < 0.5 and i > 0:
                X[r, i] = (X[r, i] + X[r, i - 1]) / 2
            else:
                R2, Q = one, u0["c_V2"][r, i] * (ub[r] - lb[r]) + lb[r]
                X[r, i] = X[r, i] + A * R2 * (Q - X[r, i])
            X[r, i] = np.clip(X[r, i], lb[r], ub[r])
    np.testing.assert_allclose(opt.CP, X, rtol=1e-12, atol=1e-12)


def test_coot_leader_swap_equals_the_matlab_loop():
    rng = np.random.default_rng(8)
    opt = started("COOT", runs=6, dim=2, agents=25)  # 3 leaders, 22 coots
    for _ in range(5):
        opt.CP, opt.LP = rng.normal(size=opt.CP.shape), rng.normal(size=opt.LP.shape)
        opt.CF = rng.choice([1.0, 2.0, 3.0, 4.0], size=opt.CF.shape)  # ties on purpose
        opt.LF = rng.choice([1.5, 2.0, 3.0, np.inf], size=opt.LF.shape)
        CP, LP, CF, LF = opt.CP.copy(), opt.LP.copy(), opt.CF.copy(), opt.LF.copy()
        for r in range(opt.R):
            for i in range(opt.Nc):
                k = (i + 1) % opt.NL
                if CF[r, i] < LF[r, k]:
                    CP[r, i], LP[r, k] = LP[r, k].copy(), CP[r, i].copy()
                    CF[r, i], LF[r, k] = LF[r, k], CF[r, i]
        opt._swap_with_leaders()
        for got, want in ((opt.CP, CP), (opt.LP, LP), (opt.CF, CF), (opt.LF, LF)):
            assert np.array_equal(got, want)


@pytest.mark.parametrize("randoms", ["mixed", "vector", "scalar"])
def test_leader_phase_equals_the_matlab_loop_from_the_phase_gbest(randoms):
    """COOT.m's leader loop, with every proposal built from the gBest of the phase start."""
    opt = started("COOT", runs=4, dim=3, agents=40, params={"randoms": randoms})  # 4 leaders
    for t in range(1, 4):
        opt.t = t
        _, B = opt.schedule()
        u = opt._draw()
        u0 = {k: v.copy() for k, v in u.items()}
        LP, LF, g0, gf0 = opt.LP.copy(), opt.LF.copy(), opt.g.copy(), opt.gf.copy()
        opt._move_leaders(B, u)
        lb, ub = opt.lb[:, 0], opt.ub[:, 0]
        for r in range(opt.R):
            g, gf = g0[r].copy(), gf0[r]
            for i in range(opt.NL):
                scalar = randoms == "scalar" or (randoms == "mixed" and u0["l_flag"][r, i] < 0.5)
                if scalar:
                    Rr, R3 = 2 * u0["l_S1"][r, i] - 1, u0["l_S2"][r, i]
                else:
                    Rr, R3 = 2 * u0["l_V1"][r, i] - 1, u0["l_V2"][r, i]
                sign = 1.0 if u0["l_sign"][r, i] < 0.5 else -1.0
                temp = B * R3 * cos2pi(Rr) * (g0[r] - LP[r, i]) + sign * g0[r]
                temp = np.clip(temp, lb[r], ub[r])
                f = float(np.sum(temp**2))
                if f < gf:  # the leader takes the old gBest; the proposal becomes gBest
                    LP[r, i], LF[r, i] = g, gf
                    g, gf = temp, f
            np.testing.assert_allclose(opt.g[r], g, rtol=1e-12, atol=1e-12)
            assert opt.gf[r] == pytest.approx(gf, rel=1e-12, abs=1e-12)
        np.testing.assert_allclose(opt.LP, LP, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(opt.LF, LF, rtol=1e-12, atol=1e-12)


def test_record_holders_is_a_strict_sweep():
    vals = np.array([[3.0, 3.0, 2.0, 2.0, 5.0, 1.0, 1.0]])
    assert record_holders(vals).tolist() == [[0, 0, 2, 2, 2, 5, 5]]


# --------------------------------------------------------------------- leaders and evaluations
@pytest.mark.parametrize("algo", FAMILY)
@pytest.mark.parametrize(
    "agents, params, leaders",
    [
        (30, {}, 3),
        (80, {"leaders": 2}, 2),
        (9, {}, 1),
        (11, {}, 2),
        (20, {"leader_fraction": 0.25}, 5),
    ],
)
def test_leader_count(algo, agents, params, leaders):
    opt = started(algo, runs=2, dim=3, agents=agents, params=params)
    assert (opt.NL, opt.Nc) == (leaders, agents - leaders)
    assert opt.LP.shape == (2, leaders, 3) and opt.CP.shape == (2, agents - leaders, 3)


@pytest.mark.parametrize("algo", FAMILY)
def test_leaders_must_leave_a_coot(algo):
    with pytest.raises(ParameterError, match="leaders"):
        started(algo, agents=4, params={"leaders": 4})


def test_evaluation_counts():
    kw = dict(dim=5, agents=30, iterations=20, runs=2, seed=1)
    assert minimize("COOT", "F1", **kw).evaluations.tolist() == [30 * 21] * 2
    assert minimize("ICOOT", "F1", **kw).evaluations.tolist() == [30 * 21] * 2
    # mCOOT: 2N for the opposition-based start, N + ceil(0.3 * 27) = 39 per iteration
    assert minimize("mCOOT", "F1", **kw).evaluations.tolist() == [60 + 20 * 39] * 2
    no_obl = {"opposition_init": False, "jump_rate": 0.0}
    assert minimize("mCOOT", "F1", params=no_obl, **kw).evaluations.tolist() == [30 * 21] * 2


def test_mcoot_without_opposition_is_coot():
    kw = dict(dim=5, agents=14, iterations=30, runs=3, seed=4)
    plain = minimize("COOT", "F5", **kw)
    bare = minimize("mCOOT", "F5", params={"opposition_init": False, "jump_rate": 0.0}, **kw)
    assert np.array_equal(plain.curve, bare.curve)


def test_mcoot_opposition_start_keeps_the_better_of_each_pair():
    seen = []

    def objective(X, s):
        seen.append(X.copy())
        return np.sum((X - 1.0) ** 2, axis=-1)

    problem = Problem(objective, np.full((2, 3), -4.0), np.full((2, 3), 6.0))
    opt = create("mCOOT", problem, 10, 5, RunStreams.for_runs(2, 2))
    opt.initialize()
    X, O = seen[0][:, :10], seen[0][:, 10:]
    assert np.allclose(O, -4.0 + 6.0 - X)
    keep = np.where((objective(O, None) < objective(X, None))[..., None], O, X)
    assert np.array_equal(np.concatenate([opt.CP, opt.LP], axis=1), keep)


def test_mcoot_jumps_the_coots_with_the_smallest_picks_in_their_order():
    """The jumping coots' opposites are evaluated in ascending order of their picks, on any
    machine (argpartition's order differs with and without AVX-512, and it decides which
    noise value of F7 each opposite gets)."""
    seen = []

    def objective(X, s):
        seen.append(X.copy())
        return np.sum(X**2, axis=-1)

    problem = Problem(objective, np.full((2, 3), -4.0), np.full((2, 3), 6.0))
    # 900 coots: with that many keys even AVX-512 argpartition leaves its picks unsorted
    opt = create("mCOOT", problem, 1000, 5, RunStreams.for_runs(2, 2), {"opposition": "static"})
    opt.initialize()
    u = opt._draw()
    CP = opt.CP.copy()
    opt._after_coot_evaluation(u)
    order = np.argsort(u["m_pick"], axis=1)[:, : opt.jumpers]
    expected = np.clip(-4.0 + 6.0 - CP[np.arange(2)[:, None], order], -4.0, 6.0)
    assert opt.jumpers == 270 and np.array_equal(seen[-1], expected)


# ----------------------------------------------------------------- parameters change behaviour
def _alternatives():
    cases = []
    for algo in FAMILY:
        cls = get_optimizer(algo)
        for key, allowed in cls.choices.items():
            cases += [(algo, key, v) for v in allowed if v != cls.defaults[key]]
    cases += [
        ("COOT", "leaders", 1),
        ("COOT", "leader_fraction", 0.3),
        ("mCOOT", "jump_rate", 0.6),
        ("mCOOT", "opposition_init", False),
        ("ICOOT", "cell", 0.02),
        ("ICOOT", "density_power", 6.0),
        ("ICOOT", "leader_gain", 1.0),
    ]
    return cases


@pytest.mark.parametrize("algo, key, value", _alternatives())
def test_every_alternative_changes_the_search(algo, key, value):
    # an asymmetric box with the optimum off the origin, so that every reading differs
    problem = sphere_problem(3, 5, lo=-2.0, hi=8.0, centre=3.0)

    def curve(params):
        opt = create(algo, problem, 14, 25, RunStreams.for_runs(6, 3), params)
        out = []
        while not opt.done:
            opt.step()
            out.append(opt.best_fitness.copy())
        return np.array(out)

    assert not np.array_equal(curve(None), curve({key: value})), (algo, key, value)


def test_icoot_centred_target_is_the_literal_one_on_symmetric_boxes():
    kw = dict(dim=6, agents=12, iterations=40, runs=2, seed=3)
    a = minimize("ICOOT", "F10", params={"random_target": "centred"}, **kw)
    b = minimize("ICOOT", "F10", params={"random_target": "literal"}, **kw)
    assert np.array_equal(a.curve, b.curve)


# ------------------------------------------------------------------------ ICOOT's acceleration
@pytest.mark.parametrize("function", ["F1", "F8", "F12"])
def test_icoot_acc_stays_finite_and_in_range(function):
    f = get_function(function)
    problem = Problem(
        lambda X, s: f.kernel(X), np.full((3, 10), f.lower), np.full((3, 10), f.upper)
    )
    opt = create("ICOOT", problem, 30, 150, RunStreams.for_runs(1, 3))
    densities = []
    while not opt.done:
        opt.step()
        for acc in (opt.acc_coots, opt.acc_leaders):
            assert np.all(np.isfinite(acc)) and np.all((acc >= 0) & (acc <= 2))
        densities.append(opt.density.copy())
    densities = np.array(densities)
    assert np.all((densities > 0) & (densities <= 1))
    assert densities[-1].mean() > densities[0].mean()  # the swarm contracts: density grows


def test_icoot_terms_are_guarded_on_degenerate_swarms():
    opt = started("ICOOT", runs=2, dim=3, agents=12)
    same = np.zeros((2, 11, 3))  # all coots on one point: r = 1 cell, beta2 = 0, alpha = -N_c
    D, free = opt.swarm_terms(same)
    assert np.allclose(D, 1.0) and np.allclose(free, 1 - 1 / 11)
    lonely = started("ICOOT", runs=2, dim=3, agents=2)  # one coot, one leader
    lonely.step()
    assert np.all(np.isfinite(lonely.acc_coots)) and np.all(np.isfinite(lonely.acc_leaders))


# ------------------------------------------------------------- Table 2 of the ICOOT paper (30-D)
# Abdulsaheb & Kadhim, IJIES 15(5) 2022, Table 2 (30 agents, 500 iterations): (min, max, avg).
PUBLISHED = {
    "COOT": {
        "F1": (9.8206e-58, 8.6061e-08, 8.7095e-11),
        "F5": (2.6813e01, 1.6774e03, 4.5168e01),
        "F6": (1.2200e-02, 1.2563e00, 1.4580e-01),
        "F8": (-1.2185e04, -4.9284e03, -7.3315e03),
        "F10": (8.8818e-16, 2.4877e-05, 7.3884e-08),
    },
    "ICOOT": {
        "F1": (3.4334e-52, 1.7486e-15, 1.7507e-18),
        "F5": (2.6941e01, 2.8691e01, 2.7950e01),
        "F6": (1.0500e-02, 2.0190e-01, 5.0200e-02),
        "F8": (-1.0322e04, -3.1085e03, -6.5649e03),
        "F12": (4.6113e-04, 1.6140e-01, 6.7000e-03),
        "F13": (5.4400e-02, 2.9690e00, 1.7224e00),
    },
    "mCOOT": {
        "F1": (6.1833e-56, 5.4187e-11, 5.4838e-12),
        "F5": (1.6882e01, 1.0561e02, 2.8439e01),
        "F6": (7.6815e-03, 7.9100e-01, 9.1800e-02),
        "F8": (-7.6720e03, -3.1031e03, -4.6161e03),
    },
}
# Optimum reached to full precision in most runs: the published average over 1000 runs is set by
# its worst runs, so we check that our runs lie in the published [min, max] range instead.
HEAVY_TAILED = {"F1", "F2", "F3", "F4", "F9", "F10", "F11"}
# Documented exceptions (docs/algorithms.md, "Measured against Table 2"): what we check
# instead of the published average's order of magnitude.
EXCEPTIONS = {
    # ours is ~10x *better*; the published ICOOT F13 is 3.8x worse than the published COOT F13
    ("ICOOT", "F13"): "better than published",
    # 6 runs in 30 stop in local minima (0.2-3.2), as 7 of COOT's do; the median matches
    ("ICOOT", "F12"): "most runs within the published range",
    # the published mCOOT column is the COOT column times 17/27 x 10^k: not a measurement.
    # F8: the derived value would make mCOOT far worse than COOT; ours is as good as our COOT
    ("mCOOT", "F8"): "at least as good as published",
    # F2: one run in 30 above the published maximum sets our mean (heavy tail)
    ("mCOOT", "F2"): "most runs within the published range",
    # F12: stuck runs as for ICOOT; the median matches
    ("mCOOT", "F12"): "most runs within the published range",
}


def _table_cases():
    return [(a, f) for a, fs in PUBLISHED.items() for f in fs]


@pytest.mark.parametrize("algo, function", _table_cases())
def test_published_table2_order_of_magnitude(algo, function):
    runs = 6 if function in ("F12", "F13") else 10
    res = minimize(algo, function, dim=30, agents=30, iterations=500, runs=runs, seed=1)
    best = res.best_fitness
    _, hi, avg = PUBLISHED[algo][function]  # (min, max, avg)
    rule = EXCEPTIONS.get((algo, function))
    if rule == "better than published":
        assert np.all(best <= hi) and best.mean() < avg / 3, best  # 30 runs: 10x better
    elif rule == "most runs within the published range":
        assert np.mean(best <= hi) >= 0.5 and best.min() <= avg, best
    elif rule == "at least as good as published":
        assert best.mean() < avg, best
    elif function == "F8":  # negative: relative
        assert best.mean() == pytest.approx(avg, rel=0.2)
    elif function in HEAVY_TAILED:
        assert np.all(best <= hi) and best.mean() <= 10 * avg, best
    else:
        assert abs(np.log10(best.mean() / avg)) < 1.0, (best.mean(), avg)


def _coot_m(N, max_iter, lb, ub, dim, fobj, rng):
    """A literal loop port of the authors' COOT.m; returns the best value ever evaluated."""
    lb, ub = np.full(dim, lb), np.full(dim, ub)
    NL = math.ceil(0.1 * N)
    Nc = N - NL
    CP = rng.random((Nc, dim)) * (ub - lb) + lb
    CF = np.array([fobj(x) for x in CP])
    LP = rng.random((NL, dim)) * (ub - lb) + lb
    LF = np.array([fobj(x) for x in LP])
    every = np.concatenate([CF, LF])
    g, gf = np.vstack([CP, LP])[np.argmin(every)].copy(), every.min()
    best = gf
    for l in range(2, max_iter + 1):
        B, A = 2 - l * (1 / max_iter), 1 - l * (1 / max_iter)
        for i in range(1, Nc + 1):
            if rng.random() < 0.5:
                R, R1 = -1 + 2 * rng.random(), rng.random()
            else:
                R, R1 = -1 + 2 * rng.random(dim), rng.random(dim)
            k = (i % NL) + 1
            x = CP[i - 1]
            if rng.random() < 0.5:
                x = 2 * R1 * np.cos(2 * np.pi * R) * (LP[k - 1] - x) + LP[k - 1]
            elif rng.random() < 0.5 and i != 1:
                x = (x + CP[i - 2]) / 2
            else:
                x = x + A * R1 * (rng.random(dim) * (ub - lb) + lb - x)
            CP[i - 1] = np.clip(x, lb, ub)
        for i in range(1, Nc + 1):
            CF[i - 1] = fobj(CP[i - 1])
            best = min(best, CF[i - 1])
            k = (i % NL) + 1
            if CF[i - 1] < LF[k - 1]:
                CP[i - 1], LP[k - 1] = LP[k - 1].copy(), CP[i - 1].copy()
                CF[i - 1], LF[k - 1] = LF[k - 1], CF[i - 1]
        for i in range(NL):
            if rng.random() < 0.5:
                R, R3 = -1 + 2 * rng.random(), rng.random()
            else:
                R, R3 = -1 + 2 * rng.random(dim), rng.random(dim)
            step = B * R3 * np.cos(2 * np.pi * R) * (g - LP[i])
            temp = np.clip(step + g if rng.random() < 0.5 else step - g, lb, ub)
            tf = fobj(temp)
            best = min(best, tf)
            if gf > tf:
                LF[i], LP[i], gf, g = gf, g.copy(), tf, temp
    return best


@pytest.mark.parametrize("centre", [0.0, 3.0])
def test_coot_behaves_like_a_literal_port_of_coot_m(centre):
    """Same distribution as COOT.m (our T steps = COOT.m's Max_iter = T + 1), also off-origin."""
    runs, T, d = 8, 100, 10

    def sphere(x):
        return float(np.sum((x - centre) ** 2))

    literal = [
        _coot_m(30, T + 1, -10.0, 10.0, d, sphere, np.random.default_rng(r)) for r in range(runs)
    ]
    opt = create(
        "COOT", sphere_problem(runs, d, -10.0, 10.0, centre), 30, T, RunStreams.for_runs(0, runs)
    )
    while not opt.done:
        opt.step()
    gap = np.median(np.log10(opt.best_fitness)) - np.median(np.log10(literal))
    assert abs(gap) < 1.0, gap
