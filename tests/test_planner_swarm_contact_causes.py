"""Swarm local planners never drive into an obstacle that moves steadily (contacts by cause,
docs/planners.md). The presets with steady movers come from the registry; the random walkers of
icoot-map4 / ihpo-map3 are excluded: there contacts happen (docs/planners.md, "Open")."""

import pytest

from swarmpath.planners import Episode
from swarmpath.world import get_map, list_maps
from swarmpath.world.scenario import RandomMotion

STEADY = [m for m in list_maps()
          if get_map(m).is_dynamic
          and not any(isinstance(o.motion, RandomMotion) for o in get_map(m).obstacles)]


def test_the_steady_presets_are_found():
    assert {"mfb-dynamic", "icoot-map3"} <= set(STEADY)


@pytest.mark.parametrize("map_name", STEADY)
@pytest.mark.parametrize("planner", ["ICOOT", "MFB"])  # a diff-drive and an omni preset
def test_no_robot_driven_contact_among_steady_movers(map_name, planner):
    out = Episode(get_map(map_name), planner, seed=1).run()
    assert out.robot_driven_contacts == 0
    assert out.robot_driven_contacts + out.obstacle_driven_contacts == out.collisions
    assert out.success, out.reason
