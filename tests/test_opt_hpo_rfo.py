"""HPO, IHPO and RFO: published numbers, origin bias, parameter readings, small-N guards.

Decisions and measured tables: docs/algorithms.md.
"""

from dataclasses import replace
from functools import partial

import numpy as np
import pytest

from swarmpath.functions import get_function
from swarmpath.optimizers import Problem, RunStreams, create, get_optimizer, minimize
from swarmpath.optimizers.hpo import hpo_c, hpo_kbest, matlab_round

# These tests are about the numpy reference (the default backend, "auto", would run the
# compiled kernels where they exist).
minimize = partial(minimize, backend="numpy")

PAPER = dict(dim=30, agents=30, iterations=500)


def paper_run(algo, function, runs=10, params=None, shifted=False, **kw):
    """The papers' setting: 30 dims, 30 agents, 500 iterations."""
    return minimize(algo, function, runs=runs, seed=1, params=params, shifted=shifted,
                    **{**PAPER, **kw})


# ------------------------------------------------------------------------------ HPO vs Table 2
# HPO column of Table 2 in Abdulsaheb & Kadhim, IJIES 16(2) 2023 (seed 001): average best.
PUBLISHED_HPO = {
    "F1": 0.0, "F2": 5.8110e-183, "F3": 1.5673e-293, "F4": 1.3881e-153, "F5": 21.8228,
    "F6": 1.5478e-11, "F7": 1.0961e-04, "F8": -9362.2, "F9": 0.0, "F10": 8.8818e-16,
    "F11": 0.0, "F12": 6.5451e-06, "F13": 0.1053,
}
# Same order of magnitude as published (a factor 10 either way), or both exactly 0 / <= 1e-15.
REPRODUCED = ["F1", "F5", "F7", "F8", "F9", "F10", "F11", "F13"]
# Exceptions (docs: "HPO against Table 2"; services/swarmpath/evidence/reference/reasons.yaml):
# * F2-F4: published 1e-153 .. 1e-293; every run of ours is astronomically small too, with
#   other exponents (the collapse onto the origin keeps going; the exponent is not quality).
# * F6, F12: heavy tails. Most runs reach the published order or better (median <= published
#   mean); a few stop early (F12: at pi/30 = 0.105, one coordinate a lattice step away), which
#   sets the mean.
ASTRONOMICAL = ["F2", "F3", "F4"]
HEAVY_TAILED = ["F6", "F12"]


def test_exceptions_cover_table_2():
    assert sorted(REPRODUCED + ASTRONOMICAL + HEAVY_TAILED) == sorted(PUBLISHED_HPO)


@pytest.mark.parametrize("function", REPRODUCED)
def test_hpo_reproduces_published_order_of_magnitude(function):
    mean = paper_run("HPO", function).best_fitness.mean()
    published = PUBLISHED_HPO[function]
    if abs(published) <= 1e-15:
        assert 0.0 <= mean <= 1e-15, mean
    else:
        assert 0.1 <= mean / published <= 10.0, (mean, published)


@pytest.mark.parametrize("function", ASTRONOMICAL)
def test_hpo_astronomically_small_where_published_so(function):
    best = paper_run("HPO", function).best_fitness
    assert np.all(best < 1e-100), best


@pytest.mark.parametrize("function", HEAVY_TAILED)
def test_hpo_heavy_tailed_cells_reach_the_published_order_in_most_runs(function):
    best = paper_run("HPO", function).best_fitness
    published = PUBLISHED_HPO[function]
    assert np.median(best) <= published, best
    assert np.count_nonzero(best > 10.0 * published) <= 3, best


def test_hpo_synchronous_update_stalls_off_origin():
    """The former default: the prey cloud contracts around a target fixed for the iteration."""
    for function, low in (("F6", 0.3), ("F12", 0.01), ("F13", 0.3)):
        mean = paper_run("HPO", function, runs=4, params={"update": "synchronous"}).best_fitness
        assert mean.mean() >= low, (function, mean)


# --------------------------------------------------------------------------------- origin bias
def plain_and_shifted(algo, params, runs=6):
    plain = paper_run(algo, "F1", runs=runs, params=params).best_fitness
    shifted = paper_run(algo, "F1", runs=runs, params=params, shifted=True).best_fitness
    return float(np.median(plain)), float(np.median(shifted))


def test_rfo_default_is_not_origin_biased_literal_eq9_is():
    plain, shifted = plain_and_shifted("RFO", None)
    assert plain < 1.0 and shifted < 1.0
    assert shifted / plain < 10.0, (plain, shifted)
    # literal eq 9, x = kappa H: new foxes between the origin and the habitat centre
    plain, shifted = plain_and_shifted("RFO", {"reproduction": "scaled_centre"})
    assert plain < 1e-12 and shifted > 1e-3, (plain, shifted)


def test_hpo_hunter_rule_is_origin_biased():
    # The published hunter rule Z (C P + (1 - C) mu) is HPO's engine and pulls to the origin:
    # exact zeros on plain F1, not even 1e-8 shifted (the authors' sweep, the default).
    plain, shifted = plain_and_shifted("HPO", None, runs=4)
    assert plain == 0.0 and shifted > 1e-8, (plain, shifted)
    # Synchronously the bias is extreme; the code's prey rule (step 2 Z) keeps the population
    # from collapsing there: shifted F1 works.
    sync = {"update": "synchronous"}
    plain, shifted = plain_and_shifted("HPO", sync)
    assert plain < 1e-100 and shifted > 100.0, (plain, shifted)
    plain_code, shifted_code = plain_and_shifted(
        "HPO", {**sync, "prey_step": "2Z", "prey_angle": "from_z"}
    )
    assert plain_code < 1e-100 and shifted_code < 1e-3 * shifted


def test_ihpo_alpha_reading_adds_no_origin_bias_literal_and_position_do():
    # With HPO's own bias removed (translation-invariant hunter), only alpha can pull to 0
    # (synchronous update: the finding of docs/algorithms.md, at a sixth of the cost).
    base = {"hunter": "relative", "update": "synchronous"}
    plain, shifted = plain_and_shifted("IHPO", {**base, "alpha_on": "step"})
    assert shifted / plain < 10.0 and plain > 1.0, (plain, shifted)
    for on in ("literal", "position"):
        plain, shifted = plain_and_shifted("IHPO", {**base, "alpha_on": on})
        assert plain < 1e-50 and shifted > 100.0, (on, plain, shifted)


def test_ihpo_default_is_printed_eq_14_and_origin_bound():
    # eq 14 as printed (alpha_on = "literal") reaches exact zeros on F1 like the published
    # IHPO column, and loses them when the optimum moves
    assert get_optimizer("IHPO").defaults["alpha_on"] == "literal"
    plain, shifted = plain_and_shifted("IHPO", None, runs=4)
    assert plain == 0.0 and shifted > 1e-8, (plain, shifted)


# -------------------------------------------------------------------------- parameter readings
ALTERNATIVES = [
    ("HPO", "prey_step", "2Z"), ("HPO", "prey_angle", "from_z"), ("HPO", "hunter", "relative"),
    ("IHPO", "alpha_on", "displacement"), ("IHPO", "alpha_on", "step"),
    ("IHPO", "alpha_on", "position"), ("IHPO", "alpha_branches", "hunter"),
    ("IHPO", "alpha_branches", "prey"), ("IHPO", "beta_draw", "iteration"),
    ("IHPO", "beta_draw", "dimension"), ("IHPO", "cp_c", "one"), ("IHPO", "hunter", "relative"),
    ("IHPO", "prey_step", "2Z"), ("IHPO", "prey_angle", "from_z"),
    ("HPO", "update", "synchronous"), ("IHPO", "update", "synchronous"),
    ("RFO", "alpha_draw", "fox"), ("RFO", "kappa_draw", "fox"),
    ("RFO", "reproduction", "scaled_centre"), ("RFO", "local_greedy", True),
]


def test_alternatives_list_every_choice():
    listed = {(a, k, v) for a, k, v in ALTERNATIVES}
    for algo in ("HPO", "IHPO", "RFO"):
        cls = get_optimizer(algo)
        for key, values in cls.choices.items():
            for v in values:
                assert v == cls.defaults[key] or (algo, key, v) in listed or (
                    key, v) == ("hunter", "centre"), (algo, key, v)  # centre: test below


@pytest.mark.parametrize(("algo", "key", "value"), ALTERNATIVES)
def test_alternative_changes_the_run(algo, key, value):
    kw = dict(dim=6, agents=30, iterations=30, runs=2, seed=3)  # RFO: 2 new foxes per iteration
    base = minimize(algo, "F5", **kw)
    alt = minimize(algo, "F5", params={key: value}, **kw)
    assert not np.array_equal(base.curve, alt.curve)


def boxed_problem(lower, upper, runs=2):
    f = get_function("F1")
    return Problem(lambda X, s: f.kernel(X - 3.0), np.full((runs, 5), lower),
                   np.full((runs, 5), upper))


@pytest.mark.parametrize("algo", ["HPO", "IHPO"])
def test_hpo_centre_hunter_is_the_paper_rule_on_symmetric_boxes_only(algo):
    """For IHPO this includes eq 14a's alpha, which scales P about the box centre."""
    def curve(problem, hunter):
        opt = create(algo, problem, agents=10, iterations=40, streams=RunStreams.for_runs(2, 2),
                     params={"hunter": hunter})
        out = []
        while not opt.done:
            opt.step()
            out.append(opt.best_fitness.copy())
        return np.array(out)

    sym = boxed_problem(-10.0, 10.0)
    assert np.array_equal(curve(sym, "paper"), curve(sym, "centre"))
    shifted_box = boxed_problem(-2.0, 18.0)
    assert not np.array_equal(curve(shifted_box, "paper"), curve(shifted_box, "centre"))


def test_rfo_local_greedy_keeps_the_population_best_monotone():
    def population_best(params):
        problem = boxed_problem(-10.0, 10.0, runs=4)
        opt = create("RFO", problem, agents=10, iterations=60, streams=RunStreams.for_runs(5, 4),
                     params=params)
        out = []
        while not opt.done:
            opt.step()
            out.append(opt.F.min(axis=1))
        return np.array(out)

    greedy = population_best({"local_greedy": True})
    assert np.all(np.diff(greedy, axis=0) <= 0.0)
    # the paper's unconditional local move can lose the population's best point
    assert np.any(np.diff(population_best(None), axis=0) > 0.0)


# ------------------------------------------------------------------------ rounding and guards
def test_matlab_round_is_half_away_from_zero():
    assert [matlab_round(x) for x in (0.5, 1.5, 2.5, -0.5, -2.5, 0.49, 2.4999)] == [
        1, 2, 3, -1, -3, 0, 2,
    ]


def test_kbest_schedule_and_guard_for_small_populations():
    T = 500
    assert hpo_kbest(hpo_c(1, T), 30) == 30
    assert hpo_kbest(hpo_c(T, T), 30) == 1  # round(0.6) = 1
    # N = 10: C N < 0.5 late in the run (the authors' code would index 0); guard keeps 1
    late = [t for t in range(1, T + 1) if 10 * hpo_c(t, T) < 0.5]
    assert late and all(hpo_kbest(hpo_c(t, T), 10) == 1 for t in late)
    assert [hpo_kbest(c, 10) for c in (0.25, 0.35, 0.15)] == [3, 4, 2]  # 2.5 -> 3, 3.5 -> 4


@pytest.mark.parametrize("algo", ["HPO", "IHPO"])
def test_small_population_runs_to_the_end_and_hunts_the_nearest(algo):
    res = minimize(algo, "F1", dim=5, agents=10, iterations=200, runs=3, seed=2)
    assert np.all(np.isfinite(res.best_fitness))
    assert np.array_equal(res.evaluations, np.full(3, 10 * 201))
    # kbest picks the kbest-th nearest agent to the mean; kbest = 1 at the end: the nearest
    problem = boxed_problem(-10.0, 10.0, runs=1)
    opt = create(algo, problem, agents=4, iterations=5, streams=RunStreams.for_runs(1, 1))
    opt.initialize()
    opt.X = np.array([[[5.0] * 5, [0.1] * 5, [-1.0] * 5, [3.0] * 5]])  # mean 1.775
    for k, expected in ((1, 3), (2, 1), (3, 2), (4, 0)):  # distances: 3.2, 1.7, 2.8, 1.2 (x sqrt 5)
        P, mu = opt._hunter_anchor(0.5, k)
        assert np.allclose(mu, 1.775) and np.array_equal(P[0], opt.X[0, expected])


def test_rfo_counts_and_small_populations():
    res = minimize("RFO", "F1", dim=4, agents=30, iterations=20, runs=2, seed=1)
    # N init + per iteration: N - 1 (global), round(0.25 N) = 8 (local), round(0.05 N) = 2 (new)
    assert np.array_equal(res.evaluations, np.full(2, 30 + 20 * (29 + 8 + 2)))
    for n, rep, move in ((2, 0, 1), (3, 1, 1), (10, 1, 3), (30, 2, 8), (50, 3, 13)):
        opt = create("RFO", boxed_problem(-1.0, 1.0), agents=n, iterations=3,
                     streams=RunStreams.for_runs(1, 2))
        assert (opt.replaced(), opt.movers()) == (rep, move)
        while not opt.done:
            opt.step()
        assert np.all(np.isfinite(opt.best_fitness))


# ------------------------------------------------------- IHPO's published F5, F6, F12, F13
# IHPO column of Table 2 (seed 001): average and minimum best over "1000 times".
PUBLISHED_IHPO = {"F5": (0.4859, 4.9762e-16), "F6": (5.6221e-15, 0.0),
                  "F12": (7.5616e-10, 1.5705e-32), "F13": (0.1109, 0.0974)}


def optimum_at_origin(name):
    """The function moved so that its minimiser is the origin (hypothesis of issue 10)."""
    f = get_function(name)
    c = f.optimum_coordinate
    return replace(f, name=f"{name}@0", kernel=lambda x: f.kernel(x + c), optimum_coordinate=0.0)


@pytest.mark.parametrize("function", sorted(PUBLISHED_IHPO))
def test_ihpo_published_cells_need_the_optimum_at_the_origin(function):
    """No reading reaches the published F5/F6/F12/F13 on the standard functions (optima at 1,
    -0.5, -1, 1); with the optimum moved to the origin every run is exactly 0, as the published
    minima of F5, F6, F12 are (to 1e-15). F13's published minimum (0.097) is not 0: the
    hypothesis explains F5, F6, F12 only."""
    avg, low = PUBLISHED_IHPO[function]
    standard = paper_run("IHPO", function, runs=3).best_fitness
    assert standard.min() > 10.0 * avg, standard
    moved = paper_run("IHPO", optimum_at_origin(function), runs=3).best_fitness
    assert np.all(moved == 0.0), moved
    if function == "F13":
        assert moved.max() < low
    else:
        assert low <= 1e-15


def test_ihpo_with_the_centre_hunter_is_translation_covariant():
    """hunter = "centre" (the planners): eq 14a's alpha scales P about the box centre, so moving
    the box and the objective together moves the whole run (no pull toward the world origin)."""
    def best(shift):
        f = get_function("F1")
        problem = Problem(lambda X, s: f.kernel(X - 3.0 - shift), np.full((2, 5), -10.0 + shift),
                          np.full((2, 5), 10.0 + shift))
        opt = create("IHPO", problem, agents=10, iterations=12,
                     streams=RunStreams.for_runs(2, 2), params={"hunter": "centre"})
        while not opt.done:
            opt.step()
        return opt.best_fitness, opt.best_position - shift

    f0, x0 = best(0.0)
    f1, x1 = best(40.0)
    assert np.allclose(f0, f1, rtol=1e-6) and np.allclose(x0, x1, atol=1e-6)
    paper = create("IHPO", Problem(lambda X, s: np.sum((X - 43.0) ** 2, axis=-1),
                                   np.full((2, 5), 30.0), np.full((2, 5), 50.0)),
                   agents=10, iterations=12, streams=RunStreams.for_runs(2, 2))
    while not paper.done:
        paper.step()
    assert not np.allclose(paper.best_fitness, f0, rtol=1e-3)  # the paper's rule is not
