"""Occupancy-grid rasterization and world <-> cell conversion."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmpath.world import Motion, Obstacle, RobotSpec, Scenario, get_map
from swarmpath.world.geometry import ObstacleSet
from swarmpath.world.raster import (
    FREE,
    OCCUPIED,
    UNKNOWN,
    GridSpec,
    OccupancyGrid,
    rasterize,
    rasterize_scenario,
)


def test_grid_spec_covering_and_conversion() -> None:
    g = GridSpec.covering((10, 5), 0.5)
    assert g.shape == (10, 20) and g.extent == (0, 0, 10, 5)
    assert GridSpec.covering((1.0, 1.0), 0.3).shape == (4, 4)  # overhangs
    assert GridSpec.covering((0.9, 0.3), 0.3).shape == (1, 3)  # no spurious extra cell
    # Row 0 is the bottom (lowest y); (row, col) order.
    assert g.world_to_cell([0.1, 0.1]).tolist() == [0, 0]
    assert g.world_to_cell([9.9, 0.1]).tolist() == [0, 19]
    assert g.world_to_cell([0.1, 4.9]).tolist() == [9, 0]
    assert g.cell_to_world([9, 0]).tolist() == [0.25, 4.75]
    # Far edge maps out of range unless clipped.
    assert g.world_to_cell([10, 5]).tolist() == [10, 20]
    assert g.world_to_cell([10, 5], clip=True).tolist() == [9, 19]
    assert g.in_bounds(np.array([[0, 0], [9, 19], [10, 0], [-1, 3]])).tolist() == [
        True, True, False, False,
    ]
    cells = np.stack(np.indices(g.shape), axis=-1)
    np.testing.assert_array_equal(g.world_to_cell(g.cell_to_world(cells)), cells)
    np.testing.assert_allclose(g.centres(), g.cell_to_world(cells))
    shifted = GridSpec((-2.0, 1.0), 0.25, (4, 4))
    assert shifted.world_to_cell([-1.9, 1.6]).tolist() == [2, 0]
    with pytest.raises(ValueError):
        GridSpec((0, 0), 0.0, (1, 1))


def _brute(obs: ObstacleSet, spec: GridSpec, inflation: float) -> np.ndarray:
    return np.asarray(obs.point_clearance(spec.centres()) <= inflation)


def test_rasterize_matches_pointwise_clearance() -> None:
    obs = ObstacleSet(
        np.array([[2.0, 2.0, 0.7], [9.8, 0.2, 0.5]]),
        (
            np.array([[4.0, 4.0], [7.0, 4.5], [6.0, 7.5], [5.5, 5.5], [4.2, 6.8]]),
            np.array([[-1.0, 8.0], [1.0, 8.0], [1.0, 12.0]]),  # partly outside the world
        ),
    )
    spec = GridSpec.covering((10, 10), 0.1)
    for infl in (0.0, 0.105, 0.5, -0.2):
        np.testing.assert_array_equal(rasterize(obs, spec, infl), _brute(obs, spec, infl))
    assert rasterize(ObstacleSet.empty(), spec).sum() == 0


@settings(max_examples=30, deadline=None)
@given(
    cx=st.floats(-1, 6), cy=st.floats(-1, 6), r=st.floats(0.01, 2),
    infl=st.floats(0, 1), res=st.sampled_from([0.1, 0.25, 0.3]),
)
def test_rasterize_circle_property(cx: float, cy: float, r: float, infl: float, res: float) -> None:
    obs = ObstacleSet(np.array([[cx, cy, r]]), ())
    spec = GridSpec.covering((5, 5), res)
    np.testing.assert_array_equal(rasterize(obs, spec, infl), _brute(obs, spec, infl))


def test_touching_counts_as_occupied() -> None:
    # Cell centres at x = 0.25, 0.75, ...; the square's left edge passes through x = 0.75.
    obs = ObstacleSet(np.zeros((0, 3)), (np.array([[0.75, 0.0], [2.0, 0.0], [2.0, 2.0],
                                                    [0.75, 2.0]]),))
    spec = GridSpec.covering((2, 2), 0.5)
    m = rasterize(obs, spec)
    assert m[:, 1].all() and not m[:, 0].any()
    # Inflated by exactly the distance to the next centre column: that column is occupied too.
    assert rasterize(obs, spec, 0.5)[:, 0].all()


def test_rasterize_scenario_inflation_and_static_only() -> None:
    s = Scenario(
        "r", (4, 4), (0.2, 0.2), (3.8, 3.8),
        robot=RobotSpec.preset("omni", radius=0.3),
        obstacles=(
            Obstacle.circle((2, 2), 0.5),
            Obstacle.circle((1, 3), 0.2, Motion(0.5, 0)),
        ),
    )
    plain = rasterize_scenario(s, 0.05)
    infl = rasterize_scenario(s, 0.05, inflate=True)
    custom = rasterize_scenario(s, 0.05, inflate=0.3)
    assert plain.shape == (80, 80) and plain.data.dtype == np.int8
    assert set(np.unique(plain.data).tolist()) == {FREE, OCCUPIED}
    np.testing.assert_array_equal(infl.data, custom.data)
    assert infl.blocked().sum() > plain.blocked().sum()
    area = plain.blocked().sum() * 0.05**2
    assert area == pytest.approx(np.pi * (0.5**2 + 0.2**2), rel=0.05)
    static = rasterize_scenario(s, 0.05, static_only=True)
    assert static.blocked().sum() * 0.05**2 == pytest.approx(np.pi * 0.25, rel=0.05)
    # Constant motion is deterministic: a Scenario can be rasterized at t > 0 directly.
    later = rasterize_scenario(s, 0.05, t=2.0)
    assert later.is_blocked(np.array([2.0, 3.0])) and not later.is_blocked(np.array([1.0, 3.0]))


def test_rasterize_world_state_at_time() -> None:
    s = get_map("icoot-map4")
    with pytest.raises(ValueError, match="WorldState"):
        rasterize_scenario(s, 0.1, t=1.0)
    w = s.instantiate(np.random.default_rng(2))
    w.advance(3.0)
    now = rasterize_scenario(w, 0.1)
    spec = now.spec
    np.testing.assert_array_equal(now.blocked(), _brute(w.obstacles_at(3.0), spec, 0.0))
    start = rasterize_scenario(w, 0.1, t=0.0)
    np.testing.assert_array_equal(start.data, rasterize_scenario(s, 0.1).data)
    assert not np.array_equal(start.data, now.data)
    assert rasterize_scenario(w, 0.1, static_only=True).blocked().sum() == 0


def test_occupancy_grid_values() -> None:
    spec = GridSpec((0, 0), 1.0, (2, 3))
    g = OccupancyGrid(spec, np.array([[0, 100, -1], [50, 0, 0]], dtype=np.int8))
    assert g.blocked().tolist() == [[False, True, True], [True, False, False]]
    assert g.blocked(unknown_as_occupied=False).tolist() == [[False, True, False],
                                                             [False, False, False]]
    pts = np.array([[0.5, 0.5], [1.5, 0.5], [0.5, 1.5], [-0.5, 0.5], [5, 5]])
    assert g.is_blocked(pts).tolist() == [False, True, True, True, True]
    assert g.resolution == 1.0 and g.origin == (0.0, 0.0) and UNKNOWN == -1
    with pytest.raises(ValueError):
        OccupancyGrid(spec, np.zeros((3, 2), dtype=np.int8))
    b = OccupancyGrid.from_bool(spec, [[True, False, False], [False, False, True]])
    assert b.data.tolist() == [[100, 0, 0], [0, 0, 100]]


@pytest.mark.parametrize("seed", range(6))
def test_circles_are_marked_as_every_cell_centre_tested_against_every_circle(seed: int) -> None:
    # thousands of sensed points go in as circles of radius 0 (swarm_aim.free_space_path); the
    # windowed marking must equal the definition cell by cell: centre within inflation + r
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 400))
    radii = rng.choice([0.0, 0.0, 0.3, 1.7], n) * rng.uniform(0, 1, n)
    circles = np.column_stack([rng.uniform(-2, 14, (n, 2)), radii])
    spec = GridSpec.covering((12.0, 9.0), float(rng.choice([0.05, 0.1, 0.37])))
    inflation = float(rng.choice([0.0, 0.14, 0.5, -0.1]))
    centres = spec.cell_to_world(np.indices(spec.shape).reshape(2, -1).T)
    d = np.hypot(centres[:, None, 0] - circles[:, 0], centres[:, None, 1] - circles[:, 1])
    want = ((d - circles[:, 2] <= inflation) & (circles[:, 2] + inflation >= 0)).any(axis=1)
    got = rasterize(ObstacleSet(circles=circles), spec, inflation)
    assert np.array_equal(got.reshape(-1), want)
