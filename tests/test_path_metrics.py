"""The field's path metrics (swarmpath.path_metrics) against values worked out by hand."""

import math

import numpy as np
import pytest

from swarmpath import path_metrics as pm
from swarmpath.planners import Episode
from swarmpath.world import get_map
from swarmpath.world.geometry import ObstacleSet


def timed(xy, dt=0.1):
    xy = np.asarray(xy, dtype=float)
    return np.column_stack([xy, dt * np.arange(len(xy))])


def straight(n=101, step=0.05):
    return timed(np.column_stack([step * np.arange(n), np.zeros(n)]))


def test_a_straight_path_has_no_curvature_cusps_or_roughness():
    P = straight()
    assert pm.curvature(P) == (0.0, 0.0)
    assert pm.cusps(P) == 0
    assert pm.motion_smoothness(P) == (0.0, 0.0, 0.0)


def test_curvature_on_a_circle_is_one_over_its_radius():
    # rows on a circle of radius 2 exactly CURVATURE_SPACING apart (chords): every triple lies
    # on the circle, so every Menger curvature is 1/2
    radius = 2.0
    dphi = 2.0 * math.asin(pm.CURVATURE_SPACING / (2.0 * radius))
    phi = dphi * np.arange(30)
    P = timed(np.column_stack([radius * np.cos(phi), radius * np.sin(phi)]))
    k = pm.curvature(P)
    assert k.max == pytest.approx(0.5, abs=1e-9)
    assert k.mean == pytest.approx(0.5, abs=1e-9)


def test_a_reversal_is_the_tightest_turn_the_spacing_shows():
    there = np.column_stack([np.linspace(0, 1.2, 5), np.zeros(5)])
    back = there[::-1][1:]
    k = pm.curvature(timed(np.vstack([there, back])))
    assert k.max == pytest.approx(2.0 / pm.CURVATURE_SPACING)


def test_cusps_count_sharp_vertices_and_a_turn_in_place_is_one():
    corner = [(0, 0), (0.5, 0), (1, 0), (1, 0), (1, 0), (1, 0.5), (1, 1)]  # stop, turn 90 deg
    assert pm.cusps(timed(corner)) == 1
    gentle = [(0, 0), (1, 0), (2, 0.5)]  # 26.6 degrees
    assert pm.cusps(timed(gentle)) == 0
    back = [(0, 0), (1, 0), (0.5, 0)]  # a reversal
    assert pm.cusps(timed(back)) == 1


def test_danger_share_counts_runs_of_consecutive_rows_like_mrpb():
    gaps = [1.0, 0.05, 0.05, 1.0, 0.05, 0.05, 0.05, 1.0, 0.05]  # times 0..8
    # runs: rows 1-2 (1 s) and rows 4-6 (2 s); the single row 8 is a run of no length
    assert pm.danger_share(gaps, np.arange(9.0)) == pytest.approx(3.0 / 8.0)
    assert pm.danger_share([0.0], [0.0]) == 0.0


def test_velocity_smoothness_and_jerk_of_a_constant_acceleration():
    t = 0.1 * np.arange(50)
    P = np.column_stack([0.5 * 1.0 * t**2, np.zeros_like(t), t])  # a = 1 m/s^2
    s = pm.motion_smoothness(P)
    assert s.velocity == pytest.approx(1.0, rel=1e-9)
    assert s.jerk == pytest.approx(0.0, abs=1e-9)
    assert s.angular == pytest.approx(0.0, abs=1e-12)


def test_angular_smoothness_is_zero_on_a_circle_and_counts_a_change_of_turn_rate():
    v, radius, dt = 0.5, 2.0, 0.1
    omega = v / radius
    t = dt * np.arange(40)
    circle = np.column_stack([radius * np.sin(omega * t), radius * (1 - np.cos(omega * t)), t])
    assert pm.motion_smoothness(circle).angular == pytest.approx(0.0, abs=1e-9)
    # then straight on along the last heading: the turn rate drops from omega to 0 once
    heading = math.atan2(*(circle[-1, 1::-1] - circle[-2, 1::-1]))
    more = circle[-1, :2] + v * dt * np.arange(1, 21)[:, None] * np.array(
        [math.cos(heading), math.sin(heading)])
    P = np.vstack([circle, np.column_stack([more, t[-1] + dt * np.arange(1, 21)])])
    steps = len(P) - 1
    turn_rates = steps - 1  # one per pair of consecutive steps
    changes = turn_rates - 1
    # the chord turn rate on the circle is omega; one change of about omega over dt
    assert pm.motion_smoothness(P).angular == pytest.approx(omega / dt / changes, rel=0.05)


def test_clearance_along_the_path_is_the_body_gap_at_each_sample_and_its_time():
    wall = ObstacleSet(polygons=(np.array([[-5, -3], [15, -3], [15, -1],
                                                       [-5, -1]], dtype=float),))
    P = straight(n=201)
    gaps = pm.clearance_profile(P, wall, 0.25)
    assert np.allclose(gaps, 0.75)
    assert pm.resample(P, pm.CLEARANCE_SPACING).shape[0] == len(gaps) == 201

    def beside(t: float) -> ObstacleSet:  # a disk keeping pace 1 m to the robot's left
        return ObstacleSet(circles=np.array([[0.5 * t, 1.0, 0.2]]))

    assert np.allclose(pm.clearance_profile(P, beside, 0.1), 1.0 - 0.2 - 0.1)
    assert pm.danger_share(pm.row_gaps(P, beside, 0.75), P[:, 2]) == 1.0  # gap 0.05 < 0.1
    assert pm.danger_share(pm.row_gaps(P, beside, 0.65), P[:, 2]) == 0.0  # gap 0.15


def test_episodes_report_the_metrics_of_their_executed_path():
    out = Episode(get_map("mfb-static"), "OMPL-RRTstar", seed=1, params={"iterations": 2000}).run()
    path = np.asarray(out.path)
    q = pm.path_quality(path, get_map("mfb-static").static_obstacles(), 0.5)
    assert out.success
    assert (out.clearance_mean, out.curvature_max, out.cusps, out.danger_share,
            out.velocity_smoothness, out.jerk) == (q.clearance_mean, q.curvature_max, q.cusps,
                                                   q.danger_share, q.velocity_smoothness, q.jerk)
    assert out.clearance_mean >= out.min_clearance > 0.0
    assert 0.0 <= out.danger_share <= 1.0
    assert out.cpu_seconds > 0.0


def test_nav2_inflation_costs_by_hand():
    from swarmpath.costmap import inflation_costs

    lethal = np.zeros((30, 30), dtype=bool)
    lethal[15, 5] = True
    unknown = np.zeros_like(lethal)
    unknown[15, 6] = unknown[15, 10] = True
    c = inflation_costs(lethal, unknown, 0.05, 0.105)
    assert c[15, 5] == 254
    assert c[15, 7] == 253  # 0.10 m <= inscribed 0.105 m
    assert c[15, 8] == math.floor(252 * math.exp(-3.0 * (0.15 - 0.105)))  # 220
    assert c[15, 16] == math.floor(252 * math.exp(-3.0 * (0.55 - 0.105)))  # 11 cells: 66
    assert c[15, 17] == 0  # beyond ceil(0.55 / 0.05) = 11 cells
    assert c[15, 6] == 253  # unknown, but inscribed: nav2 keeps the inflated cost
    assert c[15, 10] == 255  # unknown farther out: NO_INFORMATION
    assert c[20, 5] == math.floor(252 * math.exp(-3.0 * (0.25 - 0.105)))  # Euclidean, in y


def test_nav2_maps_report_costmap_costs_and_their_frame():
    from pathlib import Path

    from swarmpath.costmap import path_costs, scenario_costmap
    from swarmpath.world.importers import load_ros_map

    imported = load_ros_map(Path(__file__).parent / "data" / "tb3_sandbox.yaml")
    scenario = imported.scenario
    costmap = scenario_costmap(scenario)
    blocked = imported.blocked
    unknown = imported.grid.data == -1
    assert costmap.costs.shape == blocked.shape
    assert np.array_equal(costmap.costs == 254, blocked & ~unknown)  # exactly the occupied cells
    assert set(np.unique(costmap.costs[unknown]).tolist()) <= {253, 255}
    assert not (costmap.costs[~unknown] == 255).any()
    out = Episode(scenario, "OMPL-BITstar", seed=1, params={"iterations": 2000}).run()
    assert out.success
    assert (out.costmap_cost_mean, out.costmap_cost_max) == path_costs(costmap, out.path)
    assert 0.0 <= out.costmap_cost_mean <= out.costmap_cost_max < 254
    assert out.frame_origin == [-10.0, -10.0]
    preset = Episode(get_map("mfb-static"), "OMPL-BITstar", 1, params={"iterations": 500}).run()
    assert preset.costmap_cost_mean is None and preset.frame_origin is None


def test_the_dashboard_scene_names_a_nav2_maps_frame():
    from pathlib import Path

    from swarmpath.service.web.scene import scene
    from swarmpath.world.importers import load_ros_map

    s = scene(load_ros_map(Path(__file__).parent / "data" / "tb3_sandbox.yaml").scenario)
    assert (s["frame"], s["origin"]) == ("map", [-10.0, -10.0])
