"""The swarm planners' sensing and aim with ``backend = "numba"`` (planners.compiled_aim): each
kernel gives its numpy reference's numbers to the last bit."""

import itertools
import math

import numpy as np
import pytest

from swarmpath.planners import sensed_map


def _scans(rng):
    """Scan-like point sets: arcs and walls sampled like rays, with noise, duplicates and
    repeated points, and random clouds."""
    out = []
    for k in range(40):
        n = int(rng.integers(1, 90))
        if k % 3 == 0:
            a = np.sort(rng.uniform(-2, 2, n))
            pts = np.stack([1.5 + np.cos(a), -0.5 + np.sin(a)], axis=1)
        elif k % 3 == 1:
            pts = np.stack([np.full(n, 0.7), np.linspace(-1, 1, n)], axis=1)
            pts[n // 2:] += [0.05, 0.0]  # a step: a corner
        else:
            pts = rng.uniform(-2, 2, (n, 2))
        pts += rng.normal(0, 0.003, pts.shape) * (k % 2)
        if n > 3:
            pts[2] = pts[1]  # a repeated hit
        out.append(pts)
    return out


def test_condense_equals_numpy():
    rng = np.random.default_rng(3)
    for pts in _scans(rng):
        p = rng.uniform(-1, 1, 2)
        for reach in (0.5, 1.5, math.inf):
            for cell in (0.01, 0.1, 0.3):
                ref = sensed_map.condense(pts, p, reach, cell)
                got = sensed_map.condense(pts, p, reach, cell, "numba")
                assert np.array_equal(ref, got) and ref.shape == got.shape
    empty = np.zeros((0, 2))
    assert sensed_map.condense(empty, np.zeros(2), 1.0, 0.1, "numba").shape == (0, 2)


def test_motion_and_corners_equal_numpy():
    rng = np.random.default_rng(4)
    scans = _scans(rng)
    moved = 0
    for prev, cur in itertools.pairwise(scans):
        cur = prev[: len(cur)] + rng.normal(0, 0.02, (min(len(prev), len(cur)), 2))
        for surface in (0.0, 0.2):
            a = sensed_map.motion(prev, cur, 0.25, surface=surface)
            b = sensed_map.motion(prev, cur, 0.25, surface=surface, backend="numba")
            assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
            moved += int(a[0].sum())
        for angle in (10.0, 30.0, 60.0):
            assert sensed_map.has_corner(cur, 0.2, angle) == sensed_map.has_corner(
                cur, 0.2, angle, "numba")
    assert moved > 0
    corner = np.array([[0.0, 0.0], [0.05, 0.0], [0.1, 0.0], [0.1, 0.05]])
    assert sensed_map.has_corner(corner, 0.2, 30.0, "numba")
    assert not sensed_map.has_corner(corner[:3], 0.2, 30.0, "numba")


def test_known_obstacles_equal_numpy():
    rng = np.random.default_rng(5)
    groups = 0
    for pts in _scans(rng):
        for link in (0.05, 0.2, 0.6):
            a = sensed_map.known_obstacles(pts, link)
            b = sensed_map.known_obstacles(pts, link, backend="numba")
            assert np.array_equal(a.circles, b.circles)
            assert len(a.polygons) == len(b.polygons)
            assert all(np.array_equal(x, y) for x, y in zip(a.polygons, b.polygons, strict=True))
            groups += len(a.polygons) + len(a.circles)
    assert groups > 100


@pytest.mark.parametrize("lookahead", [0.3, 1.0, 5.0])
def test_aim_walk_equals_numpy(lookahead):
    rng = np.random.default_rng(int(lookahead * 10))
    found = 0
    for _ in range(60):
        n = int(rng.integers(2, 40))
        pts = np.cumsum(rng.uniform(-0.1, 0.3, (n, 2)), axis=0)
        if n > 4:
            pts[3] = pts[2]  # a zero-length piece
        hits = rng.uniform(-0.5, 3, (int(rng.integers(0, 50)), 2))
        for margin in (0.05, 0.15):
            ref = sensed_map.shortcut(pts, hits, margin, lookahead)
            got = sensed_map.shortcut(pts, hits, margin, lookahead, backend="numba")
            assert np.array_equal(ref, got)
        for reach in (0.2, 1.0, 10.0):
            assert sensed_map.path_clearance(pts, hits, reach) == sensed_map.path_clearance(
                pts, hits, reach, "numba")
        p = pts[int(rng.integers(0, n))] + rng.normal(0, 0.03, 2)
        for tol in (0.01, 0.05):
            ref_rest = sensed_map.rejoin(pts, p, tol)
            got_rest = sensed_map.rejoin(pts, p, tol, "numba")
            assert (ref_rest is None) == (got_rest is None)
            if ref_rest is not None:
                found += 1
                assert np.array_equal(ref_rest, got_rest)
    assert found > 5


def test_aim_clearances_equal_numpy():
    from swarmpath.planners import local
    from swarmpath.planners.swarm_aim import _line_clearance, _room

    rng = np.random.default_rng(9)
    inside = 0
    for pts in _scans(rng):
        known = sensed_map.known_obstacles(pts, 0.3)
        for _ in range(10):
            p, goal = rng.uniform(-2, 3, (2, 2))
            if _ % 3 == 0 and known.polygons:
                p = known.polygons[0].mean(axis=0)  # inside a hull
            ref = float(known.point_clearance(p[None, :])[0])
            assert _room(p, known, "numba") == ref
            inside += ref < 0
            ref = float(local.segment_hit_distance(p, goal[None, :], pts)[0][0])
            assert _line_clearance(p, goal, pts, "numba") == ref
            assert _line_clearance(p, goal, pts, "numpy") == ref
    assert inside > 5


def test_nearest_hit_equals_numpy():
    from swarmpath.planners import local
    from swarmpath.planners.swarm_aim import nearest_hit

    rng = np.random.default_rng(12)
    for pts in [*_scans(rng), np.zeros((0, 2))]:
        for p in rng.uniform(-2, 2, (5, 2)):
            ref = float(local.point_hit_distance(p[None, :], pts)[0][0])
            assert nearest_hit(p, pts, "numba") == ref == nearest_hit(p, pts, "numpy")


def test_hold_clearance_equals_numpy():
    import dataclasses

    from swarmpath.planners import local
    from swarmpath.planners.swarm_aim import clear

    rng = np.random.default_rng(13)
    both = set()
    for pts in _scans(rng):
        for margin in (0.05, 0.2):
            ctx = local.StepContext(position=np.array([0.1, -0.2]), goal=np.array([3.0, 1.0]),
                                    hits=pts, margin=margin)
            fast = dataclasses.replace(ctx, backend="numba")
            for x in rng.uniform(-2, 2, (10, 2)):
                ref = bool(local.violation(x[None, :], ctx)[0] == 0)
                assert clear(x, fast) == ref == clear(x, ctx)
                both.add(ref)
    assert both == {True, False}


def test_condense_of_a_huge_span_equals_numpy():
    rng = np.random.default_rng(14)
    pts = np.vstack([rng.uniform(0, 1e9, (50, 2)), [[5.0, 5.0], [5.001, 5.001]]])
    ref = sensed_map.condense(pts, np.zeros(2), np.inf, 0.01)
    assert np.array_equal(sensed_map.condense(pts, np.zeros(2), np.inf, 0.01, "numba"), ref)
    assert len(ref) == len(pts) - 1  # the two points in one cell merged
