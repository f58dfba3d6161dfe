"""swarmpath.metrics against hand-computed values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from swarmpath.metrics import (
    ClearanceResult,
    ContactCauses,
    contact_causes,
    final_error,
    gap,
    heading_smoothness,
    min_clearance,
    ompl_smoothness,
    path_length,
    step_clearances,
)
from swarmpath.world.geometry import ObstacleSet


def _traj(*rows: tuple[float, float, float]) -> np.ndarray:
    return np.asarray(rows, dtype=float)


def test_path_length_and_final_error() -> None:
    p = _traj((0, 0, 0), (3, 4, 1), (3, 4, 2), (6, 8, 3))
    assert path_length(p) == 10.0
    assert path_length(p[:, :2]) == 10.0
    assert path_length(p[:1]) == 0.0
    assert final_error(p, (9, 12)) == 5.0
    assert final_error(p, np.array([6.0, 8.0])) == 0.0


def test_heading_smoothness() -> None:
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    assert heading_smoothness(square) == pytest.approx(math.pi)
    # a stop (repeated point) is not a turn
    stop = np.array([[0, 0], [1, 0], [1, 0], [1, 1]], dtype=float)
    assert heading_smoothness(stop) == pytest.approx(math.pi / 2)
    assert heading_smoothness(np.array([[0, 0], [1, 0], [0, 0]], dtype=float)) == pytest.approx(
        math.pi
    )
    # headings 170 deg then -170 deg: a 20 deg turn, not 340
    a, b = math.radians(170), math.radians(-170)
    p = np.array(
        [[0, 0], [math.cos(a), math.sin(a)], [math.cos(a) + math.cos(b), math.sin(a) + math.sin(b)]]
    )
    assert heading_smoothness(p) == pytest.approx(math.radians(20))
    assert heading_smoothness(np.array([[0, 0], [1, 1], [2, 2], [5, 5]], dtype=float)) == 0.0
    assert heading_smoothness(_traj((0, 0, 0), (1, 0, 1))) == 0.0


def test_ompl_smoothness() -> None:
    # right angle, a = b = 1: cos = 0, outside angle pi/2, k = 2 (pi/2) / 2
    corner = np.array([[0, 0], [1, 0], [1, 1]], dtype=float)
    assert ompl_smoothness(corner) == pytest.approx((math.pi / 2) ** 2)
    # right angle, a = 1, b = 2: k = pi / 3
    assert ompl_smoothness(np.array([[0, 0], [1, 0], [1, 2]], dtype=float)) == pytest.approx(
        (math.pi / 3) ** 2
    )
    # two corners add up; straight vertices add 0
    zig = np.array([[0, 0], [1, 0], [2, 0], [2, 1], [3, 1]], dtype=float)
    assert ompl_smoothness(zig) == pytest.approx(2 * (math.pi / 2) ** 2)
    # 45 degree turn with a = b = 2: k = 2 (pi/4) / 4
    p = np.array([[0, 0], [2, 0], [2 + math.sqrt(2), math.sqrt(2)]])
    assert ompl_smoothness(p) == pytest.approx((math.pi / 8) ** 2)
    # OMPL quirks: an exact reversal (cos = 1) and zero-length steps add nothing
    assert ompl_smoothness(np.array([[0, 0], [1, 0], [0, 0]], dtype=float)) == 0.0
    assert ompl_smoothness(np.array([[0, 0], [1, 0], [1, 0], [1, 1]], dtype=float)) == 0.0
    assert ompl_smoothness(corner[:2]) == 0.0
    assert ompl_smoothness(_traj((0, 0, 0), (1, 0, 1), (1, 1, 2))) == pytest.approx(
        (math.pi / 2) ** 2
    )


def test_gap() -> None:
    assert gap(11.0, 10.0) == pytest.approx(0.1)
    assert gap(10.0, 10.0) == 0.0
    assert math.isnan(gap(10.0, math.nan))
    assert math.isnan(gap(10.0, math.inf))
    assert math.isnan(gap(10.0, 0.0))
    assert math.isnan(gap(math.nan, 10.0))
    assert gap(math.inf, 10.0) == math.inf
    # the optimum's straight line, summed in pieces, is a few ulps short of its own length
    line = np.array([[i * 0.03 / 5, i * 0.09 / 5] for i in range(6)])
    summed = float(np.hypot(*np.diff(line, axis=0).T).sum())
    straight = float(np.hypot(*line[-1]))
    assert summed < straight  # round-off, not a shorter path
    assert gap(summed, straight) == 0.0 and f"{100 * gap(summed, straight):.2f}" == "0.00"
    assert gap(0.99, 1.0) == pytest.approx(-0.01)  # a real shortfall stays visible


def test_static_clearance_and_touching_counts() -> None:
    obs = ObstacleSet(np.array([[5.0, 1.0, 0.5]]), ())
    p = _traj((0, 0, 0), (5, 0, 5), (10, 0, 10))
    r = min_clearance(p, lambda t: obs, 0.3)
    assert isinstance(r, ClearanceResult)
    assert r.min_gap == pytest.approx(0.2) and r.collisions == 0
    r = min_clearance(p, obs, 0.5)  # a static ObstacleSet is accepted too
    assert r.min_gap == pytest.approx(0.0) and r.collisions == 2  # both steps touch at (5, 0)
    assert min_clearance(p, ObstacleSet.empty(), 0.3) == (math.inf, 0)
    # a single row is a zero-length step
    assert min_clearance(p[:1], obs, 0.3).min_gap == pytest.approx(math.hypot(5, 1) - 0.8)


def test_moving_circle_passing_through_between_samples() -> None:
    # robot parked at the origin; a circle sweeps across it within one step
    def obs_at(t: float) -> ObstacleSet:
        return ObstacleSet(np.array([[-2.0 + 4.0 * t, 0.0, 0.5]]), ())

    p = _traj((0, 0, 0), (0, 0, 1))
    assert obs_at(0).point_clearance(np.zeros(2)) == 1.5  # both samples look safe
    r = min_clearance(p, obs_at, 0.2)
    assert r == (-0.2, 1)


def test_moving_circle_relative_motion() -> None:
    # robot (0,0) -> (4,0) while the circle goes (4,2) -> (0,2): closest at t = 0.5, distance 2
    def obs_at(t: float) -> ObstacleSet:
        return ObstacleSet(np.array([[4.0 - 4.0 * t, 2.0, 0.5]]), ())

    p = _traj((0, 0, 0), (4, 0, 1))
    assert step_clearances(p, obs_at) == pytest.approx([1.5])
    r = min_clearance(p, obs_at, 0.25)
    assert r.min_gap == pytest.approx(1.25) and r.collisions == 0


def test_moving_polygon() -> None:
    sq = np.array([[2, 1], [3, 1], [3, 2], [2, 2]], dtype=float)

    def obs_at(t: float) -> ObstacleSet:
        return ObstacleSet(np.zeros((0, 3)), (sq + np.array([-5.0 * t, 0.0]),))

    p = _traj((0, 0, 0), (0, 0, 1))
    # relative to the square the robot sweeps (0,0) -> (5,0): passes 1 m under it
    assert step_clearances(p, obs_at) == pytest.approx([1.0])
    inside = ObstacleSet(np.zeros((0, 3)), (sq - np.array([2.5, 1.5]),))

    def hit_at(t: float) -> ObstacleSet:
        return ObstacleSet(np.zeros((0, 3)), (sq + np.array([-2.5 * t, -1.5 * t]),))

    assert inside.point_clearance(np.zeros(2)) < 0
    assert min_clearance(p, hit_at, 0.1) == (-0.1, 1)


def test_sampling_never_beats_the_exact_step_clearance() -> None:
    rng = np.random.default_rng(3)
    n = 12
    t = np.cumsum(rng.uniform(0.1, 0.5, n))
    t -= t[0]
    xy = np.cumsum(rng.uniform(-0.6, 0.6, (n, 2)), axis=0)
    p = np.column_stack([xy, t])
    c0 = rng.uniform(-2, 2, (3, 2))
    v = rng.uniform(-1, 1, (3, 2))
    shape = np.array([[0, 0], [1, 0], [0.5, 0.8]])
    w = rng.uniform(-1, 1, 2)

    def obs_at(tt: float) -> ObstacleSet:
        return ObstacleSet(np.column_stack([c0 + v * tt, [0.3, 0.4, 0.5]]), (shape + w * tt,))

    exact = step_clearances(p, obs_at)
    for i in range(n - 1):
        ts = np.linspace(t[i], t[i + 1], 401)
        f = (ts - t[i]) / (t[i + 1] - t[i])
        pos = xy[i] + f[:, None] * (xy[i + 1] - xy[i])
        sampled = min(
            max(float(obs_at(tt).point_clearance(q)), 0.0) for tt, q in zip(ts, pos, strict=True)
        )
        assert exact[i] <= sampled + 1e-12
        assert sampled - exact[i] < 5e-3


def test_static_steps_equal_segment_clearance() -> None:
    rng = np.random.default_rng(5)
    obs = ObstacleSet(
        np.column_stack([rng.uniform(0, 10, (4, 2)), rng.uniform(0.2, 1, 4)]),
        (np.array([[4, 4], [6, 4], [5, 6]], dtype=float),),
    )
    xy = rng.uniform(0, 10, (20, 2))
    p = np.column_stack([xy, np.arange(20.0)])
    assert np.allclose(step_clearances(p, obs), obs.segment_clearance(xy[:-1], xy[1:]), atol=1e-12)


def test_invalid_inputs() -> None:
    obs = ObstacleSet(np.array([[0.0, 0.0, 1.0]]), ())
    with pytest.raises(ValueError, match="non-decreasing"):
        step_clearances(_traj((5, 5, 1), (6, 6, 0)), obs)
    with pytest.raises(ValueError, match="x, y, t"):
        step_clearances(np.zeros((3, 2)), obs)
    with pytest.raises(ValueError, match="same obstacles"):
        step_clearances(
            _traj((5, 5, 0), (6, 6, 1)), lambda t: obs if t < 0.5 else ObstacleSet.empty()
        )
    with pytest.raises(ValueError, match="radii"):
        step_clearances(
            _traj((5, 5, 0), (6, 6, 1)),
            lambda t: ObstacleSet(np.array([[0.0, 0.0, 1.0 + t]]), ()),
        )
    tri = np.array([[0, 0], [1, 0], [0, 1]], dtype=float)
    with pytest.raises(ValueError, match="shape"):
        step_clearances(
            _traj((5, 5, 0), (6, 6, 1)),
            lambda t: ObstacleSet(np.zeros((0, 3)), (tri * (1 + t),)),
        )
    with pytest.raises(ValueError):
        path_length(np.zeros(3))


def test_contact_causes_static_obstacle_is_robot_driven() -> None:
    obs = ObstacleSet(np.array([[5.0, 0.0, 0.5]]), ())
    p = _traj((3, 0, 0), (4.4, 0, 1), (4.4, 0, 2))  # drives in, then stands in contact
    assert min_clearance(p, obs, 0.2).collisions == 2
    assert contact_causes(p, obs, 0.2) == ContactCauses(2, 0)
    assert contact_causes(p, obs, 0.05) == ContactCauses(0, 0)


def test_contact_causes_moving_obstacle_reaching_a_still_or_fleeing_robot() -> None:
    def obs_at(t: float) -> ObstacleSet:  # a circle closing in at 3 m/s along -x
        return ObstacleSet(np.array([[4.0 - 3.0 * t, 0.0, 0.5]]), ())

    still = _traj((0, 0, 0), (0, 0, 1), (0, 0, 2))  # passed over in the second step
    assert min_clearance(still, obs_at, 0.3).collisions == 1
    assert contact_causes(still, obs_at, 0.3) == ContactCauses(0, 1)
    fleeing = _traj((0, 0, 0), (-0.5, 0, 1), (-1.0, 0, 2))  # away at 0.5 m/s: still caught
    assert min_clearance(fleeing, obs_at, 0.3).collisions == 1
    assert contact_causes(fleeing, obs_at, 0.3) == ContactCauses(0, 1)
    sideways = _traj((0, 0, 0), (0, 0.1, 1), (0, 0.2, 2))  # moves off the obstacle's line
    assert contact_causes(sideways, obs_at, 0.3) == ContactCauses(0, 1)
    # head-on: in the first step the robot drives into it; in the second it is inside and
    # leaves it (moving away from where the obstacle was) while the obstacle passes
    head_on = _traj((0, 0, 0), (1, 0, 1), (2, 0, 2))
    assert min_clearance(head_on, obs_at, 0.3).collisions == 2
    assert contact_causes(head_on, obs_at, 0.3) == ContactCauses(1, 1)
