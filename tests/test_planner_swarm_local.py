"""The swarm local planner's decisions: aim, waypoint hold, safety by robot, presets."""

import numpy as np
import pytest

from decision_log import run_recording
from swarmpath.planners import Episode
from swarmpath.world import get_map


def decisions(planner, scenario="mfb-static", params=None, steps=60):
    episode = Episode(get_map(scenario), planner, seed=2, run=0, params=params, step_limit=steps)
    return run_recording(episode)


def test_free_space_aim_is_the_lookahead_point_toward_the_goal():
    planner = Episode(get_map("mfb-static"), "MFB", seed=1).planner
    p, goal = np.array([1.0, 2.0]), np.array([9.0, 8.0])
    aim = planner._aim(p, goal, np.zeros((0, 2)), 0.51, (0.0, 0.0, 10.0, 10.0))
    # 1 m along the straight line, not the goal (whose clip to the square box would bend the
    # heading toward the box corner)
    assert aim == pytest.approx(p + (goal - p) / 10.0)


def test_held_waypoints_are_reused_and_hold_angle_zero_always_searches():
    _, made = decisions("MFB")
    held = [(p, d) for p, d in made if d.iterations == 0 and not d.finish]
    assert held, "a waypoint is held on the straight stretches"
    for k, (_, d) in enumerate(made):
        if d.iterations == 0 and not d.finish:
            assert np.array_equal(d.target, made[k - 1][1].target)  # the previous waypoint
    _, searched = decisions("MFB", params={"hold_angle": 0})
    assert all(d.iterations > 0 for _, d in searched if not d.finish)


def test_hpso_mfb_reaches_the_goal_within_3_percent_without_touching():
    out, _ = decisions("HPSO-MFB", steps=120)
    assert out.success and out.collisions == 0
    assert out.min_clearance >= 0.0
    assert out.length <= 1.03 * 14.483


@pytest.mark.parametrize(("scenario", "safety"),
                         [("mfb-static", 0.01), ("icoot-map1", 0.05), ("rfogwo-map1", 0.03)])
def test_safety_follows_the_robot_and_its_time_step(scenario, safety):
    planner = Episode(get_map(scenario), "MFB", seed=1).planner
    # omni at 5 cm per step: 1 cm; diff-drive (turns as it drives): 5 cm; 1 m per step: 3 cm
    assert planner._safety(0.0) == safety


def test_a_sensed_corner_raises_the_safety_for_a_while():
    planner = Episode(get_map("mfb-static"), "MFB", seed=1).planner
    planner._corner_until = 4.0  # as if a corner had been sensed at t = 2 s (memory 2 s)
    assert planner._safety(3.9) == 0.03 and planner._safety(4.1) == 0.01


def test_hpso_mfb_preset_runs_five_bats_per_particle():
    planner = Episode(get_map("mfb-static"), "HPSO-MFB", seed=1).planner
    assert planner._opt_params["split"] == "per_particle"
    assert planner._opt_params["particles"] == 5 and planner.p["agents"] == 5


def test_icoot_and_ihpo_are_reproducible():
    for name in ("ICOOT", "IHPO"):
        a = Episode(get_map("mfb-static"), name, seed=4, run=1, step_limit=30).run()
        b = Episode(get_map("mfb-static"), name, seed=4, run=1, step_limit=30).run()
        assert a.path == b.path


def test_knowing_the_map_shortens_the_mfb_path_without_touching():
    sensing, _ = decisions("MFB", steps=120)
    knowing, _ = decisions("MFB", params={"knowledge": "map"}, steps=120)
    assert sensing.success and knowing.success
    assert sensing.collisions == 0 and knowing.collisions == 0 and knowing.min_clearance >= 0.0
    assert knowing.length < sensing.length
    assert knowing.length <= 1.02 * 14.483
