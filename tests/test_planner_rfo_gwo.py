"""RFO, RFO-GWO and RFO-GWO-EA global planners (Ketafa & Al-Darraji 2024)."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from swarmpath.optimizers.streams import run_generator
from swarmpath.planners import Decision, Episode, Observation, PlannerError, get_planner
from swarmpath.planners.rfo_gwo import RfoFamilyPlanner, path_length
from swarmpath.robot.kinematics import Pose
from swarmpath.world import get_map
from swarmpath.world.geometry import collides
from swarmpath.world.scenario import Obstacle, RobotSpec, Scenario

PLANNERS = ("RFO", "RFO-GWO", "RFO-GWO-EA")
MAPS = ("rfogwo-map1", "rfogwo-map2", "rfogwo-map3", "mfb-static")


@functools.cache
def scenario(name: str) -> Scenario:
    return get_map(name)  # one object per map: the episode caches the exact optimum by identity


@functools.cache
def episode(map_name: str, planner: str, seed: int = 1, run: int = 0):  # type: ignore[no-untyped-def]
    ep = Episode(scenario(map_name), planner, seed=seed, run=run)
    return ep, ep.run()


def planned(map_name: str, planner: str, seed: int, params=None) -> RfoFamilyPlanner:  # type: ignore[no-untyped-def]
    s = scenario(map_name)
    pl = get_planner(planner)(s, params, run_generator(seed, 0), s.static_obstacles())
    assert isinstance(pl, RfoFamilyPlanner)
    pl.plan(np.array(s.start), np.array(s.goal), s.robot.radius)
    return pl


def assert_clear(pl: RfoFamilyPlanner, path: np.ndarray, s: Scenario) -> None:
    """Every segment passes the product's rule with the robot radius plus the safety margin
    (scaled to the map: 0.2 m on the paper's 170 m maps, 0.1 m on 10 m maps)."""
    clearance = s.static_obstacles().segment_clearance(path[:-1], path[1:])
    margin = pl.safety_clearance(*s.size)
    assert not np.any(collides(clearance, s.robot.radius + margin)), clearance.min()


def test_registered_as_global_planners():
    for name in PLANNERS:
        cls = get_planner(name)
        assert cls.kind == "global" and "Ketafa" in cls.reference
    assert get_planner("RFO").defaults["foxes"] == 15
    assert get_planner("RFO-GWO").defaults["wolves"] == 7
    assert get_planner("RFO-GWO").defaults["iterations"] == 2000


@pytest.mark.parametrize("map_name", MAPS)
@pytest.mark.parametrize("planner", PLANNERS)
def test_reaches_the_goal_collision_free(planner, map_name):
    ep, out = episode(map_name, planner)
    pl = ep.planner
    assert out.success, out.reason
    assert out.collisions == 0 and out.reason == "goal reached"
    # nodes (the paper's Table 2) = waypoints after the start = decisions of the episode
    assert out.steps == len(pl.path) - 1
    assert out.iterations == pl.cost > 0  # cost = RFO iterations consumed
    assert np.array_equal(pl.path[0], scenario(map_name).start)
    assert np.array_equal(pl.path[-1], scenario(map_name).goal)
    assert_clear(pl, pl.path, scenario(map_name))
    # the robot drives the segments exactly; the run ends within 0.2 m of the goal
    assert path_length(pl.path) - 0.2 - 1e-6 <= out.length <= path_length(pl.path) + 1e-6
    assert out.optimum is not None and path_length(pl.path) >= out.optimum - 1e-9


@pytest.mark.parametrize("planner", PLANNERS)
def test_same_seed_same_path_and_different_seed_different_path(planner):
    _, first = episode("mfb-static", planner, 1)
    again = Episode(scenario("mfb-static"), planner, seed=1, run=0).run()
    assert again.path == first.path and again.iterations == first.iterations
    _, other = episode("mfb-static", planner, 2)
    assert other.path != first.path


def test_other_run_index_gives_another_path():
    _, a = episode("rfogwo-map1", "RFO-GWO", 1, 0)
    _, b = episode("rfogwo-map1", "RFO-GWO", 1, 1)
    assert a.success and b.success and a.path != b.path


def test_ea_starts_from_the_rfo_gwo_path_and_never_lengthens_it():
    for seed in (1, 2, 3):
        hybrid = planned("mfb-static", "RFO-GWO", seed)
        ea = planned("mfb-static", "RFO-GWO-EA", seed)
        # phase A draws the same random numbers up to the first arrival: RFO-GWO's path is the
        # first of the EA's reference paths, and the others are other foxes' paths
        assert np.array_equal(ea.raw_path, hybrid.path)
        assert np.array_equal(ea.raw_paths[0], hybrid.path)
        assert len(ea.raw_paths) == ea.p["arrivals"] == 5
        assert ea.cost >= hybrid.cost
        assert path_length(ea.path) <= path_length(hybrid.path) + 1e-9


@pytest.mark.parametrize("map_name", ["mfb-static", "rfogwo-map3"])
def test_erase_mutation_never_lengthens_and_stays_clear(map_name):
    s = scenario(map_name)
    pl = planned(map_name, "RFO-GWO-EA", 4)
    raw = pl.raw_path
    for path in (raw, pl._split(raw, 1.0)):
        before = path_length(path)
        (out,) = pl._ea([path])
        assert path_length(out) <= before + 1e-9
        assert np.array_equal(out[0], path[0]) and np.array_equal(out[-1], path[-1])
        # Erase only removes nodes: the result is a subsequence of the input
        rows = [int(np.flatnonzero(np.all(path == q, axis=1))[0]) for q in out]
        assert rows == sorted(rows)
        assert_clear(pl, out, s)
    split = pl._split(raw, 1.0)
    assert path_length(split) == pytest.approx(path_length(raw))
    assert np.max(np.hypot(*np.diff(split, axis=0).T)) <= 1.0 + 1e-9


def test_ea_is_shorter_than_rfo_gwo_on_average():
    hybrid, ea = [], []
    for seed in (1, 2, 3, 4, 5):
        hybrid.append(path_length(planned("mfb-static", "RFO-GWO", seed).path))
        ea.append(path_length(planned("mfb-static", "RFO-GWO-EA", seed).path))
    for m in MAPS[:3]:
        hybrid.append(episode(m, "RFO-GWO")[1].length)
        ea.append(episode(m, "RFO-GWO-EA")[1].length)
    assert all(e <= h + 1e-6 for e, h in zip(ea, hybrid, strict=True))
    # measured: the EA removes the zigzags (about 10-30 % shorter)
    assert np.mean(ea) < 0.95 * np.mean(hybrid)


def _enclosed_goal() -> Scenario:
    walls = (
        Obstacle.rectangle(11.0, 11.0, 19.0, 12.0), Obstacle.rectangle(11.0, 18.0, 19.0, 19.0),
        Obstacle.rectangle(11.0, 11.0, 12.0, 19.0), Obstacle.rectangle(18.0, 11.0, 19.0, 19.0),
    )
    return Scenario("enclosed", (20.0, 20.0), (2.0, 2.0), (15.0, 15.0),
                    robot=RobotSpec.preset("omni", radius=0.2), obstacles=walls)


@pytest.mark.parametrize("planner,params", [
    ("RFO", {"iterations": 60}), ("RFO-GWO", {}), ("RFO-GWO-EA", {"patience": 10}),
])
def test_no_path_is_a_result_not_an_exception(planner, params):
    out = Episode(_enclosed_goal(), planner, seed=1, params=params).run()
    assert not out.success
    assert out.reason.startswith("planner gave up: no ")
    assert out.steps == 1 and out.iterations > 0


def test_start_in_collision_is_reported():
    s = Scenario("blocked", (10.0, 10.0), (2.0, 2.0), (8.0, 8.0),
                 robot=RobotSpec.preset("omni", radius=0.2),
                 obstacles=(Obstacle.circle((2.0, 2.1), 0.5),))
    # (planner only: the episode's exact optimum refuses such a scenario before planning)
    pl = get_planner("RFO-GWO")(s, None, run_generator(1, 0), s.static_obstacles())
    obs = Observation(0.0, Pose(*s.start, 0.0), np.array(s.goal), None, s.robot.radius, s.size)
    d = pl.decide(obs)
    assert d.target is None and d.reason == "start is in collision"


def test_decisions_hand_out_the_path_then_stop():
    s = scenario("mfb-static")
    pl = get_planner("RFO-GWO-EA")(s, None, run_generator(3, 0), s.static_obstacles())
    obs = Observation(0.0, Pose(*s.start, 0.0), np.array(s.goal), None, s.robot.radius, s.size)
    first = pl.decide(obs)
    assert isinstance(first, Decision) and first.duration is None
    assert first.iterations == pl.cost > 0
    got = [first.target]
    for _ in range(len(pl.path) - 2):
        d = pl.decide(obs)
        assert d.iterations == 0 and d.duration is None
        got.append(d.target)
    assert np.array_equal(np.array(got), pl.path[1:])
    end = pl.decide(obs)
    assert end.target is None and "exhausted" in (end.reason or "")


def test_parameter_options_work():
    for params in ({"reference": "best", "alpha_draw": "population"},
                   {"alpha_bound": "distance"}):
        pl = planned("mfb-static", "RFO-GWO", 1, params)
        assert pl.path is not None, pl.failure
        assert_clear(pl, pl.path, scenario("mfb-static"))


@pytest.mark.parametrize("planner,params", [
    ("RFO", {"foxes": 0}),
    ("RFO-GWO", {"wolves": 0}),
    ("RFO-GWO", {"safety_margin": 2.0}),
    ("RFO", {"notice": 1.5}),
    ("RFO-GWO-EA", {"split_length": 0.0}),
    ("RFO", {"wolves": 7}),  # RFO alone has no GWO
    ("RFO-GWO", {"alpha_bound": "cube"}),
])
def test_bad_parameters_are_rejected(planner, params):
    with pytest.raises(PlannerError):
        get_planner(planner).resolve_params(params)


def test_start_at_the_goal_gives_one_waypoint():
    s = scenario("mfb-static")
    pl = get_planner("RFO-GWO-EA")(s, None, run_generator(1, 0), s.static_obstacles())
    here = np.array([1.0, 9.0])
    path = pl.plan(here, here, s.robot.radius)
    assert path is not None and len(path) == 2 and pl.cost == 0
    assert np.array_equal(path[-1], here)


def test_node_clearance_scales_with_the_map() -> None:
    """1 m on the paper's 170 m maps, the safety margin's floor on a 10 m map."""
    cls = get_planner("RFO-GWO-EA")
    pl = cls(scenario("mfb-static"), None, run_generator(1, 0), None)
    assert isinstance(pl, RfoFamilyPlanner)
    assert pl.node_clearance(170.0, 170.0) == 1.0
    assert pl.node_clearance(10.0, 10.0) == pytest.approx(0.2)
    with pytest.raises(PlannerError):
        cls.resolve_params({"node_scale": -1.0})


def test_safety_clearance_scales_with_the_map() -> None:
    """20 cm on the paper's 170 m maps, 10 cm on a 10 m map; ``safety_scale = 0``: always 20 cm."""
    cls = get_planner("RFO-GWO")
    pl = cls(scenario("mfb-static"), None, run_generator(1, 0), None)
    assert isinstance(pl, RfoFamilyPlanner)
    assert pl.safety_clearance(170.0, 170.0) == 0.2
    assert pl.safety_clearance(10.0, 10.0) == pytest.approx(0.1)
    flat = cls(scenario("mfb-static"), {"safety_scale": 0.0}, run_generator(1, 0), None)
    assert isinstance(flat, RfoFamilyPlanner)
    assert flat.safety_clearance(10.0, 10.0) == 0.2
    with pytest.raises(PlannerError):
        cls.resolve_params({"safety_scale": -0.1})


def test_ea_path_near_the_optimum_on_mfb_static() -> None:
    """Issue 3's acceptance: seeds 1-10 collision-free at the goal, median within 3 % of the
    exact optimum (14.483 m; 14.625 m is the optimum with the 0.1 m safety margin)."""
    outs = [episode("mfb-static", "RFO-GWO-EA", seed=s)[1] for s in range(1, 11)]
    assert all(o.success and o.collisions == 0 for o in outs)
    lengths = [o.length for o in outs]
    assert float(np.median(lengths)) < 1.03 * 14.483
    assert min(lengths) > 14.483  # never below the optimum: the robot drives onto the goal


def test_relax_never_lengthens_moves_nodes_and_stays_clear() -> None:
    """The GWO optimisation of the path nodes keeps the ends, checks every segment, never
    lengthens a path and shortens the EA's output (nodes slide round the obstacles)."""
    s = scenario("mfb-static")
    pl = planned("mfb-static", "RFO-GWO-EA", 2)
    for raw in pl.raw_paths[:3]:
        (ea,) = pl._ea([raw])
        split = pl._split(ea, 0.25)
        (out,) = pl._relax([split])
        assert len(out) == len(split)
        assert np.array_equal(out[[0, -1]], split[[0, -1]])
        assert path_length(out) < path_length(split) - 1e-3
        assert_clear(pl, out, s)


def test_node_optimisation_is_what_gets_close_to_the_optimum() -> None:
    """``node_opt = "off"`` (EA and multiphase split only) against the default, same seeds."""
    with_gwo, without = [], []
    for seed in (1, 2, 3):
        with_gwo.append(path_length(planned("mfb-static", "RFO-GWO-EA", seed).path))
        off = planned("mfb-static", "RFO-GWO-EA", seed, {"node_opt": "off"})
        assert_clear(off, off.path, scenario("mfb-static"))
        without.append(path_length(off.path))
    assert np.mean(with_gwo) < np.mean(without) - 0.02  # measured 14.698 against 14.742 m


def test_final_path_keeps_only_needed_nodes() -> None:
    """No repeated node, and no interior node whose neighbours see each other (it would be
    erased)."""
    for seed in (1, 2, 3):
        pl = planned("mfb-static", "RFO-GWO-EA", seed)
        path = pl.path
        assert np.all(np.hypot(*np.diff(path, axis=0).T) > 0)
        assert not np.any(pl._segments_ok(path[:-2], path[2:]))


def test_more_arrivals_return_the_shortest_fox_path() -> None:
    """``arrivals`` > 1 without the EA: the shortest of the foxes' paths, the first one being the
    path ``arrivals`` = 1 returns."""
    one = planned("mfb-static", "RFO-GWO", 4)
    three = planned("mfb-static", "RFO-GWO", 4, {"arrivals": 3})
    assert np.array_equal(three.raw_paths[0], one.path)
    assert 1 < len(three.raw_paths) <= 3
    assert path_length(three.path) == min(path_length(q) for q in three.raw_paths)
    assert three.cost >= one.cost


@pytest.mark.parametrize("planner", PLANNERS)
def test_moving_goal_plans_again_when_the_path_is_used_up(planner: str) -> None:
    """icoot-map3: the goal walks at random; the path to where it was is followed, then the
    planner plans again to where it is."""
    out = Episode(scenario("icoot-map3"), planner, seed=1, run=0).run()
    assert out.success, out.reason
    assert out.collisions == 0


@pytest.mark.parametrize("seed", [1, 2, 10])
def test_ea_avoids_moving_obstacles_on_mfb_dynamic(seed: int) -> None:
    """Watching the sensors while following the path: no collision with the moving circles."""
    out = Episode(scenario("mfb-dynamic"), "RFO-GWO-EA", seed=seed, run=0).run()
    assert out.success, out.reason
    assert out.collisions == 0
