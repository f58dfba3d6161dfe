"""Scenarios: the JSON format and its errors, the presets, and the motion of obstacles and goal."""

from __future__ import annotations

import copy
import json
import math
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

from swarmpath.world import (
    Motion,
    Obstacle,
    RandomMotion,
    RobotSpec,
    Scenario,
    get_map,
    list_maps,
    polygon_problems,
    rasterize_scenario,
)
from swarmpath.world.geometry import ObstacleSet
from swarmpath.world.scenario_io import (
    SCHEMA_PATH,
    ScenarioError,
    load_scenario,
    save_scenario,
    scenario_json_schema,
    scenario_to_dict,
)

EXAMPLE: dict[str, Any] = {
    "name": "demo",
    "size": [10, 10],
    "start": [0, 0],
    "goal": [10, 10],
    "goal_motion": {"speed": 0.1, "heading_deg": 45},
    "robot": {"model": "omni", "radius": 0.5},
    "obstacles": [
        {"shape": "circle", "center": [2, 2.3], "radius": 0.5},
        {"shape": "circle", "center": [4, 2], "radius": 0.3, "speed": 0.3, "heading_deg": 111.8},
        {"shape": "polygon", "points": [[1, 5], [2, 5], [2, 6.5]]},
    ],
}


# ------------------------------------------------------------------------------------ JSON format
def test_required_example_loads() -> None:
    s = load_scenario(copy.deepcopy(EXAMPLE))
    assert s.name == "demo"
    assert s.size == (10.0, 10.0) and s.start == (0.0, 0.0) and s.goal == (10.0, 10.0)
    assert s.goal_motion == Motion(0.1, 45.0)
    assert s.robot.model == "omni" and s.robot.radius == 0.5
    assert s.robot.wheel_radius is None
    assert [o.shape for o in s.obstacles] == ["circle", "circle", "polygon"]
    assert s.obstacles[0].motion is None
    assert s.obstacles[1].motion == Motion(0.3, 111.8)
    assert s.obstacles[2].points == ((1.0, 5.0), (2.0, 5.0), (2.0, 6.5))
    assert s.sensors is None and s.time_step == pytest.approx(0.1)
    assert s.problems() == []


def test_round_trip_and_files(tmp_path: Any) -> None:
    s = load_scenario(copy.deepcopy(EXAMPLE))
    assert load_scenario(scenario_to_dict(s)) == s
    assert load_scenario(json.loads(json.dumps(scenario_to_dict(s)))) == s
    p = save_scenario(s, tmp_path / "demo.json")
    assert load_scenario(p) == s
    assert load_scenario(str(p)) == s
    y = tmp_path / "demo.yaml"
    import yaml

    y.write_text(yaml.safe_dump(EXAMPLE))
    assert load_scenario(y) == s


def test_optional_fields() -> None:
    doc = copy.deepcopy(EXAMPLE)
    doc["goal_motion"] = {"random": True}
    doc["obstacles"][2]["random"] = True
    doc["obstacles"][2]["max_speed"] = 0.4
    doc["sensors"] = "mfb-12"
    doc["time_step"] = 0.05
    doc["robot"] = {"preset": "turtlebot3-burger", "radius": 0.2}
    s = load_scenario(doc)
    assert s.goal_motion == RandomMotion(1.0)
    assert s.obstacles[2].motion == RandomMotion(0.4)
    assert s.sensors == "mfb-12" and s.time_step == 0.05
    assert s.robot == RobotSpec("diff-drive", 0.2, 0.22, 2.84, 0.033, 0.160)
    assert load_scenario(scenario_to_dict(s)) == s
    # Minimal document: robot defaults to the ICOOT/IHPO diff-drive preset.
    m = load_scenario({"name": "m", "size": [5, 5], "start": [1, 1], "goal": [4, 4]})
    assert m.robot == RobotSpec.preset("diff-drive") and m.obstacles == ()


def _set(doc: dict[str, Any], path: tuple[Any, ...], value: Any) -> None:
    for key in path[:-1]:
        doc = doc[key]
    doc[path[-1]] = value


def _del(doc: dict[str, Any], path: tuple[Any, ...]) -> None:
    for key in path[:-1]:
        doc = doc[key]
    del doc[path[-1]]


# (edit, field path the error must name, part of the message)
BAD: list[tuple[str, Any, str, str]] = [
    ("unknown top-level field", (("colour",), "red"), "colour", "unknown field"),
    ("unknown obstacle field", (("obstacles", 1, "colour"), "red"), "obstacles[1].colour",
     "unknown field"),
    ("unknown robot field", (("robot", "mass"), 3), "robot.mass", "unknown field"),
    ("unknown goal_motion field", (("goal_motion", "accel"), 1), "goal_motion.accel",
     "unknown field"),
    ("negative radius", (("obstacles", 1, "radius"), -0.3), "obstacles[1].radius", "must be > 0"),
    ("zero radius", (("obstacles", 0, "radius"), 0), "obstacles[0].radius", "must be > 0"),
    ("zero size", (("size",), [0, 10]), "size[0]", "must be > 0"),
    ("negative size", (("size",), [10, -1]), "size[1]", "must be > 0"),
    # float64 geometry overflows (1e300 ** 2) or loses its 1e-9 m tolerances far from 0
    ("huge size", (("size",), [1e300, 10]), "size[0]", "must be <= 1e+07"),
    ("huge polygon", (("obstacles", 2, "points"), [[1, 5], [2e299, 5], [2, 6.5]]),
     "obstacles[2].points", "within +-1e+07 m"),
    ("huge centre", (("obstacles", 0, "center"), [1e300, 1.0]), "obstacles[0].center",
     "within +-1e+07 m"),
    ("huge speed", (("obstacles", 1, "speed"), 1e300), "obstacles[1].speed", "must be <= 1e+07"),
    ("zero time_step", (("time_step",), 0), "time_step", "must be > 0"),
    ("robot radius", (("robot", "radius"), -1), "robot.radius", "must be > 0"),
    ("robot speed", (("robot", "linear_speed"), 0), "robot.linear_speed", "must be > 0"),
    ("negative speed", (("obstacles", 1, "speed"), -0.3), "obstacles[1].speed", "must be >= 0"),
    ("goal speed", (("goal_motion", "speed"), -1), "goal_motion.speed", "must be >= 0"),
    ("two polygon points", (("obstacles", 2, "points"), [[1, 5], [2, 5]]),
     "obstacles[2].points", "at least 3"),
    ("self-intersecting polygon", (("obstacles", 2, "points"), [[1, 5], [2, 6], [2, 5], [1, 6]]),
     "obstacles[2].points", "self-intersecting"),
    ("polygon touching itself", (("obstacles", 2, "points"),
                                 [[0, 5], [2, 5], [2, 7], [1, 5], [0, 7]]),
     "obstacles[2].points", "self-intersecting"),
    ("repeated vertex", (("obstacles", 2, "points"), [[1, 5], [2, 5], [2, 5], [2, 6.5]]),
     "obstacles[2].points", "coincide"),
    ("bad shape", (("obstacles", 0, "shape"), "hexagon"), "obstacles[0].shape", "must be one of"),
    ("start in obstacle", (("start",), [2, 2]), "start", "collides"),
    ("goal in inflated obstacle", (("goal",), [2.9, 2.3]), "goal", "collides"),
    ("goal outside", (("goal",), [11, 3]), "goal", "outside the world"),
    ("start outside", (("start",), [-0.1, 3]), "start", "outside the world"),
    ("speed without heading", (("obstacles", 0, "speed"), 0.2), "obstacles[0].heading_deg",
     "required when speed"),
    ("heading without speed", (("obstacles", 0, "heading_deg"), 10), "obstacles[0].speed",
     "required when heading_deg"),
    ("random with speed", (("obstacles", 1, "random"), True), "obstacles[1].speed",
     "cannot be combined"),
    ("max_speed without random", (("obstacles", 0, "max_speed"), 1), "obstacles[0].max_speed",
     "only valid with random"),
    ("random max_speed", (("goal_motion",), {"random": True, "max_speed": 0}),
     "goal_motion.max_speed", "must be > 0"),
    ("wheel on omni", (("robot", "wheel_radius"), 0.03), "robot.wheel_radius", "omni"),
    ("model vs preset", (("robot",), {"preset": "turtlebot3-burger", "model": "omni"}),
     "robot.model", "diff-drive"),
    ("unknown preset", (("robot",), {"preset": "roomba"}), "robot.preset", "must be"),
    ("unknown sensors", (("sensors",), "lidar-9000"), "sensors", "unknown sensor model"),
    ("empty name", (("name",), ""), "name", "must not be empty"),
    ("nan", (("obstacles", 0, "center"), [float("nan"), 1.0]), "obstacles[0].center[0]",
     "finite"),
    ("string radius", (("obstacles", 0, "radius"), "big"), "obstacles[0].radius", ""),
]


@pytest.mark.parametrize(("label", "edit", "path", "message"), BAD, ids=[b[0] for b in BAD])
def test_validation_errors_name_their_field(label: str, edit: Any, path: str, message: str) -> None:
    doc = copy.deepcopy(EXAMPLE)
    _set(doc, *edit)
    with pytest.raises(ScenarioError) as info:
        load_scenario(doc)
    problems = info.value.problems
    assert any(p == path and message in m for p, m in problems), problems
    assert f"\n  {path}: " in str(info.value)


@pytest.mark.parametrize("path", [("name",), ("size",), ("start",), ("goal",),
                                  ("obstacles", 0, "radius"), ("obstacles", 2, "points"),
                                  ("obstacles", 1, "shape")])
def test_missing_required_field_is_named(path: tuple[Any, ...]) -> None:
    doc = copy.deepcopy(EXAMPLE)
    _del(doc, path)
    with pytest.raises(ScenarioError) as info:
        load_scenario(doc)
    name = path[0] + "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in path[1:])
    assert any(p == name for p, _ in info.value.problems), info.value.problems


def test_touching_start_counts_as_collision() -> None:
    doc = copy.deepcopy(EXAMPLE)
    doc["obstacles"] = [{"shape": "circle", "center": [2, 0], "radius": 1.0}]
    doc["robot"] = {"model": "omni", "radius": 1.0}  # clearance of (0, 0) is exactly 1.0
    with pytest.raises(ScenarioError) as info:
        load_scenario(doc)
    assert [p for p, _ in info.value.problems] == ["start"]
    doc["robot"]["radius"] = 0.999
    assert load_scenario(doc).robot.radius == 0.999


def test_all_problems_reported_together() -> None:
    doc = copy.deepcopy(EXAMPLE)
    doc["obstacles"][2]["points"] = [[1, 5], [2, 6], [2, 5], [1, 6]]
    doc["start"] = [2, 2]
    doc["goal"] = [12, 1]
    doc["sensors"] = "nope"
    with pytest.raises(ScenarioError) as info:
        load_scenario(doc)
    assert {p for p, _ in info.value.problems} == {"obstacles[2].points", "start", "goal",
                                                    "sensors"}


def test_file_errors(tmp_path: Any) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ScenarioError, match=r"bad\.json"):
        load_scenario(bad)
    arr = tmp_path / "arr.json"
    arr.write_text("[1, 2]")
    with pytest.raises(ScenarioError, match="expected a JSON object"):
        load_scenario(arr)


def test_committed_schema_is_fresh() -> None:
    committed = json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))
    assert committed == scenario_json_schema(), (
        "schemas/scenario.schema.json is stale: run `python -m swarmpath.world.scenario_io`"
    )


def test_schema_describes_the_format() -> None:
    schema = scenario_json_schema()
    assert schema["additionalProperties"] is False
    assert set(schema["required"]) == {"name", "size", "start", "goal"}
    assert {"goal_motion", "robot", "obstacles", "sensors", "time_step"} <= set(
        schema["properties"]
    )


def test_polygon_problems() -> None:
    assert polygon_problems([(0, 0), (1, 0), (1, 1), (0, 1)]) == []
    assert polygon_problems([(0, 0), (2, 0), (2, 2), (1, 0.5), (0, 2)]) == []  # concave is fine
    assert polygon_problems([(0, 0), (1, 0), (2, 0)])  # degenerate
    assert polygon_problems([(0, 0), (1, 1), (1, 0), (0, 1)])  # bow tie


# ---------------------------------------------------------------------------------------- presets
EXPECTED_MAPS = [
    "mfb-static", "mfb-dynamic",
    "icoot-map1", "icoot-map2", "icoot-map3", "icoot-map4",
    "ihpo-map1", "ihpo-map2", "ihpo-map3",
    "rfogwo-map1", "rfogwo-map2", "rfogwo-map3",
]


def test_list_maps() -> None:
    assert list_maps() == EXPECTED_MAPS
    with pytest.raises(KeyError, match="valid"):
        get_map("icoot-map5")


def _reachable(s: Scenario) -> bool:
    """Start and goal in one 8-connected free component of the robot-inflated obstacles at t=0."""
    res = 0.05 if max(s.size) <= 20 else 0.5
    grid = rasterize_scenario(s, res, inflate=True)
    free = ~grid.blocked()
    labels, _ = ndimage.label(free, structure=np.ones((3, 3), dtype=bool))
    a = tuple(grid.world_to_cell(np.array(s.start), clip=True))
    b = tuple(grid.world_to_cell(np.array(s.goal), clip=True))
    return bool(free[a] and free[b] and labels[a] == labels[b])


@pytest.mark.parametrize("name", list_maps())
def test_preset_is_valid_and_reachable(name: str) -> None:
    s = get_map(name)
    assert s.name == name
    assert s.problems() == []
    assert load_scenario(scenario_to_dict(s)) == s
    assert get_map(name) == s  # deterministic
    assert _reachable(s)
    if s.sensors is not None:
        from swarmpath.robot.sensors import SENSOR_MODELS

        assert s.sensors in SENSOR_MODELS


def _counts(s: Scenario) -> tuple[int, int, int]:
    static = sum(not o.is_moving for o in s.obstacles)
    rand = sum(isinstance(o.motion, RandomMotion) for o in s.obstacles)
    const = sum(isinstance(o.motion, Motion) for o in s.obstacles)
    return static, rand, const


def test_mfb_presets_are_exactly_the_published_tables() -> None:
    st_ = get_map("mfb-static")
    assert st_.start == (0, 0) and st_.goal == (10, 10) and st_.size == (10, 10)
    assert st_.robot.model == "omni" and st_.robot.radius == 0.5
    centres = [(2, 2.3), (5.8, 4.3), (8.5, 2), (2, 6.5), (8.5, 5), (7.7, 8), (3, 9), (5, 1),
               (3, 4.5), (5, 7.2)]
    assert [o.center for o in st_.obstacles] == centres
    assert all(o.radius == 0.5 and o.motion is None for o in st_.obstacles)
    dy = get_map("mfb-dynamic")
    assert dy.start == (1, 1) and dy.goal == (10, 10) and dy.robot.radius == 0.3
    table = [((4, 2), 0.3, 111.8), ((3, 7), 0.35, 315), ((9, 4), 0.36, 126.86),
             ((7, 9), 0.25, 315)]
    assert [(o.center, o.motion.speed, o.motion.heading_deg) for o in dy.obstacles] == table  # type: ignore[union-attr]
    assert all(o.radius == 0.3 for o in dy.obstacles)
    assert st_.sensors == dy.sensors == "mfb-12"


def test_paper_maps_follow_their_descriptions() -> None:
    for name in EXPECTED_MAPS[2:9]:
        s = get_map(name)
        assert s.size == (10, 10) and s.start == (0, 0) and s.goal == (10, 10), name
        assert s.robot == RobotSpec.preset("diff-drive")
        assert s.robot.linear_speed == 0.5 and s.robot.wheel_radius == 0.034
        assert s.robot.angular_speed == pytest.approx(0.5 / 0.034)
        assert all(o.shape == "polygon" for o in s.obstacles), name  # irregular polygons
    assert _counts(get_map("icoot-map1")) == (4, 0, 0)
    assert _counts(get_map("icoot-map2")) == (7, 0, 0)
    assert isinstance(get_map("icoot-map3").goal_motion, RandomMotion)
    assert _counts(get_map("icoot-map4")) == (0, 10, 0)
    assert _counts(get_map("ihpo-map1")) == (6, 0, 0)
    assert isinstance(get_map("ihpo-map2").goal_motion, RandomMotion)
    assert _counts(get_map("ihpo-map3")) == (0, 10, 0)
    for name in ("icoot-map1", "icoot-map2", "icoot-map4", "ihpo-map1", "ihpo-map3"):
        assert get_map(name).goal_motion is None
    n = []
    for name in EXPECTED_MAPS[9:]:
        s = get_map(name)
        assert s.size == (170, 170) and not s.is_dynamic
        assert s.start[0] > 150 and s.start[1] < 20  # bottom-right corner
        assert s.goal[0] < 20 and s.goal[1] > 150  # top-left
        n.append(len(s.obstacles))
    assert n[0] < n[1] < n[2]  # crowded to different degrees


# ----------------------------------------------------------------------------------------- motion
def _dynamic() -> Scenario:
    return Scenario(
        "dyn", (10, 10), (0, 0), (9, 9),
        goal_motion=RandomMotion(0.5),
        robot=RobotSpec.preset("omni", radius=0.2),
        obstacles=(
            Obstacle.polygon([(4, 4), (5, 4), (4.5, 5)], RandomMotion(2.0)),
            Obstacle.circle((2, 7), 0.5),
            Obstacle.circle((7, 3), 0.4, RandomMotion()),
            Obstacle.circle((5, 8), 0.3, Motion(0.5, 30)),
        ),
    )


def _trace(world: Any, steps: int) -> np.ndarray:
    rows = []
    for _ in range(steps):
        world.advance()
        o = world.obstacles()
        rows.append(np.concatenate([o.circles.ravel(), *[p.ravel() for p in o.polygons],
                                    world.goal]))
    return np.array(rows)


def test_random_motion_reproducible_and_seed_dependent() -> None:
    s = _dynamic()
    a = _trace(s.instantiate(np.random.default_rng(7)), 200)
    b = _trace(s.instantiate(np.random.default_rng(7)), 200)
    c = _trace(s.instantiate(np.random.default_rng(8)), 200)
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)
    assert np.ptp(a, axis=0).max() > 0.1  # things do move


def test_random_motion_independent_of_queries_and_caller_draws() -> None:
    s = _dynamic()
    rng = np.random.default_rng(3)
    w1 = s.instantiate(rng)
    rng.random(1000)  # the caller keeps using its generator: the world must not notice
    ref = _trace(w1, 100)
    w2 = s.instantiate(np.random.default_rng(3))
    # Query the far future first, then advance in uneven chunks.
    w2.obstacles_at(50.0)
    for _ in range(50):
        w2.advance(0.05)
        w2.velocities()
    for _ in range(25):
        w2.advance(0.1)
    w2.advance(5.0)
    assert w2.time == pytest.approx(10.0)
    o = w2.obstacles()
    final = np.concatenate([o.circles.ravel(), *[p.ravel() for p in o.polygons], w2.goal])
    np.testing.assert_allclose(final, ref[-1], atol=1e-12)
    # Past positions stay available.
    past = w2.obstacles_at(1.0)
    np.testing.assert_allclose(past.circles.ravel(), ref[9][: past.circles.size], atol=1e-12)


def test_random_walk_step_sizes() -> None:
    s = _dynamic()
    w = s.instantiate(np.random.default_rng(0))
    dt = s.time_step
    prev = w.obstacle_positions_at(0.0)  # set order: static, random, constant circle; polygon
    for k in range(1, 300):
        cur = w.obstacle_positions_at(k * dt)
        step = np.hypot(*(cur - prev).T)
        assert step[0] == 0.0  # static circle
        assert step[1] <= 1.0 * dt + 1e-12  # default max_speed 1 m/s
        assert step[2] <= 0.5 * dt + 1e-12  # constant 0.5 m/s (less when it bounces)
        assert step[3] <= 2.0 * dt + 1e-12  # polygon, max_speed 2
        prev = cur
    v = w.velocities(3.0)
    assert v.shape == (4, 2)
    assert np.hypot(*v[2]) == pytest.approx(0.5)
    assert np.hypot(*v[1]) <= 1.0 and np.hypot(*v[3]) <= 2.0


def test_constant_velocity_is_exact() -> None:
    s = get_map("mfb-dynamic")
    w = s.instantiate(np.random.default_rng(0))
    for _ in range(10):
        w.advance()
    assert w.time == pytest.approx(1.0)
    c = w.obstacles().circles
    for (centre, _r, v, hdg), row in zip(
        [((4, 2), 0.3, 0.3, 111.8), ((3, 7), 0.3, 0.35, 315), ((9, 4), 0.3, 0.36, 126.86),
         ((7, 9), 0.3, 0.25, 315)], c, strict=True
    ):
        a = math.radians(hdg)
        assert row[0] == pytest.approx(centre[0] + v * math.cos(a), abs=1e-12)
        assert row[1] == pytest.approx(centre[1] + v * math.sin(a), abs=1e-12)
    vel = w.velocities()
    assert vel[0] == pytest.approx([0.3 * math.cos(math.radians(111.8)),
                                    0.3 * math.sin(math.radians(111.8))])
    # Goal and static obstacles stay put.
    np.testing.assert_array_equal(w.goal, [10, 10])
    assert w.static_obstacles().is_empty


def test_reflection_at_walls() -> None:
    s = Scenario(
        "bounce", (10, 10), (0, 0), (5, 5),
        goal_motion=Motion(1.0, 90),
        robot=RobotSpec.preset("omni", radius=0.1),
        obstacles=(
            Obstacle.circle((9, 5), 0.5, Motion(2.0, 0)),
            Obstacle.polygon([(1, 1), (2, 1), (2, 2), (1, 2)], Motion(1.0, 225)),
        ),
    )
    w = s.instantiate(np.random.default_rng(0))
    # Circle: centre band [0.5, 9.5]; unfolded x at t=0.5 is 10 -> reflected to 9.
    o = w.obstacles_at(0.5)
    assert o.circles[0, 0] == pytest.approx(9.0)
    assert w.velocities(0.5)[0] == pytest.approx([-2.0, 0.0])
    assert w.obstacles_at(0.25).circles[0, 0] == pytest.approx(9.5)
    # Polygon: hits the lower-left corner after sqrt(2) s, then comes back.
    p = w.obstacles_at(2 * math.sqrt(2)).polygons[0]
    np.testing.assert_allclose(p.min(axis=0), [1.0, 1.0], atol=1e-9)
    # Goal: band y in [0, 10]; from 5 at 1 m/s up -> 10 at t=5 -> 7 at t=8.
    assert w.goal_at(8.0) == pytest.approx([5.0, 7.0])
    assert w.goal_velocity(8.0) == pytest.approx([0.0, -1.0], abs=1e-12)
    # Long run: everything stays in the world.
    for t in np.linspace(0, 100, 401):
        o = w.obstacles_at(float(t))
        assert 0.5 - 1e-9 <= o.circles[0, 0] <= 9.5 + 1e-9
        assert o.polygons[0].min() >= -1e-9 and o.polygons[0].max() <= 10 + 1e-9


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), steps=st.integers(1, 400))
def test_random_walk_stays_in_world(seed: int, steps: int) -> None:
    s = get_map("icoot-map4")
    s = Scenario(s.name, s.size, s.start, s.goal, RandomMotion(5.0), s.robot,
                 tuple(Obstacle.polygon(o.points or (), RandomMotion(5.0)) for o in s.obstacles),
                 time_step=0.5)
    w = s.instantiate(np.random.default_rng(seed))
    t = steps * s.time_step
    o = w.obstacles_at(t)
    pts = np.concatenate(o.polygons)
    assert pts.min() >= -1e-9 and pts.max() <= 10 + 1e-9
    g = w.goal_at(t - 0.3 * s.time_step)
    assert 0 <= g.min() and g.max() <= 10
    # Shapes are only translated.
    for p0, p1 in zip(s.initial_obstacles().polygons, o.polygons, strict=True):
        d = p1 - p0
        np.testing.assert_allclose(d, np.broadcast_to(d[0], d.shape), atol=1e-9)


def test_static_obstacles_and_order() -> None:
    s = _dynamic()
    w = s.instantiate(np.random.default_rng(0))
    static = w.static_obstacles()
    assert isinstance(static, ObstacleSet)
    assert static.circles.tolist() == [[2, 7, 0.5]] and static.polygons == ()
    assert s.static_obstacles().circles.tolist() == [[2, 7, 0.5]]
    assert w.set_order == (1, 2, 3, 0)  # circles first, then polygons
    v = w.velocities()
    assert np.all(v[0] == 0) and np.hypot(*v[2]) == pytest.approx(0.5)
    assert not s.static_obstacles().is_empty and s.is_dynamic and s.has_random_motion
    assert s.max_obstacle_speed == 2.0 and get_map("mfb-dynamic").max_obstacle_speed == 0.36
    assert get_map("icoot-map3").max_obstacle_speed == 0.0


def test_static_world_is_cheap_and_fixed() -> None:
    s = get_map("icoot-map1")
    w = s.instantiate(np.random.default_rng(0))
    w.advance(100.0)
    assert w.obstacles() is w.obstacles_at(0.0)
    assert np.all(w.velocities() == 0)
    np.testing.assert_array_equal(w.goal, [10, 10])


def test_random_goal_moves() -> None:
    s = get_map("icoot-map3")
    w = s.instantiate(np.random.default_rng(5))
    goals = np.array([w.goal_at(k * s.time_step) for k in range(100)])
    assert np.ptp(goals, axis=0).max() > 0
    assert goals.min() >= 0 and goals.max() <= 10


def test_bad_time_queries() -> None:
    w = _dynamic().instantiate(np.random.default_rng(0))
    with pytest.raises(ValueError):
        w.advance(-1)
    with pytest.raises(ValueError):
        w.obstacles_at(-0.5)
    with pytest.raises(ValueError):
        w.obstacles_at(float("nan"))
