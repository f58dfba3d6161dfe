"""Why runs fail (planners.failures): each class from trajectories made to show it, from real
episodes, in the summaries (CLI, store) and the dashboard's failure kind; and the episode's
limits, which grow with the exact optimum so that a long way is not cut as a failure."""

import math
from pathlib import Path

import numpy as np
import pytest

from swarmpath.failure_classes import FAILURE_CLASSES, count_classes
from swarmpath.planners import Episode
from swarmpath.planners.failures import classify
from swarmpath.planners.summary import summarize_cell
from swarmpath.service.store.summaries import map_cell_summary
from swarmpath.service.web.series import failure_kind
from swarmpath.world import get_map
from swarmpath.world.scenario_io import load_scenario

DATA = Path(__file__).parent / "data"


def _path(xy, dt=0.1):
    xy = np.asarray(xy, dtype=float)
    return np.column_stack([xy, dt * np.arange(len(xy))])


def _limit(path, to_go, mover_gap=None, radius=0.105):
    return classify(path, "time limit (200 s simulated)", 0, radius, np.asarray(to_go), True,
                    False, 0.2, float(to_go[-1]), mover_gap)


def test_each_class_from_a_trajectory_made_to_show_it():
    n = 2000  # 200 s
    # still getting closer at the end: the budget, not a trap
    xs = np.linspace(0.0, 40.0, n)
    kind, detail = _limit(_path(np.column_stack([xs, np.zeros(n)])), 50.0 - xs)
    assert kind == "progressing" and "closer in the last" in detail
    # stuck after 20 s: nearly still, back and forth, far and wide
    approach = np.linspace(0.0, 10.0, 200)
    still = np.full(n - 200, 10.0) + np.linspace(0.0, 0.3, n - 200)
    to_go = np.concatenate([30.0 - approach, np.full(n - 200, 20.0)])
    boxed = np.column_stack([np.concatenate([approach, still]), np.zeros(n)])
    assert _limit(_path(boxed), to_go).kind == "boxed-in"
    shake = 10.0 + 0.8 * np.sin(np.linspace(0.0, 60.0, n - 200))
    oscillating = np.column_stack([np.concatenate([approach, shake]), np.zeros(n)])
    kind, detail = _limit(_path(oscillating), to_go)
    assert kind == "oscillating"
    assert "no progress for 18" in detail and "20.0 m from the goal" in detail
    angle = np.linspace(0.0, 4 * math.pi, n - 200)
    loop = np.column_stack([10.0 + 8.0 * np.sin(angle), 8.0 - 8.0 * np.cos(angle)])
    wandering = np.vstack([np.column_stack([approach, np.zeros(200)]), loop])
    assert _limit(_path(wandering), to_go).kind == "wandering"
    # the same still robot beside a moving obstacle
    assert _limit(_path(boxed), to_go, lambda t, xy: 0.2).kind == "blocked-by-mover"
    assert _limit(_path(boxed), to_go, lambda t, xy: 3.0).kind == "boxed-in"


def test_terminal_classes():
    path = _path([[0.0, 0.0], [1.0, 0.0]])
    to_go = np.array([2.0, 1.0])
    assert classify(path, "goal reached", 3, 0.1, to_go, True, False, 0.2,
                    1.0).kind == "collision"
    gave = classify(path, "planner gave up: no path found", 0, 0.1, to_go, True, False, 0.2, 1.0)
    assert gave == ("gave-up", "no path found")
    short = classify(path, "time limit (9 s simulated)", 0, 0.1, np.array([2.0, 0.3]), True,
                     False, 0.2, 0.15)
    assert short.kind == "short-of-goal"
    # a moving goal within the tolerance is reached, never "short"
    assert classify(path, "time limit", 0, 0.1, np.array([2.0, 0.15]), False, True,
                    0.2, 0.15).kind != "short-of-goal"


def test_counts_follow_the_class_order():
    counts = count_classes(["wandering", "boxed-in", None, "boxed-in", "collision", "<b>x"])
    assert list(counts) == ["collision", "boxed-in", "wandering", "unclassified"]
    assert counts["unclassified"] == 2  # a name no classifier gives is data, not a class
    assert counts["boxed-in"] == 2
    assert set(FAILURE_CLASSES) >= {"oscillating", "boxed-in", "blocked-by-mover", "progressing"}


def test_a_run_cut_by_its_step_limit_while_driving_on_is_progressing():
    out = Episode(get_map("mfb-static"), "MFB", seed=1, step_limit=40).run()
    assert not out.success and out.reason == "step limit (40 decisions)"
    assert out.failure_class == "progressing"
    assert "along free space" in (out.failure_detail or "")
    ok = Episode(get_map("mfb-static"), "MFB", seed=1).run()
    assert ok.success and ok.failure_class is None and ok.failure_detail is None


def test_a_swarm_planner_trapped_at_a_thin_wall_oscillates():
    """COOT without the escape on the thin wall (docs/planners.md, "Escaping a local minimum"):
    it ends at the time limit going back and forth beside the wall, 1.9 m from the goal. It
    makes no progress after its first 3-4 s, so a 50 s limit (the default's half) shows it as
    well as the default 107 s does (the same class, the same 1.9 m) at half the CPU."""
    scenario = load_scenario(DATA / "thin_wall.json")
    out = Episode(scenario, "COOT", seed=1, params={"escape": 0}, time_limit=50.0).run()
    assert out.reason == "time limit (50 s simulated)"
    assert out.failure_class == "oscillating", out.failure_detail
    summary = summarize_cell([out.to_dict()])
    assert summary["failure_classes"] == {"oscillating": 1}
    store = map_cell_summary([out.to_dict()])
    assert store["failure_classes"] == {"oscillating": 1}
    assert failure_kind(out.to_dict()) == "oscillating"
    # runs stored before the classes keep the old kinds
    assert failure_kind({"reason": "time limit (9 s simulated)", "collisions": 0}) == "timeout"
    assert failure_kind({"reason": "time limit", "failure_class": "<script>"}) == "timeout"


def test_limits_grow_with_the_exact_optimum():
    """The time limit is 6 x the optimum's travel time + 60 s (the straight line on maps with
    moving things); the step limit allows a decision per simulated step."""
    two_walls = load_scenario(DATA / "two_walls.json")
    ep = Episode(two_walls, "MFB", seed=1)
    speed = two_walls.robot.linear_speed
    assert ep.time_limit == pytest.approx(6.0 * 12.659 / speed + 60.0, rel=1e-4)
    assert ep.step_limit == max(2000, math.ceil(ep.time_limit / two_walls.time_step - 1e-9))
    moving = get_map("icoot-map4")
    straight = math.dist(moving.start, moving.goal)
    ep = Episode(moving, "MFB", seed=1)
    assert ep.time_limit == pytest.approx(6.0 * straight / moving.robot.linear_speed + 60.0)
    assert ep.step_limit == math.ceil(ep.time_limit / moving.time_step - 1e-9)
    assert Episode(moving, "MFB", seed=1, step_limit=7).step_limit == 7
