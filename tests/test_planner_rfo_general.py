"""RFO-GWO family on maps beyond the paper's: traps of eq 17, tight start/goal, diff drive."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from swarmpath.planners import Episode, get_planner, list_planners
from swarmpath.planners.cost_to_go import MAX_CELLS, CostToGo
from swarmpath.planners.episode import scenario_optimum
from swarmpath.planners.rfo_gwo import RfoFamilyPlanner
from swarmpath.world import get_map
from swarmpath.world.geometry import ObstacleSet
from swarmpath.world.scenario_io import load_scenario

TWO_WALLS = Path(__file__).parent / "data" / "two_walls.json"
# the planners with Algorithm 2 (GWO) and the stall rule, from the registry
HYBRIDS = [n for n in list_planners()
           if issubclass(cls := get_planner(n), RfoFamilyPlanner) and cls.fallback == "gwo"]


def test_cost_to_go_follows_free_space():
    s = load_scenario(TWO_WALLS)
    field = CostToGo(s.static_obstacles(), s.size, np.array(s.goal), s.robot.radius)
    optimum = scenario_optimum(s)
    assert optimum is not None
    start, goal = field(np.array([s.start, s.goal]))
    assert goal == 0.0
    assert 0.99 * optimum <= start <= 1.09 * optimum  # octile grid: at most 8 % above
    # left of the second wall, at the top: straight-line closer than below it, the way not
    below, above = field(np.array([[7.6, 3.6], [7.6, 6.5]]))
    assert np.hypot(11 - 7.6, 7 - 6.5) < np.hypot(11 - 7.6, 7 - 3.6)
    assert below < above
    assert np.isinf(field(np.array([[4.1, 2.0]]))[0])  # inside the first wall


def test_cost_to_go_cells_are_never_coarser_than_the_clearance():
    """A 300-cell field of a 512 m maze had 1.7 m cells, coarser than its 1 m walls (the RFO
    family stalled there); a field's cells are at most the clearance, as far as MAX_CELLS allows,
    and small maps keep their 300 cells."""
    wall = np.array([[100.0, 0.0], [100.2, 0.0], [100.2, 90.0], [100.0, 90.0]])
    obs = ObstacleSet(np.zeros((0, 3)), (wall,))
    big = CostToGo(obs, (200.0, 100.0), np.array([110.0, 5.0]), 0.3)
    assert big.spec.resolution == pytest.approx(0.3)
    capped = CostToGo(obs, (600.0, 600.0), np.array([110.0, 5.0]), 0.3)
    assert 0.3 < capped.spec.resolution and capped.free.size <= MAX_CELLS
    small = CostToGo(obs, (12.0, 8.0), np.array([11.0, 7.0]), 0.3)
    assert small.spec.resolution == pytest.approx(12.0 / 300)
    # around the wall's top, never through it
    assert big(np.array([[99.6, 5.0]]))[0] >= np.hypot(0.5, 85.3) + np.hypot(9.9, 85.3)


@pytest.mark.parametrize("planner", HYBRIDS)
def test_eq17_trap_is_left_along_free_space(planner):
    s = load_scenario(TWO_WALLS)
    assert s.robot.model == "diff-drive"
    # the paper's straight-line progress alone: trapped left of the second wall, and says so
    stuck = Episode(s, planner, seed=1, params={"progress": "euclidean"}).run()
    assert not stuck.success
    assert "no fox got closer to the goal" in stuck.reason and "in a straight line" in stuck.reason
    for seed in (1, 2):
        out = Episode(s, planner, seed=seed).run()
        assert out.success, out.reason
        assert out.collisions == 0
        # turned in place at each node: the executed path is the planned one
        assert out.planned_length is not None
        assert abs(out.length - out.planned_length) < 1e-3


@pytest.mark.parametrize("planner", HYBRIDS)
def test_paper_maps_keep_the_paper_rule(planner):
    # no stall on the paper's map: eq 17 as printed is what plans
    s = get_map("rfogwo-map1")
    pl = get_planner(planner)(s, None, np.random.default_rng(1), s.static_obstacles())
    assert isinstance(pl, RfoFamilyPlanner)
    assert pl.plan(np.array(s.start), np.array(s.goal), s.robot.radius) is not None
    assert pl.progress_used == "euclidean"


def test_a_goal_closer_than_the_safety_margin_is_still_reached():
    # goal 4 cm beyond the radius from the first wall's face: the safety rule (10 cm on a 12 m
    # map) would forbid every final segment; the margin shrinks to half the goal's spare
    s = dataclasses.replace(load_scenario(TWO_WALLS), goal=(3.855, 2.0))
    assert abs(float(s.static_obstacles().point_clearance(np.array(s.goal))) - 0.145) < 1e-9
    out = Episode(s, "RFO-GWO-EA", seed=1).run()
    assert out.success, out.reason
    assert out.collisions == 0


DATA = Path(__file__).parent / "data"


@pytest.mark.parametrize("map_name", ["tb3_sandbox.yaml", "arena.map", "icoot-map1", "icoot-map2"])
@pytest.mark.parametrize("planner", HYBRIDS)
def test_imported_and_preset_maps_are_solved(planner, map_name):
    """Issue 12's maps beyond the paper's (nav2's tb3_sandbox and MovingAI's arena with the
    importers' default endpoints; ICOOT's maps 1-2): reached, without contact, never below the
    exact optimum. Seed 3 here; scripts/bench/maps.py runs seeds 1-5 (docs/benchmarks.md)."""
    from swarmpath.world.importers import load_movingai_map, load_ros_map

    if map_name.endswith(".yaml"):
        s = load_ros_map(DATA / map_name).scenario
    elif map_name.endswith(".map"):
        s = load_movingai_map(DATA / map_name).scenario
    else:
        s = get_map(map_name)
    out = Episode(s, planner, seed=3).run()
    assert out.success, out.reason
    assert out.collisions == 0
    assert out.optimum is not None and out.length >= out.optimum - 2e-9
