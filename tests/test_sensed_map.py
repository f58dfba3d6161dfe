"""What a local planner makes of its sensor hits: motion, the known path, its shortcut."""

import numpy as np
import pytest

from swarmpath.planners import sensed_map
from swarmpath.world.geometry import ObstacleSet, point_segment_distance


def arc(centre, radius, a0, a1, n):
    t = np.linspace(a0, a1, n)
    return np.stack([centre[0] + radius * np.cos(t), centre[1] + radius * np.sin(t)], axis=1)


def test_a_static_surface_does_not_move_however_its_hits_slide():
    previous = arc((2.0, 0.0), 0.5, 2.4, 3.9, 16)
    current = arc((2.0, 0.0), 0.5, 2.45, 4.0, 16)  # the same circle, other rays, more of it seen
    # the point rule sees hits between previous hits "moving" and predicts phantom points
    assert len(sensed_map.predict(previous, current, 0.25, (1.0,))) > 0
    assert len(sensed_map.predict(previous, current, 0.25, (1.0,), surface=0.2)) == 0


def test_an_approaching_surface_is_extrapolated_along_its_motion():
    previous = arc((2.0, 0.0), 0.3, 2.6, 3.7, 12)
    current = arc((1.9, 0.0), 0.3, 2.6, 3.7, 12)  # 0.1 m toward the robot in 0.25 s
    ahead = sensed_map.predict(previous, current, 0.25, (1.0,), surface=0.2)
    assert len(ahead) > 0
    # 0.4 m/s for 1 s: the predicted points are ~0.4 m closer to the robot at the origin
    assert np.min(np.hypot(*ahead.T)) == pytest.approx(np.min(np.hypot(*current.T)) - 0.4,
                                                      abs=0.02)


def test_shortcut_is_the_farthest_reachable_point_of_the_path():
    hits = arc((1.2, 0.9), 0.4, -np.pi, np.pi, 40)
    known = ObstacleSet(np.array([[1.2, 0.9, 0.4]]), ())
    path = sensed_map.known_path(np.array([0.0, 0.0]), np.array([2.5, 2.5]), known, 0.52,
                                 (-1.0, -1.0, 4.0, 4.0))
    assert path is not None and len(path) > 2
    aim = sensed_map.shortcut(path, hits, 0.5, 1.5)
    chord = point_segment_distance(hits, path[0], aim).min()
    assert chord >= 0.5  # reachable in a straight line
    # and no farther sample of the path is
    far = sensed_map.along(path, np.linspace(0.0, 1.5, 17)[1:])
    reach = [point_segment_distance(hits, path[0], q).min() >= 0.5 for q in far]
    k = int(np.flatnonzero(np.all(np.isclose(far, aim), axis=1))[0])
    assert reach[k] and not any(reach[k + 1:])
    # nothing sensed: the lookahead point itself
    assert np.allclose(sensed_map.shortcut(path, np.zeros((0, 2)), 0.5, 1.5),
                       sensed_map.along(path, 1.5))


def test_rejoin_returns_the_rest_of_the_path_from_the_robot():
    path = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    rest = sensed_map.rejoin(path, np.array([0.5, 0.01]), 0.02)
    assert rest is not None and np.allclose(rest, [[0.5, 0.01], [1.0, 0.0], [1.0, 1.0]])
    assert sensed_map.rejoin(path, np.array([0.5, 0.1]), 0.02) is None
    assert sensed_map.path_clearance(rest, np.array([[0.7, -0.3]]), 5.0) == pytest.approx(0.306,
                                                                                          abs=0.01)


def test_corners_are_told_from_circles():
    circle = arc((2.0, 0.0), 0.5, 2.4, 3.9, 16)  # 16 hits on a 0.5 m circle
    assert not sensed_map.has_corner(circle, 0.2, 30.0)
    x = np.linspace(0.0, 0.5, 6)
    corner = np.vstack([np.stack([x, np.full(6, 1.0)], 1), np.stack([np.full(5, 0.5),
                                                                      1.0 - x[1:]], 1)])
    assert sensed_map.has_corner(corner, 0.2, 30.0)
    assert not sensed_map.has_corner(corner, 0.05, 30.0)  # pieces longer than surface: unjoined


def test_surface_points_sample_every_static_surface_densely():
    square = np.array([[4.0, 4.0], [6.0, 4.0], [6.0, 5.0], [4.0, 5.0]])
    obstacles = ObstacleSet(np.array([[2.0, 2.0, 0.5], [8.0, 7.0, 0.3]]), (square,))
    pts = sensed_map.surface_points(obstacles, 0.05)
    assert np.abs(obstacles.point_clearance(pts)).max() < 1e-9  # on a surface, never off it
    for cx, cy, r in obstacles.circles:  # every circle is sampled all round
        mine = pts[np.abs(np.hypot(pts[:, 0] - cx, pts[:, 1] - cy) - r) < 1e-9]
        angles = np.sort(np.arctan2(mine[:, 1] - cy, mine[:, 0] - cx))
        gaps = np.diff(np.concatenate([angles, angles[:1] + 2 * np.pi]))
        assert r * gaps.max() <= 0.05 + 1e-12
    edge = pts[np.abs(pts[:, 1] - 4.0) < 1e-12]  # the square's lower edge, corners included
    xs = np.sort(edge[:, 0])
    assert xs[0] == 4.0 and np.diff(np.append(xs, 6.0)).max() <= 0.05 + 1e-12
    assert sensed_map.surface_points(ObstacleSet.empty(), 0.05).shape == (0, 2)


def test_condense_keeps_the_first_hit_of_every_cell_in_order():
    """Against the definition: hits within reach, the first of each cell (pairs of cell indices
    compared as pairs), in their input order; negative coordinates and reach inf included."""
    rng = np.random.default_rng(11)
    hits = np.vstack([rng.uniform(-3.0, 5.0, (400, 2)), rng.uniform(0.0, 0.05, (50, 2))])
    for reach, cell in ((np.inf, 0.01), (2.0, 0.1), (0.5, 0.3)):
        near = hits[np.hypot(*(hits - [0.5, -0.2]).T) <= reach]
        seen, expected = set(), []
        for h in near:
            key = (int(np.floor(h[0] / cell)), int(np.floor(h[1] / cell)))
            if key not in seen:
                seen.add(key)
                expected.append(h)
        got = sensed_map.condense(hits, np.array([0.5, -0.2]), reach, cell)
        assert np.array_equal(got, np.array(expected).reshape(-1, 2))
    assert sensed_map.condense(np.zeros((0, 2)), np.zeros(2), 1.0, 0.1).shape == (0, 2)
