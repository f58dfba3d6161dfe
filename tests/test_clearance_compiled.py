"""The simulator's compiled geometry (world.clearance_compiled through world.clearance): swept
step clearances, segment clearances and sensor rays equal to the numpy references to the last
bit, on grid maps (many polygons), presets with circles and moving obstacles, and random
segments of every length; an episode is the same run with either backend."""

from pathlib import Path

import numpy as np
import pytest

from swarmpath import metrics
from swarmpath.planners import Episode
from swarmpath.planners.episode import TIMING_FIELDS
from swarmpath.robot.sensors import get_sensor_model, read_sensors, read_sensors_in
from swarmpath.world import clearance, get_map
from swarmpath.world.geometry import ObstacleSet
from swarmpath.world.importers import load_movingai_map

pytest.importorskip("numba")
DATA = Path(__file__).parent / "data"


def _bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64).view(np.int64)


def _walk(rng, n, lo, hi, scale):
    """A random walk with a few long jumps (coarse time steps) inside [lo, hi]."""
    steps = rng.normal(0.0, scale, (n, 2))
    steps[rng.random(n) < 0.02] *= 40.0
    xy = np.clip(np.cumsum(steps, axis=0) + (np.asarray(lo) + hi) / 2, lo, hi)
    return np.column_stack([xy, 0.1 * np.arange(n)])


@pytest.mark.parametrize("name", ["arena.map", "maze512-32-9.map"])
def test_static_grid_maps_equal_numpy(name):
    scenario = load_movingai_map(DATA / name).scenario
    obstacles = scenario.static_obstacles()
    rng = np.random.default_rng(7)
    w, h = scenario.size
    for scale in (0.02, 0.3, 3.0):
        path = _walk(rng, 500, (0.0, 0.0), (w, h), scale)
        ref = metrics.step_clearances(path, obstacles, "numpy")
        got = metrics.step_clearances(path, obstacles, "numba")
        assert np.array_equal(_bits(ref), _bits(got))
        assert metrics.min_clearance(path, obstacles, 0.105, "numba") == metrics.min_clearance(
            path, obstacles, 0.105, "numpy")
    # segments from anywhere, inside walls too
    for _ in range(200):
        a = rng.uniform(-5, max(w, h) + 5, 2)
        b = a + rng.normal(0, rng.choice([0.01, 1.0, 50.0]), 2)
        assert float(obstacles.segment_clearance(a, b)) == clearance.segment_clearance(
            obstacles, a, b, "numba")


@pytest.mark.parametrize("preset", ["mfb-static", "mfb-dynamic", "icoot-map1", "icoot-map4",
                                    "rfogwo-map3"])
def test_presets_with_circles_and_movers_equal_numpy(preset):
    scenario = get_map(preset)
    world = scenario.instantiate(np.random.default_rng(3))
    rng = np.random.default_rng(5)
    w, h = scenario.size
    path = _walk(rng, 400, (0.0, 0.0), (w, h), 0.05 * w / 10)
    ref = metrics.step_clearances(path, world.obstacles_at, "numpy")
    got = metrics.step_clearances(path, world.obstacles_at, "numba")
    assert np.array_equal(_bits(ref), _bits(got))
    radius = scenario.robot.radius
    assert metrics.contact_causes(path, world.obstacles_at, radius, "numba") == (
        metrics.contact_causes(path, world.obstacles_at, radius, "numpy"))
    model = get_sensor_model("icoot-80")
    for _ in range(80):
        world.advance()
        obstacles = world.obstacles()
        x, y = rng.uniform(0, w), rng.uniform(0, h)
        theta = rng.uniform(-4, 4)
        _same_reading(read_sensors(model, x, y, theta, radius, obstacles.circles,
                                   obstacles.polygons),
                      read_sensors_in(model, x, y, theta, radius, obstacles, "numba"))
        a = np.array([x, y])
        b = a + rng.normal(0, 0.5, 2)
        assert float(obstacles.segment_clearance(a, b)) == clearance.segment_clearance(
            obstacles, a, b, "numba")


def _same_reading(a, b):
    for name in ("distances", "hit_points", "fired", "nearest"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name


@pytest.mark.parametrize("model", ["mfb-12", "icoot-80"])
def test_sensors_on_a_grid_map_equal_numpy(model):
    scenario = load_movingai_map(DATA / "maze512-32-9.map").scenario
    obstacles = scenario.static_obstacles()
    sensors = get_sensor_model(model)
    rng = np.random.default_rng(11)
    hits = 0
    for _ in range(80):
        # near walls: half the poses within a few metres of a polygon vertex
        poly = obstacles.polygons[int(rng.integers(len(obstacles.polygons)))]
        x, y = poly[int(rng.integers(len(poly)))] + rng.normal(0, 1.0, 2)
        theta = rng.uniform(-4, 4)
        ref = read_sensors(sensors, x, y, theta, 0.105, obstacles.circles, obstacles.polygons)
        _same_reading(ref, read_sensors_in(sensors, x, y, theta, 0.105, obstacles, "numba"))
        hits += len(ref.hit_points)
    assert hits > 300  # the poses do see walls


def test_empty_and_single_polygon_sets():
    empty = ObstacleSet.empty()
    path = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.1]])
    assert np.isinf(metrics.step_clearances(path, empty, "numba")).all()
    square = ObstacleSet(np.zeros((0, 3)), (np.array([[2.0, -1], [3, -1], [3, 1], [2, 1]]),))
    assert metrics.step_clearances(path, square, "numba")[0] == 1.0
    inside = np.array([[2.5, 0.0, 0.0], [2.6, 0.0, 0.1]])
    assert metrics.step_clearances(inside, square, "numba")[0] == 0.0
    assert clearance.segment_clearance(square, np.array([10.0, 0]), np.array([11.0, 0]),
                                       "numba") == 7.0


def test_episode_is_the_same_run_with_either_backend(monkeypatch):
    """MFB on a MovingAI maze (sensing, motion guard and metrics through the kernels): the
    outcome with the compiled geometry equals the numpy one exactly."""
    imported = load_movingai_map(DATA / "maze512-32-9.map", start=(200.5, 290.5),
                                 goal=(206.5, 282.5))
    scenario = imported.scenario

    def outcome():
        return Episode(scenario, "MFB", seed=1, run=0, params={"backend": "numba"},
                       step_limit=150).run().to_dict()

    fast = outcome()
    monkeypatch.setattr(clearance, "compiled_available", lambda: False)
    slow = outcome()
    for key in TIMING_FIELDS:
        fast.pop(key)
        slow.pop(key)
    assert fast == slow
    assert fast["steps"] > 20


def test_backend_names_are_checked():
    with pytest.raises(ValueError, match="backend"):
        clearance.resolve("fortran")
    assert clearance.resolve("numpy") == "numpy"


@pytest.mark.parametrize("source", ["arena.map", "maze512-32-9.map", "icoot-map1",
                                    "mfb-static"])
def test_point_clearances_equal_numpy(source):
    if source.endswith(".map"):
        obstacles = load_movingai_map(DATA / source).scenario.static_obstacles()
    else:
        obstacles = get_map(source).static_obstacles()
    lo, hi = -3.0, max(float(np.max(p)) for p in obstacles.polygons or (np.full(1, 11.0),))
    points = np.random.default_rng(13).uniform(lo, hi + 3.0, (1500, 2))
    ref = obstacles.point_clearance(points)
    got = clearance.point_clearances(obstacles, points, "numba")
    assert np.array_equal(_bits(ref), _bits(got))
    assert (ref < 0).any() or source == "mfb-static"  # points inside walls are covered
