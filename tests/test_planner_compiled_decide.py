"""The swarm planners' compiled decisions (planners.compiled_decide, compiled_score): the same
numbers as the numpy optimizer loop and ``local.score``, to the last bit, and the same draws."""

import dataclasses

import numpy as np
import pytest

from swarmpath.optimizers import RunStreams, get_optimizer
from swarmpath.planners import compiled_decide, get_planner, list_planners, local
from swarmpath.planners.swarm_search import numpy_search

PLANNER = get_planner("ICOOT")
REPAIRS = PLANNER.choices["repair"]
OBJECTIVES = PLANNER.choices["objective"]


def _context(rng, repair="grid", objective="cost", hits=60):
    p = rng.uniform(1.0, 2.0, 2)
    wall = np.stack([np.full(hits // 2, p[0] + 0.45), p[1] + np.linspace(-0.6, 0.6, hits // 2)],
                    axis=1)
    scattered = p + rng.uniform(-1.0, 1.0, (hits - hits // 2, 2))
    return local.StepContext(
        position=p, goal=p + rng.uniform(-3.0, 3.0, 2), hits=np.vstack([wall, scattered]),
        margin=float(rng.uniform(0.08, 0.15)), repair=repair, objective=objective, safety=0.02,
        lower=np.maximum(p - 0.8, 0.0), upper=p + 0.8)


@pytest.mark.parametrize("repair", REPAIRS)
@pytest.mark.parametrize("objective", OBJECTIVES)
def test_compiled_score_equals_numpy(repair, objective):
    rng = np.random.default_rng(len(repair) + 10 * len(objective))
    for hits in (0, 1, 40, 90):
        ctx = _context(rng, repair, objective, hits)
        fast = dataclasses.replace(ctx, backend="numba")
        for m in (1, 7, 78):
            C = ctx.position + rng.uniform(-0.9, 0.9, (m, 2))
            ref, got = local.score(C, ctx), local.score(C, fast)
            assert np.array_equal(ref[0], got[0]) and np.array_equal(ref[1], got[1])
            if hits > 1 and m == 78:
                assert np.any(ref[0] >= local.PENALTY) and np.any(ref[0] < local.PENALTY)


def _planner_settings():
    """(optimizer, optimizer parameters, agents, iterations, repair, objective) of every swarm
    planner preset whose optimizer has a compiled decision."""
    out = []
    for name in list_planners():
        cls = get_planner(name)
        optimizer = cls.defaults.get("optimizer")
        if "backend" in cls.defaults and optimizer in compiled_decide.names():
            params = get_optimizer(optimizer).resolve_params(cls.optimizer_params)
            out.append((name, optimizer, params, cls.defaults["agents"],
                        cls.defaults["iterations"], cls.defaults["repair"],
                        cls.defaults["objective"]))
    return out


SETTINGS = _planner_settings()


@pytest.mark.parametrize("setting", SETTINGS, ids=[s[0] for s in SETTINGS])
@pytest.mark.parametrize("patience", [0, 1])
def test_compiled_decision_equals_numpy(setting, patience):
    _, optimizer, params, agents, iterations, repair, objective = setting
    decide = compiled_decide.decider(optimizer, params, agents)
    assert decide is not None
    rng = np.random.default_rng(agents + patience)
    stopped = 0
    for case in range(6):
        ctx = _context(rng, repair, objective, (0, 30, 60, 90, 120, 60)[case])
        a, b = np.random.default_rng(case), np.random.default_rng(case)
        ref = numpy_search(optimizer, params, RunStreams([a]), ctx, agents, iterations,
                           patience, 1e-6)
        got = decide(b, dataclasses.replace(ctx, backend="numba"), agents, iterations, patience,
                     1e-6)
        assert ref[0] == got[0] and np.array_equal(ref[1], got[1]) and ref[2] == got[2]
        assert a.random() == b.random()  # the same draws, no more
        stopped += ref[2] < iterations
    assert stopped > 0 if patience else stopped == 0


def test_planners_with_compiled_decisions():
    """ICOOT, IHPO, MFB and HPSO-MFB (the issue's swarm planners) all have one."""
    assert {s[0] for s in SETTINGS} >= {"ICOOT", "IHPO", "MFB", "HPSO-MFB"}


VARIANTS = [
    ("ICOOT", {"randoms": "vector", "gbest": "any", "random_target": "offset"}),
    ("ICOOT", {"leader_update": "paper", "mirror": "plus", "counter": "paper", "acc": "one"}),
    ("COOT", {"randoms": "scalar", "leaders": 3}),
    ("IHPO", {"alpha_on": "step", "beta_draw": "iteration", "cp_c": "one"}),
    ("IHPO", {"alpha_on": "displacement", "alpha_branches": "prey", "hunter": "relative"}),
    ("IHPO", {"alpha_on": "position", "alpha_branches": "hunter", "prey_step": "2Z",
              "prey_angle": "from_z"}),
    ("IHPO", {"hunter": "paper", "beta": 0.4}),
    ("HPO", {"hunter": "centre", "beta": 0.3}),
    ("MFB", {"beta_time": "literal", "beta_r": "pulse", "velocity": "literal"}),
    ("MFB", {"beta_time": "uniform", "beta_per": "dimension", "walk_scale": "absolute"}),
    ("MFB", {"accept": "own", "move": "always", "update": "accept", "beta_per": "dimension"}),
    ("HPSO-MFB", {"restart": "none", "best": "swarm", "split": "per_particle"}),
    ("HPSO-MFB", {"split": "divide", "pso_iterations": 2, "particles": 3}),
]


@pytest.mark.parametrize("variant", VARIANTS, ids=[f"{v[0]}-{i}" for i, v in enumerate(VARIANTS)])
def test_compiled_decision_variants_equal_numpy(variant):
    """The other parameter values the kernels implement, on harder settings (more agents and
    iterations, every repair and objective)."""
    optimizer, settings = variant
    params = get_optimizer(optimizer).resolve_params(settings)
    agents, iterations = 12, 9
    decide = compiled_decide.decider(optimizer, params, agents)
    assert decide is not None
    rng = np.random.default_rng(len(str(settings)))
    for case, (repair, objective) in enumerate(
            (r, o) for r in REPAIRS for o in OBJECTIVES):
        ctx = _context(rng, repair, objective, 40 + 10 * case)
        a, b = np.random.default_rng(case), np.random.default_rng(case)
        ref = numpy_search(optimizer, params, RunStreams([a]), ctx, agents, iterations, 0, 1e-6)
        got = decide(b, dataclasses.replace(ctx, backend="numba"), agents, iterations, 0, 1e-6)
        assert ref[0] == got[0] and np.array_equal(ref[1], got[1]) and ref[2] == got[2]
        assert a.random() == b.random()


def test_unimplemented_settings_run_the_numpy_loop():
    for optimizer, settings, agents in (("HPO", {"update": "synchronous"}, 10),
                                        ("IHPO", {"beta_draw": "dimension"}, 10),
                                        ("HPSO-MFB", {"restart": "cold"}, 10),
                                        ("HPSO-MFB", {}, 1), ("ICOOT", {"leaders": 4}, 4)):
        params = get_optimizer(optimizer).resolve_params(settings)
        assert compiled_decide.decider(optimizer, params, agents) is None


def test_hunter_anchor_is_the_stable_argsorts():
    """IHPO's prey P (``HPO._hunter_anchor``): the kbest-th agent of the stable argsort of the
    distances to the mean, ties (repeated agents, rounded coordinates) by index."""
    from swarmpath.planners.compiled_hpo import _anchor

    rng = np.random.default_rng(3)
    tied = 0
    for _ in range(400):
        n = int(rng.integers(1, 90))
        X = np.round(rng.uniform(0.0, 1.0, (1, n, 2)), int(rng.integers(1, 4)))
        X[0, rng.integers(0, n, n // 3)] = X[0, 0]
        kbest = int(rng.integers(1, n + 1))
        mu = X.mean(axis=1)
        diff = X - mu[:, None, :]
        dist2 = np.einsum("rnd,rnd->rn", diff, diff)[0]
        ref = X[0, np.argsort(dist2, kind="stable")[kbest - 1]]
        P, got_mu = np.empty(2), np.empty(2)
        _anchor(np.ascontiguousarray(X[0]), kbest, P, got_mu)
        assert np.array_equal(P, ref) and np.array_equal(got_mu, mu[0])
        tied += int(np.sum(dist2 == dist2[np.argsort(dist2, kind="stable")[kbest - 1]]) > 1)
    assert tied > 50
