"""The exact shortest path with ``backend = "numba"`` (world.optimum_compiled): the same path and
length, to the last bit, as the numpy reference."""

from __future__ import annotations

import numpy as np
import pytest

from swarmpath.planners import sensed_map
from swarmpath.world import get_map
from swarmpath.world.geometry import ObstacleSet
from swarmpath.world.optimum import _compiled, shortest_path
from swarmpath.world.optimum_compiled import segments_blocked_kernel
from swarmpath.world.optimum_scene import _Scene


def _scene(rng: np.random.Generator, k: int) -> ObstacleSet:
    """Sensed-map-like obstacles: hulls of random point groups, point circles, a disk."""
    polys = []
    for _ in range(k):
        centre = rng.uniform(1, 7, 2)
        pts = centre + rng.normal(0, 0.4, (int(rng.integers(3, 12)), 2))
        polys.append(pts)
    known = sensed_map.known_obstacles(np.concatenate(polys), link=0.2)
    circles = np.vstack([known.circles.reshape(-1, 3),
                         [[*rng.uniform(1, 7, 2), float(rng.uniform(0, 0.5))]]])
    return ObstacleSet(circles, known.polygons)


@pytest.mark.parametrize("seeds", [range(0, 8), range(8, 16)])
def test_compiled_shortest_path_equals_numpy(seeds: range) -> None:
    bent = 0
    for seed in seeds:
        bent += _compare_paths(seed)
    assert bent >= 8


def _compare_paths(seed: int) -> int:
    rng = np.random.default_rng(seed)
    obstacles = _scene(rng, 1 + seed % 3)
    if seed % 4 < 2:  # polygons only (the sensed maps' usual case)
        obstacles = ObstacleSet(np.zeros((0, 3)), obstacles.polygons)
    world = (0.0, 0.0, 8.0, 8.0) if seed % 2 else None
    bent = 0
    centres = [p.mean(axis=0) for p in obstacles.polygons]
    for k in range(8):
        s, g = rng.uniform(0.2, 7.8, (2, 2))
        if k % 2 and centres:  # across an obstacle: a bent path
            u = rng.normal(0, 1, 2)
            c = centres[k % len(centres)]
            s, g = np.clip([c + 1.5 * u / np.hypot(*u), c - 1.5 * u / np.hypot(*u)], 0.2, 7.8)
        margin = float(rng.choice([0.05, 0.15, 0.3]))
        try:
            ref = shortest_path(s, g, obstacles, margin, world=world)
        except ValueError as exc:
            with pytest.raises(ValueError, match=str(exc).split(" ")[0]):
                shortest_path(s, g, obstacles, margin, world=world, backend="numba")
            continue
        got = shortest_path(s, g, obstacles, margin, world=world, backend="numba")
        assert repr(ref.length) == repr(got.length) and ref.exact == got.exact
        assert np.array_equal(ref.points, got.points)
        bent += len(ref.points) > 2
    return bent


def test_compiled_segment_checks_equal_numpy() -> None:
    rng = np.random.default_rng(7)
    blocked = 0
    for k in range(20):
        obstacles = _scene(rng, 1 + k % 4)
        margin = float(rng.uniform(0.01, 0.3))
        scene = _Scene(obstacles, margin, (0.0, 0.0, 8.0, 8.0) if k % 2 else None)
        a = rng.uniform(-0.5, 8.5, (300, 2))
        b = a + rng.normal(0, 2, (300, 2))
        b[:20] = a[:20]  # points
        ref = scene.segments_blocked(a, b)
        got = segments_blocked_kernel(a, b, margin, *_compiled(scene))
        assert np.array_equal(ref, got)
        blocked += int(ref.sum())
    assert 0 < blocked < 20 * 300


def test_compiled_planner_paths_on_a_preset() -> None:
    """The 10 m mfb-static map's obstacles (circles and polygons) as one scene."""
    scenario = get_map("mfb-static")
    obstacles = scenario.static_obstacles()
    rng = np.random.default_rng(1)
    for _ in range(5):
        s, g = rng.uniform(0.5, 9.5, (2, 2))
        try:
            ref = shortest_path(s, g, obstacles, 0.12)
        except ValueError:
            continue
        got = shortest_path(s, g, obstacles, 0.12, backend="numba")
        assert repr(ref.length) == repr(got.length) and np.array_equal(ref.points, got.points)


def test_compiled_arc_checks_equal_numpy() -> None:
    from swarmpath.world.optimum_base import _in_arc
    from swarmpath.world.optimum_compiled_arcs import _in_arc as in_arc_kernel

    rng = np.random.default_rng(11)
    phi = np.concatenate([rng.uniform(-10, 10, 500), np.arange(-4, 5) * np.pi,
                          np.arange(-3, 4) * 2 * np.pi])
    th0, dth = rng.uniform(-7, 7, len(phi)), rng.uniform(0, 2 * np.pi, len(phi))
    dth[:20] = np.mod(phi[:20] - th0[:20], 2 * np.pi)  # on the arc's end, exactly
    ref = _in_arc(phi, th0, dth)
    assert [in_arc_kernel(*x) for x in zip(phi, th0, dth, strict=True)] == ref.tolist()
    blocked = 0
    for k in range(20):
        obstacles = _scene(rng, 1 + k % 4)
        if k % 4 < 2:  # polygons only (the sensed maps' usual case)
            obstacles = ObstacleSet(np.zeros((0, 3)), obstacles.polygons)
        margin = float(rng.uniform(0.01, 0.3))
        ref_scene = _Scene(obstacles, margin, (0.0, 0.0, 8.0, 8.0) if k % 2 else None)
        fast = _Scene(obstacles, margin, (0.0, 0.0, 8.0, 8.0) if k % 2 else None)
        fast.backend = "numba"
        verts = np.concatenate([np.zeros((0, 2)), *obstacles.polygons])
        c = np.concatenate([verts, rng.uniform(0, 8, (100, 2))])
        rho = np.concatenate([np.full(len(verts), margin), rng.uniform(0.05, 1.5, 100)])
        th0 = rng.uniform(0, 2 * np.pi, len(c))
        dth = rng.uniform(0, 2 * np.pi, len(c))
        ref = ref_scene.arcs_blocked(c, rho, th0, dth)
        assert np.array_equal(ref, fast.arcs_blocked(c, rho, th0, dth))
        blocked += int(ref.sum())
    assert 0 < blocked < 20 * 150


def test_compiled_disks_equal_numpy() -> None:
    from swarmpath.world.optimum_compiled import disks_kernel
    from swarmpath.world.optimum_tangents import _disks

    rng = np.random.default_rng(21)
    covered = 0
    for k in range(30):
        obstacles = _scene(rng, 1 + k % 4)
        polys = list(obstacles.polygons)
        if k % 3 == 0:  # touching and overlapping axis-aligned rectangles (grid maps)
            x, y = rng.uniform(1, 6, 2)
            polys += [np.array([[x, y], [x + 1, y], [x + 1, y + 1], [x, y + 1]]),
                      np.array([[x + 1, y], [x + 2, y], [x + 2, y + 1], [x + 1, y + 1]]),
                      np.array([[x + 0.5, y + 0.5], [x + 1.5, y + 0.5], [x + 1.5, y + 2],
                                [x + 0.5, y + 2]])]
        obstacles = ObstacleSet(obstacles.circles, tuple(polys))
        for margin in (0.0, 0.1):
            s, g = rng.uniform(0, 8, (2, 2))
            ref = _disks(s, g, obstacles, margin)
            scene = _Scene(obstacles, margin, None)
            got = disks_kernel(s, g, scene.circles, scene.e0, scene.counts, margin)
            for a, b in zip(ref, got, strict=True):
                assert np.array_equal(a, b)
            kept = int(np.sum(obstacles.circles[:, 2] + margin > 0.0))
            vertex_disks = len(ref[0]) - 2 - kept
            covered += sum(int(np.sum(_convex_count(p))) for p in polys) - vertex_disks
    assert covered > 0


def _convex_count(poly: np.ndarray) -> np.ndarray:
    prev, nxt = np.roll(poly, 1, axis=0), np.roll(poly, -1, axis=0)
    d1, d2 = poly - prev, nxt - poly
    area = np.sum(poly[:, 0] * nxt[:, 1] - poly[:, 1] * nxt[:, 0])
    return (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) * np.sign(area) > 0


def test_unknown_backend_is_refused() -> None:
    square = ObstacleSet(polygons=(np.array([[1.0, -1.0], [2.0, -1.0], [2.0, 1.0], [1.0, 1.0]]),))
    with pytest.raises(ValueError, match="backend"):
        shortest_path((0.0, 0.0), (3.0, 0.0), square, 0.1, backend="cuda")


def test_compiled_tolerance_is_the_reference_one() -> None:
    """The kernels keep their own copy of the geometric tolerance (the numba cache is keyed by
    the compiled sources only, so an import from optimum_base would not recompile them on a
    change); the copy must stay the reference's value."""
    from swarmpath.world import optimum_base, optimum_compiled

    assert optimum_compiled.TOL == optimum_base.TOL
