"""The simulator's motion guard (docs/planners.md, "The motion guard"): a swarm planner's step that
would sweep the body into a static obstacle is cut short, so no robot-driven contact with static
geometry happens, even on a map where the swarms used to drive into a thin wall."""

from pathlib import Path

import numpy as np
import pytest

from swarmpath.planners import Episode, get_planner, list_planners
from swarmpath.planners.simulator import Simulator
from swarmpath.world.scenario_io import load_scenario

THIN_WALL = Path(__file__).parent / "data" / "thin_wall.json"
#: Simulated seconds per run (the map's default limit is 79 s). Without the guard every swarm
#: planner but MFB touches the wall within it (first contacts, seed 1: 13-38 s); with it and
#: ``escape = 0`` four of them creep along the wall until the limit (tests/test_planner_escape.py).
TIME_LIMIT = 40.0
GUARDED = [n for n in list_planners() if get_planner(n).guarded]


def test_the_swarm_planners_are_guarded():
    assert {"ICOOT", "IHPO", "COOT", "MFB"} <= set(GUARDED)


@pytest.mark.parametrize("planner", GUARDED)
def test_no_contact_beside_a_thin_wall(planner):
    """Seed 1: ICOOT, IHPO, HPO, HPSO-MFB and GWO collided here (5-10 steps) and COOT and PSO
    collided until the time limit, all robot-driven, before the guard. Without it, ICOOT, COOT,
    IHPO, HPO, HPSO-MFB, PSO and GWO all touch the wall within TIME_LIMIT."""
    out = Episode(load_scenario(THIN_WALL), planner, seed=1, time_limit=TIME_LIMIT).run()
    assert out.collisions == 0, out.reason
    assert out.robot_driven_contacts == 0


def _toward_the_wall(guard: bool) -> Simulator:
    sim = Simulator(load_scenario(THIN_WALL), np.random.default_rng(0), None, guard=guard)
    sim.drive(np.array([1.9, 0.5]), None, time_limit=20.0, align=True)
    return sim


def test_the_guard_stops_the_body_at_the_wall():
    guarded = _toward_the_wall(True)
    radius = guarded.radius
    assert guarded.pose.x < 1.8 - radius  # never touching (clearance <= radius is a contact)
    assert guarded.pose.x > 1.8 - radius - 0.01  # but it drove as far as it safely could
    assert _toward_the_wall(False).pose.x > 1.8 - radius  # without it the body enters the wall
