"""The known path of the swarm local planners on icoot-map2 (docs/planners.md, "icoot-map2")."""

import functools

from swarmpath.planners import Episode
from swarmpath.world import get_map


@functools.cache
def icoot_map2():  # type: ignore[no-untyped-def]
    return get_map("icoot-map2")  # one object: the episode caches the exact optimum by identity


def test_planning_around_everything_known_avoids_the_dead_end():
    # aim_hits = "near" (the earlier rule) planned only around the hits within reach of a
    # candidate and drove along the underside of the L-shaped obstacle: 10.2 % above the optimum
    near = Episode(icoot_map2(), "ICOOT", seed=1, params={"aim_hits": "near"}).run()
    known = Episode(icoot_map2(), "ICOOT", seed=1).run()
    assert near.success and known.success
    assert known.collisions == near.collisions == 0
    assert known.length < near.length - 0.3  # 15.39 m against 15.95 m


def test_with_the_map_known_icoot_is_within_three_percent():
    # what remains is the sensing: from the start only part of the first pentagon is seen, and
    # the shortest way around that part is on the side the whole map shows to be longer
    out = Episode(icoot_map2(), "ICOOT", seed=1, params={"knowledge": "map"}).run()
    assert out.success and out.collisions == 0
    assert out.gap is not None and out.gap < 0.03  # 0.44 %
