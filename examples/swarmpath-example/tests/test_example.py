"""The example plugin's own tests: swarmpath's conformance gate (swarmpath.testing) on both
extensions, the variant's equation, and the design problem against the literature."""

from __future__ import annotations

import numpy as np
import pytest
from swarmpath.optimizers import Problem, RunStreams, minimize
from swarmpath.testing import check_function, check_optimizer

from swarmpath_example import MGWO
from swarmpath_example.spring import F_BEST, SPRING, X_BEST, constraints, weight


def test_mgwo_passes_the_conformance_gate():
    report = check_optimizer(MGWO)  # raises naming any property that fails
    assert report.ok and "origin-bias" in report.info


def test_spring_design_passes_the_conformance_gate():
    assert check_function(SPRING).ok


def test_mgwo_decays_a_as_its_paper_says():
    problem = Problem(lambda X, s: np.zeros(X.shape[:2]), np.zeros((1, 2)), np.ones((1, 2)))
    opt = MGWO(problem, agents=5, iterations=100, streams=RunStreams.for_runs(0, 1))
    a = []
    for t in range(1, 101):
        opt.t = t
        a.append(opt.control())
    a = np.array(a)
    done = np.arange(100) / 100
    assert np.array_equal(a, 2.0 * (1.0 - done * done))  # eq. 7, t counted from 0
    assert np.mean(a > 1.0) == pytest.approx(1 / np.sqrt(2), abs=0.01)  # explores 71 % of the run
    gwo = 2.0 * (1.0 - done)
    assert np.all(a[1:] > gwo[1:])  # never below GWO's linear schedule


def test_mgwo_differs_from_gwo_only_by_its_schedule():
    kw = dict(dim=5, agents=10, iterations=40, runs=3, seed=2)
    same = minimize("mGWO", "F9", **kw, params={"a_max": 2.0})
    assert not np.array_equal(same.curve, minimize("GWO", "F9", **kw).curve)
    # with one iteration both schedules give a = a_max: the same numbers
    one = dict(kw, iterations=1)
    assert np.array_equal(minimize("mGWO", "F9", **one).curve, minimize("GWO", "F9", **one).curve)


#: Designs and weights printed in Mirjalili et al. (2014), Table 9: d, D, N, weight
TABLE9 = {
    "GWO": (0.05169, 0.356737, 11.28885, 0.012666),
    "PSO (He and Wang)": (0.051728, 0.357644, 11.244543, 0.0126747),
    "DE (Huang et al.)": (0.051609, 0.354714, 11.410831, 0.0126702),
    "ES (Coello and Montes)": (0.051989, 0.363965, 10.890522, 0.0126810),
    "GA (Coello)": (0.051480, 0.351661, 11.632201, 0.0127048),
}  # HS (Mahdavi et al.) is left out: its printed design weighs 0.012887, not its 0.0126706


@pytest.mark.parametrize("who", TABLE9)
def test_literature_designs_weigh_what_they_print_and_are_above_the_known_best(who):
    *x, printed = TABLE9[who]
    w = float(weight(np.array(x)))
    assert w == pytest.approx(printed, rel=1e-4)  # the formulation is the literature's
    assert w > F_BEST


def test_known_best_is_a_feasible_constrained_minimum():
    from scipy.optimize import minimize as scipy_minimize

    x = np.array(X_BEST)
    assert np.all(constraints(x) <= 1e-12)
    assert float(weight(x)) == pytest.approx(F_BEST, rel=1e-14)
    lower, upper = SPRING.bounds(3)
    polished = scipy_minimize(weight, x, method="SLSQP", bounds=list(zip(lower, upper,
                                                                          strict=True)),
                              constraints=[{"type": "ineq", "fun": lambda y: -constraints(y)}],
                              options={"ftol": 1e-16, "maxiter": 500})
    assert polished.fun >= F_BEST - 1e-12  # no feasible neighbour is lighter


def test_mgwo_designs_a_spring_near_the_best_known():
    res = minimize("mGWO", "spring-design", dim=3, agents=30, iterations=500, runs=10, seed=1)
    assert res.best_fitness.min() <= 1.01 * F_BEST
    assert np.median(res.best_fitness) <= 1.02 * F_BEST
    assert np.all(constraints(res.best_position) <= 1e-9)  # the reported designs are feasible
