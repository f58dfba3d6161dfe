"""The contact rule shared by the swarm local planners: never drive toward what the robot touches
(:func:`swarmpath.planners.local.keep_off`, docs/planners.md, "Contacts by cause")."""

import numpy as np
import pytest

from swarmpath.planners import Episode, local
from swarmpath.world import get_map


def test_a_move_with_nothing_near_is_unchanged():
    p = np.array([1.0, 1.0])
    move = np.array([0.3, -0.1])
    far = np.array([[3.0, 1.0], [1.0, 2.5]])
    assert np.array_equal(local.keep_off(p, move, far, 0.25), move)
    assert np.array_equal(local.keep_off(p, move, np.zeros((0, 2)), 0.25), move)


def test_a_move_into_a_touched_wall_slides_along_it():
    p = np.array([0.0, 0.0])
    wall = np.array([[0.2, 0.0]])  # touching a robot of radius 0.2 on its right
    kept = local.keep_off(p, np.array([0.3, 0.4]), wall, 0.2 + 1e-3)
    assert kept == pytest.approx([0.0, 0.4])  # the tangent part stays, the part into it goes
    away = np.array([-0.3, 0.1])
    assert np.array_equal(local.keep_off(p, away, wall, 0.2 + 1e-3), away)
    # straight into it: stop
    assert local.keep_off(p, np.array([0.5, 0.0]), wall, 0.2 + 1e-3) == pytest.approx([0, 0])


def test_in_a_corner_only_the_moves_closing_on_neither_wall_remain():
    p = np.array([0.0, 0.0])
    corner = np.array([[0.2, 0.0], [0.0, 0.2]])  # walls on the right and above
    assert local.keep_off(p, np.array([0.3, 0.3]), corner, 0.21) == pytest.approx([0, 0])
    assert local.keep_off(p, np.array([0.3, -0.2]), corner, 0.21) == pytest.approx([0, -0.2])
    assert local.keep_off(p, np.array([-0.1, 0.4]), corner, 0.21) == pytest.approx([-0.1, 0])


def test_a_kept_move_never_brings_the_robot_closer_to_a_touched_disk():
    rng = np.random.default_rng(7)
    for _ in range(200):
        p = rng.uniform(-1, 1, 2)
        centre = p + rng.normal(size=2)
        radius = float(np.hypot(*(centre - p))) - rng.uniform(0.05, 0.2)  # body gap 0..0.2 m
        angles = np.linspace(0, 2 * np.pi, 180, endpoint=False)
        surface = centre + radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)
        move = rng.normal(size=2) * 0.3
        kept = local.keep_off(p, move, surface, 0.2 + 1e-3)
        before = np.hypot(*(centre - p)) - radius
        after = np.hypot(*(centre - p - kept)) - radius
        assert after >= before - 1e-3  # the disk is sampled every 2 degrees
        assert np.hypot(*(kept - move)) <= np.hypot(*move) + 1e-12  # never worse than stopping


def test_the_random_walker_contact_the_robot_drove_into_is_gone():
    # icoot-map4, MFB, seed 5: at t = 26.8 s the robot, 7 cm from a random walker (polygon 8),
    # drove 4.5 cm toward it while it came on: one robot-driven colliding step. Without the band
    # around moving points (only touching points kept off) it is still there (with ``give_way``
    # off too: giving way keeps the robot away from that walker by itself).
    before = Episode(get_map("icoot-map4"), "MFB", seed=5,
                     params={"contact_band": 0.0, "give_way": 0.0}).run()
    assert before.robot_driven_contacts >= 1
    after = Episode(get_map("icoot-map4"), "MFB", seed=5).run()
    assert after.robot_driven_contacts == 0
    assert after.collisions == after.obstacle_driven_contacts
