"""Grid maps as few exact polygons, default endpoints of imported maps, import limits."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from PIL import Image

from swarmpath.world.geometry import points_in_polygon
from swarmpath.world.grid_polygons import blocked_components, grid_polygons
from swarmpath.world.importers import (
    ENDPOINT_MARGIN,
    MapLimitError,
    check_limits,
    load_movingai_map,
    load_ros_map,
)
from swarmpath.world.scenario import obstacle_set, polygon_problems

DATA = Path(__file__).parent / "data"


def _coverage(polys: list[np.ndarray], shape: tuple[int, int]) -> np.ndarray:
    """How many polygons contain each cell centre (cell units)."""
    count = np.zeros(shape, dtype=int)
    for poly in polys:
        lo, hi = poly.min(axis=0), poly.max(axis=0)
        ys, xs = np.mgrid[lo[1] : hi[1], lo[0] : hi[0]]
        centres = np.stack([xs + 0.5, ys + 0.5], axis=-1).reshape(-1, 2)
        inside = points_in_polygon(centres, poly.astype(float)).reshape(xs.shape)
        count[lo[1] : hi[1], lo[0] : hi[0]] += inside
    return count


@settings(max_examples=60, deadline=None)
@given(
    arrays(np.bool_, st.tuples(st.integers(1, 30), st.integers(1, 30))),
    st.integers(2, 40),
)
def test_polygons_cover_blocked_cells_exactly_once(mask: np.ndarray, tile: int) -> None:
    polys = grid_polygons(mask, tile=tile)
    np.testing.assert_array_equal(_coverage(polys, mask.shape), mask.astype(int))
    for poly in polys:
        assert polygon_problems(poly.astype(float)) == []  # simple: no pinch, no hole
        e = np.roll(poly, -1, axis=0) - poly
        assert np.all((e[:, 0] == 0) != (e[:, 1] == 0))  # orthogonal, no collinear vertex
        area2 = np.sum(poly[:, 0] * np.roll(poly[:, 1], -1) - np.roll(poly[:, 0], -1) * poly[:, 1])
        assert area2 > 0  # counter-clockwise


def test_rooms_and_rings_are_cut_open() -> None:
    m = np.zeros((12, 12), dtype=bool)
    m[1, 1:11] = m[10, 1:11] = m[1:11, 1] = m[1:11, 10] = True  # a ring (one hole)
    m[4:7, 4:7] = True
    m[5, 5] = False  # a block with a one-cell hole inside the ring
    polys = grid_polygons(m)
    np.testing.assert_array_equal(_coverage(polys, m.shape), m.astype(int))
    assert 2 < len(polys) <= 6


def test_tb3_sandbox_cell_by_cell() -> None:
    m = load_ros_map(DATA / "tb3_sandbox.yaml")
    res = m.grid.resolution
    polys = [np.rint(np.asarray(o.points) / res).astype(np.int64) for o in m.scenario.obstacles]
    np.testing.assert_array_equal(_coverage(polys, m.blocked.shape), m.blocked.astype(int))
    assert len(m.scenario.obstacles) < 100  # the old rectangles were 179


def test_default_endpoints_inside_the_building(tmp_path: Path) -> None:
    """A building whose outside reads as free (nav2's unknown grey with free_thresh 0.25): the
    default start and goal are inside, far apart, with clearance >= radius + margin."""
    img = np.full((80, 120), 205, dtype=np.uint8)  # unknown grey all around
    img[20:60, 30:90] = 254  # the floor
    img[20:22, 30:90] = img[58:60, 30:90] = 0  # walls
    img[20:60, 30:32] = img[20:60, 88:90] = 0
    img[35:45, 50:60] = 0  # a shelf
    Image.fromarray(img).save(tmp_path / "depot.pgm")
    (tmp_path / "depot.yaml").write_text(
        "image: depot.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.25\n"
    )
    m = load_ros_map(tmp_path / "depot.yaml")
    s = m.scenario
    res = 0.05
    for x, y in (s.start, s.goal):
        assert 32 * res < x < 88 * res and 22 * res < y < 58 * res, (x, y)  # image rows flip
    clearance = obstacle_set(s.obstacles).point_clearance(np.array([s.start, s.goal]))
    assert np.all(clearance >= s.robot.radius + ENDPOINT_MARGIN - 1e-12)
    assert np.hypot(*np.subtract(s.goal, s.start)) > 2.0  # far apart (the floor is 2.8 x 1.8 m)


def test_cell_limit_names_the_limit(tmp_path: Path) -> None:
    p = tmp_path / "big.map"
    p.write_text("type octile\nheight 300\nwidth 300\nmap\n" + ("." * 300 + "\n") * 300)
    with pytest.raises(MapLimitError, match=r"max_cells=80,000 \(raise it with"):
        load_movingai_map(p, max_cells=80_000)
    assert load_movingai_map(p, max_cells=90_000).grid.shape == (300, 300)


def test_noisy_2000_grid_is_refused_at_once(tmp_path: Path, monkeypatch: pytest.MonkeyPatch
                                            ) -> None:
    """"At once": the components are counted and the map refused before any polygon is built
    (building them is what took 120 s and 6.5 GB); no timing is asserted."""
    from swarmpath.world import grid_import

    rng = np.random.default_rng(7)
    blocked = rng.random((2000, 2000)) < 0.2
    assert blocked_components(blocked) > 5_000
    with pytest.raises(MapLimitError, match=r"max_obstacles=5,000 \(raise it with"):
        check_limits(blocked, "noise.map", 4_194_304, 5_000)
    rows = np.where(blocked, "@", ".")
    p = tmp_path / "noise.map"
    p.write_text("type octile\nheight 2000\nwidth 2000\nmap\n"
                 + "\n".join("".join(r) for r in rows) + "\n")
    built: list[int] = []

    def no_polygons(*args: object, **kwargs: object) -> list[np.ndarray]:
        built.append(1)
        return []

    monkeypatch.setattr(grid_import, "grid_polygons", no_polygons)
    with pytest.raises(MapLimitError, match="max_obstacles"):
        load_movingai_map(p)
    assert built == []
