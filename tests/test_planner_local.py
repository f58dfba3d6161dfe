"""The local planner's objective, feasibility and repairs (pure functions)."""

import numpy as np
import pytest

from swarmpath.planners import local


def ctx(hits, repair="mfb", **kw):
    return local.StepContext(
        position=np.array([0.0, 0.0]),
        goal=np.array([4.0, 0.0]),
        hits=np.asarray(hits, dtype=float).reshape(-1, 2),
        margin=0.5,
        repair=repair,
        lower=np.array([-1.0, -1.0]),
        upper=np.array([1.0, 1.0]),
        **kw,
    )


def test_cost_prefers_progress_and_heading():
    c = ctx([])
    near, far, off = np.array([[0.5, 0.0], [1.0, 0.0], [0.0, 1.0]])
    costs = local.raw_cost(np.stack([near, far, off]), c)
    assert costs[1] < costs[0] < costs[2]
    # f2 is the wrapped absolute heading error: 90 degrees off costs w2 * pi/2 on top of f1
    assert costs[2] == pytest.approx(0.9 * np.hypot(4, 1) + 0.1 * np.pi / 2)


def test_inverse_objective_keeps_the_ranking():
    cands = np.array([[0.5, 0.0], [1.0, 0.0], [0.0, 1.0]])
    a, _ = local.score(cands, ctx([]))
    b, _ = local.score(cands, ctx([], objective="inverse"))
    assert np.array_equal(np.argsort(a), np.argsort(b))


@pytest.mark.parametrize("mode", ["mfb", "grid"])
def test_repair_makes_blocked_candidates_feasible(mode):
    hits = [[0.8, y] for y in np.linspace(-0.05, 0.05, 3)]  # a small obstacle ahead
    c = local.StepContext(
        position=np.array([0.0, 0.0]), goal=np.array([4.0, 0.0]), hits=np.array(hits),
        margin=0.3, repair=mode, lower=np.array([-2.0, -2.0]), upper=np.array([2.0, 2.0]),
    )
    blocked = np.array([[1.5, 0.0], [0.8, 0.1], [1.2, -0.1]])
    assert np.all(local.violation(blocked, c) > 0)
    fixed = local.repair(blocked, c)
    assert np.all(local.violation(fixed, c) == 0), fixed
    assert np.all(fixed >= c.lower) and np.all(fixed <= c.upper)


def test_mfb_case1_pushes_radially_to_margin_plus_safety():
    c = local.StepContext(
        position=np.array([0.5, 2.0]), goal=np.array([0.5, 4.0]), hits=np.array([[0.5, 0.0]]),
        margin=0.5, safety=0.05,
    )
    fixed = local.repair_mfb(np.array([[0.5, 0.2]]), c, rounds=1)
    # eqs 19-20: moved along the obstacle->candidate direction to margin + ds from the obstacle
    assert fixed[0] == pytest.approx([0.5, 0.55])


def test_no_repair_penalises():
    c = ctx([[0.6, 0.0]], repair="none")
    cost, fixed = local.score(np.array([[1.0, 0.0], [0.0, -1.0]]), c)
    assert cost[0] >= local.PENALTY and cost[1] < local.PENALTY
    assert np.array_equal(fixed, [[1.0, 0.0], [0.0, -1.0]])


def test_unknown_modes_are_named():
    with pytest.raises(ValueError, match="valid: mfb, grid, none"):
        local.repair(np.zeros((1, 2)), ctx([], repair="magic"))


def test_hit_distances_match_the_geometry_module():
    from swarmpath.world.geometry import point_segment_distance

    rng = np.random.default_rng(7)
    p = rng.uniform(-1, 1, 2)
    C = rng.uniform(-2, 2, (3, 5, 2))
    C[0, 0] = p  # a zero-length segment
    hits = rng.uniform(-2, 2, (11, 2))
    d_seg, i_seg = local.segment_hit_distance(p, C, hits)
    full = point_segment_distance(hits, p, C[..., None, :])
    assert np.allclose(d_seg, full.min(axis=-1)) and np.array_equal(i_seg, full.argmin(axis=-1))
    d_pt, i_pt = local.point_hit_distance(C, hits)
    direct = np.hypot(*np.moveaxis(C[..., None, :] - hits, -1, 0))
    assert np.allclose(d_pt, direct.min(axis=-1)) and np.array_equal(i_pt, direct.argmin(-1))


@pytest.mark.parametrize("mode", ["mfb", "grid"])
def test_score_penalises_exactly_what_stays_infeasible(mode):
    rng = np.random.default_rng(3)
    hits = np.array([[0.5, y] for y in np.linspace(-0.3, 0.3, 7)])
    c = ctx(hits, repair=mode)
    cands = rng.uniform(-1, 1, (40, 2))
    cost, fixed = local.score(cands, c)
    left = local.violation(fixed, c)
    assert np.array_equal(cost >= local.PENALTY, left > 0)
    assert np.allclose(cost[left > 0], local.PENALTY + left[left > 0])


@pytest.mark.parametrize("mode", ["mfb", "grid", "none"])
@pytest.mark.parametrize("objective", ["cost", "inverse"])
def test_score_is_rowwise(mode, objective):
    """A candidate's score and repair do not depend on the candidates scored with it, to the last
    bit: the swarm planners' problems say so (``Problem.rowwise``) and HPO's sweep relies on it."""
    rng = np.random.default_rng(5)
    wall = np.stack([np.full(40, 0.6), np.linspace(-0.8, 0.8, 40)], axis=1)
    hits = np.vstack([wall, rng.uniform(-1.2, 1.2, (25, 2))])
    c = ctx(hits, mode, objective=objective, safety=0.05)
    cands = rng.uniform(-1.0, 1.0, (120, 2))
    cost, fixed = local.score(cands, c)
    assert np.any(cost >= local.PENALTY) or mode != "none"
    for k in range(0, 120, 7):
        one, one_fixed = local.score(cands[k : k + 1], c)
        assert one[0] == cost[k] and np.array_equal(one_fixed[0], fixed[k])
    sub = np.arange(3, 120, 4)
    part, part_fixed = local.score(cands[sub], c)
    assert np.array_equal(part, cost[sub]) and np.array_equal(part_fixed, fixed[sub])
