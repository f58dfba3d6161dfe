"""Giving way to moving obstacles (docs/planners.md, "Giving way to moving obstacles").

A circle crossing the robot's straight way to its goal from the side at 0.8 m/s (faster than the
0.5 m/s diff drive), timed to meet it: without ``give_way`` ICOOT drives into its path and is run
over; with it the robot keeps out of the circle's predicted path.
"""

import numpy as np
import pytest

from swarmpath.planners import Episode, give_way
from swarmpath.world.scenario import Motion, Obstacle, RobotSpec, Scenario


def crossing() -> Scenario:
    """Start (1, 5), goal (9, 5); a 0.3 m circle from (4.5, 11.64) straight down at 0.8 m/s,
    across y = 5 about 8.3 s later, when the robot gets there."""
    return Scenario(
        name="crossing", size=(10.0, 16.0), start=(1.0, 5.0), goal=(9.0, 5.0),
        robot=RobotSpec.preset("diff-drive"),
        obstacles=(Obstacle.circle((4.5, 5.0 + 0.8 * 8.3), 0.3, Motion(0.8, 270.0)),),
        sensors="icoot-80",
    )


def test_the_robot_gives_way_to_an_obstacle_crossing_its_path():
    # ICOOT, seed 1: run over without giving way (11 colliding steps, all obstacle-driven), no
    # contact with it (least body gap 0.144 m)
    off = Episode(crossing(), "ICOOT", seed=1, params={"give_way": 0.0}).run()
    assert off.obstacle_driven_contacts > 0
    on = Episode(crossing(), "ICOOT", seed=1).run()
    assert on.success and on.collisions == 0 and on.min_clearance > 0


def test_rollout_turns_in_place_then_drives_straight():
    p = np.array([0.0, 0.0])
    targets = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, 0.0]])
    # 1 rad/s of turning, 0.1 s steps: 90 degrees take 16 steps, 180 degrees 32
    c = give_way.rollout(p, 0.0, targets, 0.5, 1.0, 0.1, 40)
    assert np.allclose(c[0, :, 0], np.minimum(0.05 * np.arange(1, 41), 1.0))
    assert np.allclose(c[1, 15], [0.0, 0.0]) and np.allclose(c[1, 16], [0.0, 0.05])
    assert np.allclose(c[2, 31], [0.0, 0.0]) and np.allclose(c[2, 32], [-0.05, 0.0])
    assert np.allclose(c[3], 0.0)
    omni = give_way.rollout(p, 0.0, targets, 0.5, None, 0.1, 2)
    assert np.allclose(omni[2, 1], [-0.1, 0.0])


def test_steady_points_follow_their_velocity_erratic_ones_spread():
    centres = np.zeros((1, 10, 2))  # a robot standing at the origin for 1 s
    x = np.array([[1.0, 0.0]])
    v = np.array([[-0.5, 0.0]])
    steady = give_way.moving_gaps(centres, 0.1, x, v, np.array([True]), 1.0, 0.1)
    assert steady[0] == pytest.approx(1.0 - 0.5 - 0.1)  # at (0.5, 0) after 1 s
    erratic = give_way.moving_gaps(centres, 0.1, x, -v, np.array([False]), 1.0, 0.1)
    assert erratic[0] == pytest.approx(1.0 - 0.5 - 0.1)  # moving away, but may turn back
    half = give_way.moving_gaps(centres, 0.1, x, -v, np.array([False]), 0.5, 0.1)
    assert half[0] == pytest.approx(1.0 - 0.25 - 0.1)


def test_choose_keeps_a_safe_decision_else_the_safe_move_nearest_its_target():
    ends = np.array([[1.0, 0.0], [0.0, 0.0], [0.5, 0.5], [0.5, -0.5], [-1.0, 0.0]])
    wanted = np.array([1.0, 0.0])
    still = np.full(5, np.inf)
    safe = np.array([0.2, 0.2, 0.2, 0.2, 0.2])
    assert give_way.choose(safe, still, np.inf, 0.05, ends, wanted) == 0
    moving = np.array([0.0, -0.1, 0.1, 0.2, 0.3])
    assert give_way.choose(moving, still, np.inf, 0.05, ends, wanted) in (2, 3)
    # a move closer to a static point than the safety distance and than now is not taken
    still = np.array([np.inf, np.inf, 0.01, 0.01, np.inf])
    assert give_way.choose(moving, still, 0.2, 0.05, ends, wanted) == 4
    # nothing keeps the distance: the largest gap
    moving = np.array([-0.3, -0.2, -0.1, 0.0, -0.05])
    assert give_way.choose(moving, np.full(5, np.inf), np.inf, 0.05, ends, wanted) == 3
