"""The sensors-only fallback of the swarm local planners (``escape_plan = "memory"``;
planners/swarm_memory.py; docs/planners.md, "Leaving clutter with sensors only"): an occupancy
memory of the robot's own scans and the shortest way on it, unseen cells free."""

from __future__ import annotations

import dataclasses
import itertools
from pathlib import Path

import numpy as np
import pytest

from swarmpath.optimizers.streams import OPTIMIZER, run_generator
from swarmpath.planners import Episode, get_planner
from swarmpath.planners.cost_to_go import MAX_CELLS
from swarmpath.planners.swarm_memory import MemoryWay
from swarmpath.world import clearance as fast
from swarmpath.world import get_map
from swarmpath.world.geometry import ObstacleSet
from swarmpath.world.importers import load_movingai_map

DATA = Path(__file__).parent / "data"
# a cut of maze-32-32-4 (rows 10-20, top and bottom closed; tests/data/README.md): the goal is in
# the room above the start's corridor, behind a 21 m wall open only at its far (left) end
MAZE_CUT = DATA / "maze-32-32-4-cut.map"
ENDS = {"start": (28.5, 2.5), "goal": (15.5, 9.5)}
FAST = "numba" if fast.compiled_available() else "numpy"


def _cup() -> np.ndarray:
    """Points of a cup open to the left around (5, 5): walls at x = 6, y = 4 and y = 6."""
    t = np.linspace(0.0, 1.0, 41)
    right = np.column_stack([np.full_like(t, 6.0), 4.0 + 2.0 * t])
    low = np.column_stack([4.0 + 2.0 * t, np.full_like(t, 4.0)])
    high = np.column_stack([4.0 + 2.0 * t, np.full_like(t, 6.0)])
    return np.concatenate([right, low, high])


def _length(way: np.ndarray) -> float:
    return float(np.sum(np.hypot(*np.diff(way, axis=0).T)))


def test_the_way_leaves_a_cup_by_its_opening_and_keeps_the_clearance():
    memory = MemoryWay((10.0, 10.0), 0.1, 0.3, 0.3, "numpy")
    cup = _cup()
    memory.remember(cup)
    start, goal = np.array([5.0, 5.0]), np.array([9.0, 5.0])
    way = memory.ahead(start, goal, 1.0)
    assert memory.found and memory.plans == 1
    assert np.array_equal(way[0], start) and np.allclose(way[-1], goal)
    assert np.min(way[:, 0]) < 4.0  # out by the opening on the left, around a wall
    dots = ObstacleSet(circles=np.column_stack([cup, np.zeros(len(cup))]))
    for a, b in itertools.pairwise(way):
        assert float(dots.segment_clearance(a, b)) > 0.3
    # at least as long as going round the wall's end, at most the octile excess more
    assert _length(way) > 2 * 1.3 + 2.0


def test_the_way_is_planned_again_only_when_a_new_hit_comes_near_it():
    memory = MemoryWay((10.0, 10.0), 0.1, 0.3, 0.3, "numpy")
    start, goal = np.array([1.0, 5.0]), np.array([9.0, 5.0])
    way = memory.ahead(start, goal, 1.0)
    assert memory.plans == 1 and _length(way) == pytest.approx(8.0)  # nothing known: straight
    far = np.array([[5.0, 9.0], [5.1, 9.0]])
    memory.remember(far)
    memory.ahead(start, goal, 1.0)
    assert memory.plans == 1  # a hit off the way: the way is still the shortest
    wall = np.column_stack([np.full(31, 5.0), np.linspace(3.5, 6.5, 31)])
    memory.remember(wall)
    way = memory.ahead(start, goal, 1.0)
    assert memory.plans == 2  # a wall across it: planned again, around it
    assert _length(way) > 8.5
    # hits already known change nothing
    memory.remember(wall)
    memory.ahead(start, goal, 1.0)
    assert memory.plans == 2

def test_the_memory_is_bounded_by_the_worlds_area():
    memory = MemoryWay((600.0, 600.0), 0.1, 0.3, 0.3, "numpy")
    assert memory.occupied.size <= MAX_CELLS
    assert memory.spec.resolution > 0.1


def test_a_robot_closer_than_the_clearance_starts_from_a_free_cell_nearby():
    memory = MemoryWay((10.0, 10.0), 0.1, 0.3, 0.3, "numpy")
    wall = np.column_stack([np.linspace(0.0, 10.0, 101), np.full(101, 5.0)])
    memory.remember(wall)
    memory.ahead(np.array([2.0, 5.2]), np.array([8.0, 8.0]), 1.0)
    assert memory.found and memory.way is not None
    assert memory.way[1][1] > 5.3  # away from the wall first, to a cell keeping the clearance


def _maze(planner: str, seed: int = 1, time_limit: float | None = None, **params):
    scenario = load_movingai_map(MAZE_CUT, **ENDS).scenario
    return Episode(scenario, planner, seed=seed, params={"backend": FAST, **params},
                   time_limit=time_limit).run()


def test_in_the_maze_cut_the_memory_reaches_the_goal_where_the_earlier_rule_does_not():
    new = _maze("MFB")
    assert new.success, new.reason
    assert new.collisions == 0
    assert new.length >= new.optimum
    old = _maze("MFB", time_limit=2 * new.travel_time, escape_plan="hulls")
    assert not old.success
    assert old.collisions == 0


def test_the_planner_never_reads_the_map():
    """The same run when the planner is handed a scenario without its obstacles: everything it
    knows of them comes from the simulator's sensor readings."""
    scenario = load_movingai_map(MAZE_CUT, **ENDS).scenario
    params = {"backend": FAST}
    seen = Episode(scenario, "MFB", seed=1, params=params, time_limit=120.0)
    blind = Episode(scenario, "MFB", seed=1, params=params, time_limit=120.0)
    hidden = dataclasses.replace(scenario, obstacles=(), grid=None)
    blind.planner = get_planner("MFB")(hidden, params, run_generator(1, 0, OPTIMIZER), None)
    a, b = seen.run(), blind.run()
    assert seen.planner._memory_way.leading  # the fallback ran
    assert a.length == b.length and a.steps == b.steps
    assert np.array_equal(seen.sim.path(), blind.sim.path())


def test_a_run_without_a_stall_is_the_same_with_either_escape_plan():
    """mfb-static never stalls: the memory is kept but never followed, the paper preset's run is
    the same to the last digit as with the earlier rule."""
    on = Episode(get_map("mfb-static"), "MFB", seed=1)
    off = Episode(get_map("mfb-static"), "MFB", seed=1, params={"escape_plan": "hulls"})
    a, b = on.run(), off.run()
    assert not on.planner._memory_way.leading
    assert a.success and a.length == b.length and a.steps == b.steps
