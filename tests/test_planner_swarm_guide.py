"""The global guide of swarm local planners that know the map (``knowledge = "map"``)."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

from swarmpath.planners import Episode, get_planner, list_planners
from swarmpath.planners.cost_to_go import CostToGo
from swarmpath.planners.sensed_map import along, known_obstacles, known_path, surface_points
from swarmpath.planners.swarm_aim import free_space_path
from swarmpath.planners.swarm_guide import descend, taut
from swarmpath.planners.swarm_local import SwarmLocalPlanner
from swarmpath.world import clearance as fast
from swarmpath.world import get_map
from swarmpath.world.importers import load_movingai_map
from swarmpath.world.optimum import shortest_path

DATA = Path(__file__).parent / "data"
SWARM = [n for n in list_planners() if issubclass(get_planner(n), SwarmLocalPlanner)]
# the same runs either way (the backend only saves time); the target's runs are long in numpy
FAST = "numba" if fast.compiled_available() else "numpy"


def _grid(name: str):
    return load_movingai_map(DATA / f"{name}.map").scenario


def _in_box(points: np.ndarray, p: np.ndarray, half: float) -> np.ndarray:
    return points[np.all((points >= p - half) & (points <= p + half), axis=1)]


@pytest.mark.parametrize("scenario", ["mfb-static", "random-32-32-20"])
def test_the_surfaces_near_the_robot_are_the_maps_surface_points_in_its_box(scenario):
    # the points a decision knows are exactly those sensed_map.surface_points samples on the
    # whole map (the old prior), cut to the box around the robot: the same points every time
    sc = get_map(scenario) if scenario == "mfb-static" else _grid(scenario)
    planner = Episode(sc, "MFB", seed=1, params={"knowledge": "map"}).planner
    guide = planner._guide
    assert guide is not None
    every = surface_points(guide.static, 0.01)
    w, h = sc.size
    for p in (np.array(sc.start), np.array([0.5 * w, 0.5 * h]), np.array([0.3 * w, 0.8 * h])):
        near = guide.near(p, 1.8)
        want = _in_box(every, p, 1.8 + 0.5)
        assert len(want) > 0
        assert sorted(map(tuple, near)) == sorted(map(tuple, want))


@pytest.mark.parametrize("name", SWARM)
def test_knowledge_map_gives_a_guide_along_the_exact_optimum_and_sensors_none(name):
    scenario = get_map("mfb-static")
    sensing = Episode(scenario, name, seed=1).planner
    assert sensing.static_map is None and sensing._guide is None and len(sensing._prior) == 0
    knowing = Episode(scenario, name, seed=1, params={"knowledge": "map"}).planner
    guide = knowing._guide
    assert knowing.static_map is not None and guide is not None
    assert len(knowing.static_map.circles) == len(scenario.obstacles)
    start, goal = np.array(scenario.start, float), np.array(scenario.goal, float)
    way = guide.ahead(start, goal, 1.0)
    # mfb-static's robot is holonomic among circles: the planner keeps 1 cm, the known path
    # 1 cm more (carrot_clearance), and so does the guide
    assert guide.clearance == pytest.approx(0.02)
    best = shortest_path(start, goal, knowing.static_map, scenario.robot.radius + 0.02,
                         world=(0.0, 0.0, *scenario.size))
    assert guide.planned_by == "optimum"
    assert np.sum(np.hypot(*np.diff(way, axis=0).T)) == pytest.approx(best.length, abs=1e-6)


def test_knowing_the_map_turns_the_first_aim_off_the_blocked_straight_line():
    # mfb-static: the circle at (2, 2.3) blocks the diagonal; the robot senses it only after
    # driving about a metre, a planner that knows the map heads around it from the start
    scenario = get_map("mfb-static")
    world = (0.0, 0.0, 10.0, 10.0)
    start, goal = np.array([0.0, 0.0]), np.array([10.0, 10.0])
    sensing = Episode(scenario, "MFB", seed=1).planner
    aim = sensing._aim(start, goal, np.zeros((0, 2)), 0.51, world)
    assert np.degrees(np.arctan2(aim[1], aim[0])) == pytest.approx(45.0)
    guide = Episode(scenario, "MFB", seed=1, params={"knowledge": "map"}).planner._guide
    aim = guide.aim(start, goal, guide.near(start, 1.8), 0.51, 1.0, "shortcut")
    assert abs(np.degrees(np.arctan2(aim[1], aim[0])) - 45.0) > 5.0
    assert np.hypot(*aim) == pytest.approx(1.0, abs=0.07)  # a point of the way, 1 m ahead


def test_the_cost_to_go_descent_goes_downhill_and_its_taut_way_keeps_the_margin():
    sc = _grid("room-32-32-4")
    static = sc.static_obstacles()
    goal, start = np.array(sc.goal, float), np.array(sc.start, float)
    margin = sc.robot.radius + 0.04
    field = CostToGo(static, sc.size, goal, margin)
    cells = descend(field, start, goal)
    assert cells is not None
    assert np.array_equal(cells[0], start) and np.array_equal(cells[-1], goal)
    values = field(cells[1:-1])
    assert np.all(np.diff(values) < 0)
    way = taut(cells, static, margin)
    assert len(way) < len(cells) / 3
    # a segment that skips cells keeps the margin; one from a cell to the next is the grid's own
    step = np.sqrt(2.0) * field.spec.resolution + 1e-9
    for a, b in itertools.pairwise(way[1:-1]):  # the ends are the robot's and the goal's
        assert fast.segment_clearance(static, a, b) > margin or np.hypot(*(b - a)) <= step
    # the taut way is within the grid's octile excess of the exact optimum
    best = shortest_path(start, goal, static, margin, world=(0.0, 0.0, *sc.size))
    length = float(np.sum(np.hypot(*np.diff(way, axis=0).T)))
    assert best.length <= length <= 1.1 * best.length


def test_off_the_way_by_more_than_guide_rejoin_the_way_is_planned_again():
    sc = get_map("mfb-static")
    guide = Episode(sc, "MFB", seed=1, params={"knowledge": "map"}).planner._guide
    start, goal = np.array(sc.start, float), np.array(sc.goal, float)
    guide.ahead(start, goal, 1.0)
    plans = guide.plans
    on = guide.ahead(np.array([0.6, 0.3]), goal, 1.0)  # near the way: followed, not planned
    assert guide.plans == plans and guide.at >= 0
    off = np.array([0.2, 1.6])
    way = guide.ahead(off, goal, 1.0)
    assert guide.plans == plans + 1
    assert np.array_equal(way[0], off) and np.array_equal(way[-1], goal)
    assert not np.array_equal(on[1], way[1])
    moved = np.array([9.0, 10.0])  # the goal moved: planned again to the new goal
    assert np.array_equal(guide.ahead(off, moved, 1.0)[-1], moved)
    assert guide.plans == plans + 2


def test_the_cost_to_go_guide_reaches_the_goal_on_a_cluttered_map():
    sc = _grid("random-32-32-20")
    out = Episode(sc, "MFB", seed=1,
                  params={"knowledge": "map", "guide": "cost-to-go", "backend": FAST}).run()
    assert out.success and out.collisions == 0, out.reason
    assert out.gap is not None and out.gap < 0.05


TARGET = [("random-32-32-20", name) for name in SWARM] + [
    (scenario, name) for scenario in ("room-32-32-4", "maze-32-32-4") for name in ("ICOOT", "MFB")]


@pytest.mark.parametrize(("scenario", "name"), TARGET)
def test_swarm_planners_that_know_the_map_reach_the_goal_near_the_optimum(scenario, name):
    # issue 23's target on small copies of the MovingAI random, room and maze families: every
    # swarm planner on random-32-32-20 (where MFB stalled 3 m from the start with sensors only),
    # one of each family (bats, coots) on the others; docs/planners.md has all of them
    out = Episode(_grid(scenario), name, seed=1,
                  params={"knowledge": "map", "backend": FAST}).run()
    assert out.success and out.collisions == 0, out.reason
    assert out.gap is not None and out.gap < 0.05


def test_with_sensors_only_a_pocket_whose_hull_covers_the_robot_still_has_a_way_out():
    # a cup of sensed points open to the left, the robot inside, the goal behind its bottom:
    # the hulls of the known map cover the robot (no known path: the straight line, into the
    # bottom, was the aim), the grid of the points themselves leads out of the opening
    side = np.linspace(-0.6, 1.0, 33)
    cup = np.vstack([np.column_stack([np.full(41, 1.0), np.linspace(-1.0, 1.0, 41)]),
                     np.column_stack([side, np.full(33, 1.0)]),
                     np.column_stack([side, np.full(33, -1.0)])])
    shift = np.array([1.0, 2.0])  # the cup in the middle of a 6 x 4 m world
    p, goal, cup = np.array([0.3, 0.0]) + shift, np.array([4.0, 0.0]) + shift, cup + shift
    world = (0.0, 0.0, 6.0, 4.0)
    known = known_obstacles(cup, link=0.4)
    assert known.point_clearance(p[None, :])[0] <= 0  # the robot is inside the hull
    assert known_path(p, goal, known, 0.2, world) is None
    way = free_space_path(p, goal, cup, 0.2, world, "numpy")
    assert way is not None
    assert np.array_equal(way[0], p) and np.array_equal(way[-1], goal)
    assert way[1][0] < p[0]  # first out of the opening, away from the goal
    dense = along(way, np.arange(0.0, float(np.sum(np.hypot(*np.diff(way, axis=0).T))), 0.01))
    gaps = np.hypot(dense[:, None, 0] - cup[:, 0], dense[:, None, 1] - cup[:, 1]).min(axis=1)
    assert gaps.min() > 0.1
    assert free_space_path(p, goal, cup, 0.2, world, "numpy") is not None  # no state


def test_with_sensors_only_mfb_gets_out_of_random_32_32_20s_pocket():
    # MFB seed 1 with sensors only oscillated in a pocket of random-32-32-20 until the time
    # limit (no_path = "line", the earlier rule; docs/planners.md "Why runs fail")
    out = Episode(_grid("random-32-32-20"), "MFB", seed=1, params={"backend": FAST}).run()
    assert out.success and out.collisions == 0, out.reason
