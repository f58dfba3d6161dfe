"""OMPL baselines: solved static maps, exact re-check, failures with reasons, determinism."""

import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import owned
from swarmpath.planners import Episode, PlannerError, get_planner, list_planners
from swarmpath.planners import ompl_baselines as ompl_mod
from swarmpath.planners.ompl_checks import FastChecker
from swarmpath.world import Obstacle, RobotSpec, Scenario, get_map
from swarmpath.world.geometry import ObstacleSet, collides
from swarmpath.world.importers import load_ros_map
from swarmpath.world.scenario_io import load_scenario, scenario_from_dict

BASELINES = [n for n in list_planners() if issubclass(get_planner(n), ompl_mod.OmplPlanner)]
DATA = Path(__file__).parent / "data"
TWO_WALLS = DATA / "two_walls.json"
FAST = {"iterations": 2000}


def planned_length(path: np.ndarray) -> float:
    return float(np.sum(np.hypot(*np.diff(path, axis=0).T)))


def walled_goal() -> Scenario:
    """The goal (5, 5) inside a closed box of four walls: no path exists."""
    walls = (
        Obstacle.rectangle(3.5, 3.5, 6.5, 3.8),
        Obstacle.rectangle(3.5, 6.2, 6.5, 6.5),
        Obstacle.rectangle(3.5, 3.5, 3.8, 6.5),
        Obstacle.rectangle(6.2, 3.5, 6.5, 6.5),
    )
    return Scenario(name="walled-goal", size=(10.0, 10.0), start=(1.0, 1.0), goal=(5.0, 5.0),
                    robot=RobotSpec.preset("omni", radius=0.2), obstacles=walls)


def test_registered_as_global_planners_given_the_static_map():
    assert len(BASELINES) >= 2
    for name in BASELINES:
        assert name in list_planners()
        cls = get_planner(name)
        assert cls.kind == "global"
        assert "static map" in cls.description
        assert cls.defaults["budget"] == "iterations"  # the same result on any machine
        assert cls.defaults["iterations"] >= 10_000


@pytest.mark.parametrize("name", BASELINES)
@pytest.mark.parametrize("map_name", ["mfb-static", "rfogwo-map1"])
def test_solves_static_maps_collision_free_and_no_shorter_than_the_optimum(name, map_name):
    scenario = get_map(map_name)
    ep = Episode(scenario, name, seed=1, run=0, params=FAST)
    out = ep.run()
    assert out.success, out.reason
    assert out.collisions == 0 and out.min_clearance > 0
    assert out.optimum is not None
    path = ep.planner.path
    assert path is not None
    assert np.allclose(path[0], scenario.start) and np.allclose(path[-1], scenario.goal)
    # every planned segment clears the static obstacles by more than the robot radius
    clear = scenario.static_obstacles().segment_clearance(path[:-1], path[1:])
    assert not collides(clear, scenario.robot.radius).any()
    planned = planned_length(path)
    assert planned >= out.optimum - 1e-9
    # the last waypoint is the goal, driven onto (Decision.finish): the executed path is complete
    assert out.error <= 0.01
    assert out.length >= out.optimum - 1e-9 and out.gap >= -1e-9
    if map_name == "mfb-static":
        assert planned <= 1.15 * out.optimum
        assert out.length <= 1.15 * out.optimum


def test_diff_drive_robot_reaches_the_goal():
    # deterministic mode: the same paths every time (seeds 1 and 3 stall with the bug)
    for seed in range(1, 5):
        out = Episode(get_map("icoot-map1"), "OMPL-RRTstar", seed=seed, run=0,
                      params={"iterations": 1000}).run()
        assert out.success, out.reason


@pytest.mark.parametrize("name", BASELINES)
def test_walled_in_goal_is_a_failure_with_a_reason(name):
    out = Episode(walled_goal(), name, seed=1, run=0, params={"iterations": 1000}).run()
    assert not out.success
    assert out.collisions == 0
    assert name in out.reason and "no path" in out.reason


def test_timeout_reason_names_the_budget_and_the_iterations_done():
    res = ompl_mod.plan_path("BITstar", walled_goal().static_obstacles(), np.array([1.0, 1.0]),
                             np.array([5.0, 5.0]), 0.2, (10.0, 10.0),
                             {**ompl_mod.OmplPlanner.defaults, "iterations": 40}, seed=2)
    assert res.path is None
    assert "within 40 iterations (40 iterations done)" in res.reason


@pytest.mark.parametrize("name", BASELINES)
@pytest.mark.parametrize(("map_name", "seed", "run"), [
    ("icoot-map1", 3, 9),  # collided 17 times: the diff drive cut the corners it turned at
    (TWO_WALLS, 1, 0),  # stalled at a corner until the time limit
])
def test_diff_drive_follows_the_checked_path_exactly(name, map_name, seed, run):
    scenario = load_scenario(map_name) if isinstance(map_name, Path) else get_map(map_name)
    assert scenario.robot.model == "diff-drive"
    out = Episode(scenario, name, seed=seed, run=run, params={"iterations": 20000}).run()
    assert out.success, out.reason
    assert out.collisions == 0
    # turn in place at each vertex, then drive the checked segment: executed = planned
    assert out.planned_length is not None
    assert abs(out.length - out.planned_length) < 1e-3
    assert out.min_clearance >= 0.02 - 1e-6  # the planner's margin, kept while driving


def test_start_without_clearance_for_the_planner_is_named():
    # a start 1.4e-17 m outside the inflated square: valid for the product's collision rule,
    # not for a planner whose states must be strictly clear (BIT* reported "Timeout, 0 iterations")
    square = np.array([[1.3512936187542919, 0.8087067104500392],
                       [2.191293289549961, 1.3512936187542919],
                       [1.6487063812457081, 2.191293289549961],
                       [0.8087067104500392, 1.6487063812457081]])
    obstacles = ObstacleSet(np.zeros((0, 3)), [square])
    start = np.array([1.629434778351066, 0.8633683412269666])
    assert not collides(obstacles.point_clearance(start[None])[0], 0.105)
    for algorithm in ("BITstar", "RRTstar"):
        res = ompl_mod.plan_path(algorithm, obstacles, start, np.array([4.0, 4.0]), 0.105,
                                 (5.0, 5.0), ompl_mod.OmplPlanner.defaults, seed=1)
        assert res.path is None
        assert "start (1.62943, 0.863368) is not a valid state for the planner" in res.reason
        assert "beyond the robot radius" in res.reason


def test_plan_path_rejects_start_inside_an_inflated_obstacle():
    obstacles = ObstacleSet(np.array([[2.0, 2.0, 1.0]]))
    res = ompl_mod.plan_path("RRTstar", obstacles, np.array([2.0, 3.2]), np.array([9.0, 9.0]),
                             0.5, (10.0, 10.0), ompl_mod.OmplPlanner.defaults, seed=3)
    assert res.path is None and "start is inside an obstacle" in res.reason


def test_discrete_motion_checking_also_passes_the_exact_recheck():
    scenario = get_map("mfb-static")
    ep = Episode(scenario, "OMPL-RRTstar", seed=2, run=0,
                 params={"iterations": 2000, "motion_check": "discrete",
                         "simplify": "none"})
    out = ep.run()
    assert out.success, out.reason
    assert out.collisions == 0


def test_iteration_budget_is_deterministic_and_runs_differ():
    scenario = get_map("mfb-static")
    params = {"iterations": 300}

    def path(name: str, run: int) -> list:
        return Episode(scenario, name, seed=7, run=run, params=params).run().path

    a = path("OMPL-RRTstar", 0)
    b = path("OMPL-BITstar", 0)
    assert path("OMPL-RRTstar", 1) != a
    assert path("OMPL-RRTstar", 0) == a  # after other plans: OMPL's generator is re-seeded
    assert path("OMPL-BITstar", 0) == b
    ep = Episode(scenario, "OMPL-RRTstar", seed=7, run=0, params=params)
    ep.step()
    assert ep.iterations == 300


def test_parameters_are_checked():
    cls = get_planner("OMPL-RRTstar")
    for bad in ({"budget": "wall", "time": 0}, {"budget": "cpu", "time": -1.0},
                {"iterations": -1}, {"iterations": 0}, {"margin": -0.1},
                {"resolution": 0.0}, {"simplify": "yes"}, {"motion_check": "maybe"},
                {"budget": 1.0}, {"budget": "seconds"}):
        with pytest.raises(PlannerError):
            cls.resolve_params(bad)
    assert cls.resolve_params({"budget": "cpu", "time": 2})["time"] == 2.0
    assert cls.resolve_params({"iterations": 10})["iterations"] == 10
    # a budget the planner would silently ignore is refused, naming the parameter
    with pytest.raises(PlannerError, match=r"OMPL-RRTstar\.time applies to budget 'cpu' or 'wall'"):
        cls.resolve_params({"time": 0.5})
    with pytest.raises(PlannerError, match=r"OMPL-RRTstar\.iterations applies to budget"):
        cls.resolve_params({"budget": "wall", "iterations": 100})


@pytest.mark.parametrize("map_name", ["mfb-static", "rfogwo-map2"])
def test_fast_checker_agrees_with_the_exact_geometry(map_name):
    scenario = get_map(map_name)
    obstacles = scenario.static_obstacles()
    thr = scenario.robot.radius + 0.02
    checker = FastChecker(obstacles, thr)
    rng = np.random.default_rng(5)
    w, h = scenario.size
    P = rng.uniform([0, 0], [w, h], size=(400, 2))
    Q = P + rng.normal(scale=0.1 * w, size=P.shape)
    exact_points = obstacles.point_clearance(P) > thr
    exact_segments = obstacles.segment_clearance(P, Q) > thr
    assert [checker.point_ok(*p) for p in P] == exact_points.tolist()
    assert [checker.segment_ok(*p, *q) for p, q in zip(P, Q, strict=True)] == (
        exact_segments.tolist()
    )


def test_no_nanobind_leak_report_at_exit():
    code = (
        "from swarmpath.planners import Episode\n"
        "from swarmpath.world import get_map\n"
        "o = Episode(get_map('mfb-static'), 'OMPL-BITstar', 1, 0, {'iterations': 500}).run()\n"
        "print(o.success)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, check=True)
    assert "leaked" not in done.stderr


def test_contacts_are_counted_by_cause():
    # a circle crossing the start at 3 m/s while the TurtleBot3 turns in place toward the goal
    # behind it: every contact is obstacle-driven; the counts add up to the collisions
    scenario = scenario_from_dict({
        "name": "run-over", "size": [10, 10], "start": [5, 5], "goal": [1, 5],
        "robot": {"preset": "turtlebot3-burger"},
        "obstacles": [{"shape": "circle", "center": [5, 8], "radius": 0.3, "speed": 3.0,
                       "heading_deg": -90}]})
    out = Episode(scenario, "OMPL-RRTstar", seed=1, params={"iterations": 200}).run()
    assert out.collisions > 0 and not out.success
    assert out.robot_driven_contacts == 0
    assert out.obstacle_driven_contacts == out.collisions


def _busy_processes(n: int) -> list[subprocess.Popen]:
    """``n`` processes spinning on the CPU (each in its own process group, bounded to 300 s)."""
    code = "import time\nend = time.time() + 300\nwhile time.time() < end:\n    pass\n"
    return [owned.popen([sys.executable, "-c", code])
            for _ in range(n)]


@pytest.mark.parametrize("name", BASELINES)
def test_the_default_budget_gives_the_same_result_under_load_and_quiet(name):
    # the failure: 1 s of wall clock found no path under load in 1 of 3 runs; the default
    # budget counts iterations, so a loaded worker plans exactly what a quiet one plans
    scenario = load_ros_map(DATA / "tb3_sandbox.yaml").scenario

    def run() -> tuple[list, int, bool]:
        out = Episode(scenario, name, seed=4, run=1).run()
        return out.path, out.iterations, out.success

    quiet = run()
    busy = _busy_processes(2 * (os.cpu_count() or 2))
    try:
        loaded = run()
    finally:
        for p in busy:
            p.kill()
            p.wait()
    assert quiet[2], "the default budget solves tb3_sandbox"
    assert loaded == quiet
    assert quiet[1] == get_planner(name).defaults["iterations"]


def test_cpu_budget_ends_on_this_threads_cpu_time():
    params = {**ompl_mod.OmplPlanner.defaults, "budget": "cpu", "time": 0.2}
    started = time.thread_time()
    res = ompl_mod.plan_path("RRTstar", walled_goal().static_obstacles(), np.array([1.0, 1.0]),
                             np.array([5.0, 5.0]), 0.2, (10.0, 10.0), params, seed=2)
    assert time.thread_time() - started >= 0.2
    assert res.path is None and "the budget of 0.2 s of CPU time" in res.reason
