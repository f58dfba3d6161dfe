"""The swarm planners' ``backend = "numba"`` (planners.compiled): the grid repair and the hit
distances compiled, with the numpy reference's numbers to the last bit."""

import dataclasses

import numpy as np
import pytest

from swarmpath.planners import Episode, get_planner, list_planners, local, sensed_map
from swarmpath.planners.base import PlannerError
from swarmpath.planners.compiled import segments_clearance_kernel
from swarmpath.planners.episode import TIMING_FIELDS
from swarmpath.world import get_map

SWARM = [name for name in list_planners() if "backend" in get_planner(name).defaults]


def _context(rng, bounded, margin):
    wall = np.stack([np.full(30, 0.6), np.linspace(-0.7, 0.7, 30)], axis=1)
    ring = 0.4 * np.stack([np.cos(np.linspace(0, 5, 20)), np.sin(np.linspace(0, 5, 20))], axis=1)
    ring += np.array([-0.5, 0.3])
    hits = np.vstack([wall, ring, rng.uniform(-1.2, 1.2, (15, 2))])
    box = dict(lower=np.array([-1.0, -0.9]), upper=np.array([1.0, 0.8])) if bounded else {}
    return local.StepContext(position=np.array([0.05, -0.02]), goal=np.array([3.0, 0.5]),
                             hits=hits, margin=margin, repair="grid", safety=0.03, **box)


@pytest.mark.parametrize("bounded", [True, False])
@pytest.mark.parametrize("margin", [0.06, 0.12, 0.2])
def test_compiled_grid_repair_equals_numpy(bounded, margin):
    rng = np.random.default_rng(int(margin * 100) + bounded)
    ctx = _context(rng, bounded, margin)
    fast = dataclasses.replace(ctx, backend="numba")
    cands = rng.uniform(-1.1, 1.1, (300, 2))
    cands[:5] = [[0.6, 0.0], [0.05, -0.02], [-1.0, 0.8], [0.6, 0.7], [1.0, -0.9]]
    ref, ref_short = local._repair_grid(cands, ctx)
    got, got_short = local._repair_grid(cands, fast)
    assert np.array_equal(ref, got) and np.array_equal(ref_short, got_short)
    assert np.any(ref_short > 0) and np.any((ref_short == 0) & np.any(ref != cands, axis=1))
    a, b = local.score(cands.reshape(20, 15, 2), ctx), local.score(cands.reshape(20, 15, 2), fast)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    for one, other in zip(local._distances(cands, ctx), local._distances(cands, fast),
                          strict=True):
        assert np.array_equal(one, other) and one.dtype == other.dtype
    mfb, mfb_fast = (dataclasses.replace(c, repair="mfb") for c in (ctx, fast))
    a, b = local.score(cands, mfb), local.score(cands, mfb_fast)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])


@pytest.mark.parametrize("bounded", [True, False])
@pytest.mark.parametrize("margin", [0.06, 0.12, 0.2])
@pytest.mark.parametrize("rounds", [1, 3])
def test_compiled_mfb_repair_equals_numpy(bounded, margin, rounds):
    rng = np.random.default_rng(int(margin * 100) + 7 * bounded + rounds)
    ctx = dataclasses.replace(_context(rng, bounded, margin), repair="mfb")
    fast = dataclasses.replace(ctx, backend="numba")
    cands = rng.uniform(-1.1, 1.1, (300, 2))
    # on a hit, on the robot, straight behind a hit (the left normal), outside the box
    cands[:5] = [[0.6, 0.0], [0.05, -0.02], [1.15, -0.02], [1.3, 0.7], [-1.2, -1.0]]
    ref, ref_short = local._repair_mfb(cands.reshape(20, 15, 2), ctx, rounds)
    got, got_short = local._repair_mfb(cands.reshape(20, 15, 2), fast, rounds)
    assert np.array_equal(ref, got) and np.array_equal(ref_short, got_short)
    moved = np.any(ref.reshape(-1, 2) != cands, axis=1)
    # both cases repaired some candidates, and some stay infeasible
    assert moved.sum() > 10 and np.any(ref_short > 0) and np.any(moved & (ref_short.ravel() == 0))


@pytest.mark.parametrize("name", SWARM)
def test_planner_episode_is_the_same_with_numba(name):
    scenario = get_map("icoot-map4")
    runs = [Episode(scenario, name, 2, 0, {"backend": b}, step_limit=40).run() for b in
            ("numpy", "numba")]
    a, b = (r.to_dict() for r in runs)
    for key in TIMING_FIELDS:
        a.pop(key), b.pop(key)
    assert a == b and a["iterations"] > 0


def test_backend_is_checked():
    with pytest.raises(PlannerError, match="backend"):
        get_planner("ICOOT").resolve_params({"backend": "cuda"})


def test_compiled_segment_clearance_equals_numpy():
    rng = np.random.default_rng(5)
    hits = rng.uniform(-1.0, 1.0, (70, 2))
    path = np.cumsum(rng.uniform(-0.3, 0.5, (12, 2)), axis=0)
    path[3] = path[2]  # a zero-length piece
    for reach in (0.2, 1.0, 50.0):
        ref = sensed_map.path_clearance(path, hits, reach)
        assert ref == sensed_map.path_clearance(path, hits, reach, "numba") and ref < 0.3
    aims = set()
    for margin in (0.05, 0.1, 0.3):
        for lookahead in (0.5, 1.5, 4.0):
            ref = sensed_map.shortcut(path, hits, margin, lookahead)
            got = sensed_map.shortcut(path, hits, margin, lookahead, backend="numba")
            assert np.array_equal(ref, got)
            aims.add(tuple(ref))
    assert len(aims) > 3  # the margins and lookaheads pick different samples
    a, b = path[:-1], path[1:]
    ref = sensed_map._segments_clearance(hits, a, b)
    assert np.array_equal(ref, segments_clearance_kernel(hits, a, b))


@pytest.mark.parametrize("surface", [0.05, 0.2, 0.5])
def test_compiled_surface_motion_equals_numpy(surface):
    rng = np.random.default_rng(int(surface * 100))
    moved = 0
    for _ in range(20):
        a = np.linspace(0.0, rng.uniform(1.0, 6.0), 60)
        radius = rng.uniform(0.5, 3.0, (60, 1))
        previous = np.stack([np.cos(a), np.sin(a)], axis=1) * radius
        current = previous + rng.normal(0.0, 0.03, previous.shape)
        current[:20] += 0.05  # a piece of the surface moved
        ref = sensed_map.motion(previous, current, 0.25, surface=surface)
        got = sensed_map.motion(previous, current, 0.25, surface=surface, backend="numba")
        assert np.array_equal(ref[0], got[0]) and np.array_equal(ref[1], got[1])
        moved += int(ref[0].sum())
        for one, other in zip(sensed_map._to_surface(current, previous, surface),
                              sensed_map._to_surface(current, previous, surface, "numba"),
                              strict=True):
            assert np.array_equal(one, other)
    assert moved > 0
