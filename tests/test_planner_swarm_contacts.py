"""Contacts of the swarm local planners that were planner bugs (docs/planners.md, "Open").

* With 1 s simulated steps (the rfogwo maps) a decision drove a whole 1 m step toward its
  waypoint, past the 0.8 m that mfb-12 senses beyond the body: the robot ran into obstacles it
  had not seen, or into a corner's tip between two rays. A move is now cut to where the
  sensors covered the space with less than the safety distance of error.
* Sensed hits were merged on a 5 cm grid keeping an arbitrary one per cell, so a corner's hit
  could be dropped for one 5-7 cm away; the grid is now 1 cm.
"""

import numpy as np
import pytest

from decision_log import run_recording
from swarmpath import metrics
from swarmpath.planners import Episode, sensed_map, swarm_local
from swarmpath.robot.sensors import get_sensor_model
from swarmpath.world import get_map, load_scenario


def wall_ahead(time_step: float) -> object:
    """A wall across the straight line 3.1 m ahead of the start: with 1 m steps the robot stands
    at x = 3 with the wall 1.1 m away (beyond the 0.2 + 0.8 m it senses), and a 1 m step puts its
    0.2 m body 0.1 m into it."""
    return load_scenario({
        "name": "wall-ahead", "size": [12, 8], "start": [1, 4], "goal": [11, 4],
        "robot": {"model": "omni", "radius": 0.2, "linear_speed": 1.0},
        "obstacles": [{"shape": "polygon", "points": [[4.1, 2.5], [4.4, 2.5], [4.4, 5.5],
                                                       [4.1, 5.5]]}],
        "sensors": "mfb-12", "time_step": time_step,
    })


@pytest.mark.parametrize("planner", ["MFB", "HPSO-MFB", "ICOOT", "IHPO"])
def test_a_move_never_reaches_past_what_the_sensors_covered(planner):
    # before the cut, HPSO-MFB, ICOOT and IHPO (seed 1) touched the wall (MFB missed it by luck)
    episode = Episode(wall_ahead(1.0), planner, seed=1, step_limit=40)
    out, made = run_recording(episode)
    # within the range (0.8 m - 3 cm of corner safety), and where a corner between two rays 5
    # degrees apart sticks out by less than 3 cm: 2 * 0.03 / 5 deg - 0.2 - 0.03 = 0.457 m
    reach = min(float(np.max(get_sensor_model("mfb-12").ranges)) - 0.03,
                2 * 0.03 / np.radians(5.0) - 0.2 - 0.03)
    assert episode.planner._commit(0.0, 0.2) == pytest.approx(reach)
    moves = [float(np.hypot(*(d.target - p))) for p, d in made if d.target is not None]
    assert max(moves) <= reach + 1e-9
    assert out.success and out.collisions == 0 and out.min_clearance > 0


def test_fine_time_steps_are_not_cut():
    # 0.1 s steps at 1 m/s: a decision (0.25 s -> 3 steps) drives 0.3 m, well inside the range
    planner = Episode(wall_ahead(0.1), "MFB", seed=1).planner
    assert planner._travel == pytest.approx(0.3)
    assert planner._travel < planner._commit(0.0, 0.2)
    planner = Episode(wall_ahead(1.0), "MFB", seed=1).planner
    assert planner._travel == pytest.approx(1.0) and planner._range == pytest.approx(0.8)


def test_merged_hits_stay_within_a_fraction_of_the_safety_distance():
    rng = np.random.default_rng(5)
    hits = rng.uniform(0.0, 2.0, size=(4000, 2))
    kept = sensed_map.condense(hits, np.array([1.0, 1.0]), np.inf, swarm_local.HIT_CELL)
    nearest = np.min(np.hypot(*(hits[:, None, :] - kept[None, :, :]).transpose(2, 0, 1)), axis=1)
    # every sensed point has a kept point within the cell diagonal (1.4 cm), under the 3 cm
    # that the robot keeps near corners
    assert nearest.max() <= swarm_local.HIT_CELL * np.sqrt(2) + 1e-12
    assert swarm_local.HIT_CELL * np.sqrt(2) < 0.03


@pytest.mark.parametrize("planner", ["MFB", "IHPO"])
def test_rfogwo_map3_seed_1_reaches_the_goal_without_contact(planner):
    # Before: MFB ran 0.8-0.9 m of a 1 m step into unseen obstacles (t = 76, 215, 229 s);
    # IHPO touched a polygon corner whose hit the 5 cm merge had dropped (t = 223 s).
    episode = Episode(get_map("rfogwo-map3"), planner, seed=1)
    out = episode.run()
    path = episode.sim.path()
    gaps = metrics.step_clearances(path, episode.sim.world.obstacles_at) - episode.sim.radius
    assert out.success, out.reason
    assert out.collisions == 0 and gaps.min() > 0
