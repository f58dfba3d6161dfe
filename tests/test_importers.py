"""Map importers: ROS map_server / nav2 YAML + image, MovingAI .map. Every map is written here."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from PIL import Image

from swarmpath.world import Obstacle, RobotSpec
from swarmpath.world.importers import (
    MapImportError,
    blocked_rectangles,
    load_movingai_map,
    load_ros_map,
    movingai_cell_center,
    parse_movingai_map,
    ros_occupancy,
)
from swarmpath.world.raster import GridSpec, rasterize
from swarmpath.world.scenario import obstacle_set
from swarmpath.world.scenario_io import ScenarioError

# ------------------------------------------------------------------------------- rectangles


def _cover(rects: list[tuple[int, int, int, int]], shape: tuple[int, int]) -> np.ndarray:
    count = np.zeros(shape, dtype=int)
    for r0, c0, r1, c1 in rects:
        assert r0 < r1 and c0 < c1
        count[r0:r1, c0:c1] += 1
    return count


@settings(max_examples=60, deadline=None)
@given(arrays(np.bool_, st.tuples(st.integers(1, 12), st.integers(1, 12))))
def test_rectangles_cover_blocked_cells_exactly_once(mask: np.ndarray) -> None:
    rects = blocked_rectangles(mask)
    count = _cover(rects, mask.shape)
    np.testing.assert_array_equal(count, mask.astype(int))


def test_rectangles_merge_runs_vertically() -> None:
    m = np.zeros((6, 7), dtype=bool)
    m[1:5, 2:6] = True  # one solid block
    m[0, :] = True  # a wall along the bottom
    m[5, 0] = True
    rects = blocked_rectangles(m)
    assert sorted(rects) == [(0, 0, 1, 7), (1, 2, 5, 6), (5, 0, 6, 1)]
    assert blocked_rectangles(np.zeros((3, 3), dtype=bool)) == []
    assert blocked_rectangles(np.ones((4, 5), dtype=bool)) == [(0, 0, 4, 5)]


# --------------------------------------------------------------------------------- ROS maps
def _write_ros(
    tmp: Path, img: np.ndarray, name: str = "m", ext: str = "pgm", **yaml_fields: object
) -> Path:
    Image.fromarray(img).save(tmp / f"{name}.{ext}")
    fields = {"image": f"{name}.{ext}", "resolution": 0.5, "origin": [-1.0, 2.0, 0.0],
              "negate": 0, "occupied_thresh": 0.65, "free_thresh": 0.196}
    fields.update(yaml_fields)
    text = "".join(f"{k}: {v}\n" for k, v in fields.items() if v is not None)
    y = tmp / f"{name}.yaml"
    y.write_text(text)
    return y


def _map_saver_image() -> np.ndarray:
    """6 x 8 image as map_saver writes it: 254 free, 0 occupied, 205 unknown; row 0 = top.

    205 reads as unknown with ROS 1's free_thresh 0.196 (occ = 0.19608 is not below it); with
    nav2's 0.25 it would read as free.
    """
    img = np.full((6, 8), 254, dtype=np.uint8)
    img[0, :] = 0  # top wall (highest y)
    img[2:4, 2:5] = 0  # a block
    img[5, 7] = 205  # unknown, bottom-right
    return img


def test_ros_pgm_trinary(tmp_path: Path) -> None:
    y = _write_ros(tmp_path, _map_saver_image())
    assert (tmp_path / "m.pgm").read_bytes()[:2] == b"P5"
    m = load_ros_map(y)
    g = m.grid
    assert g.shape == (6, 8) and g.resolution == 0.5 and g.origin == (0.0, 0.0)
    # Image row 0 is the top of the map: it becomes grid row 5 (highest y).
    assert (g.data[5] == 100).all()
    assert (g.data[2:4, 2:5] == 100).all()
    assert g.data[0, 7] == -1
    assert (g.data[0, :7] == 0).all()
    s = m.scenario
    assert s.name == "m" and s.size == (4.0, 3.0)
    assert m.offset == (-1.0, 2.0) and m.to_map_frame((0, 0)) == (-1.0, 2.0)
    assert m.to_scenario_frame((-1.0, 2.0)) == (0.0, 0.0)
    assert s.robot == RobotSpec.preset("turtlebot3-burger")
    # Obstacles: top wall, the block, the unknown cell (unknown counts as blocked by default).
    assert {frozenset(o.points or ()) for o in s.obstacles} == {
        frozenset(Obstacle.rectangle(0.0, 2.5, 4.0, 3.0).points or ()),
        frozenset(Obstacle.rectangle(1.0, 1.0, 2.5, 2.0).points or ()),
        frozenset(Obstacle.rectangle(3.5, 0.0, 4.0, 0.5).points or ()),
    }
    # Defaults: the cell nearest the lower-left corner among those keeping radius + margin
    # (0.155 m, half a cell diagonal included: 0.51 m from blocked cell centres), then the one
    # farthest from it in the same region.
    assert s.start == (0.25, 0.25)
    assert s.goal == (3.75, 1.75)
    assert s.problems() == []
    # Rasterizing the rectangles reproduces the blocked cells.
    spec = GridSpec((0, 0), 0.5, g.shape)
    np.testing.assert_array_equal(rasterize(obstacle_set(s.obstacles), spec), m.blocked)
    assert m.meta["mode"] == "trinary" and m.meta["origin"] == [-1.0, 2.0, 0.0]


def test_ros_unknown_as_free_and_explicit_endpoints(tmp_path: Path) -> None:
    y = _write_ros(tmp_path, _map_saver_image())
    m = load_ros_map(y, unknown_as_occupied=False, start=(0.25, 0.75), goal=(3.75, 0.25),
                     name="lab", robot=RobotSpec.preset("omni", radius=0.2), sensors="mfb-12")
    assert len(m.scenario.obstacles) == 2
    assert m.scenario.goal == (3.75, 0.25) and m.scenario.name == "lab"
    assert m.scenario.sensors == "mfb-12" and m.scenario.robot.radius == 0.2
    with pytest.raises(ScenarioError) as info:
        load_ros_map(y, start=(1.5, 1.5))  # inside the block
    assert [p for p, _ in info.value.problems] == ["start"]


def test_ros_negate_and_thresholds(tmp_path: Path) -> None:
    img = np.array([[0, 60, 89, 90, 166, 167, 255]], dtype=np.uint8)
    # occ = 1 - v/255: 1.0, .765, .651, .647, .349, .345, 0.0
    y = _write_ros(tmp_path, img, occupied_thresh=0.65, free_thresh=0.346)
    data = load_ros_map(y, start=(3.25, 0.25), goal=(3.25, 0.25)).grid.data[0].tolist()
    assert data == [100, 100, 100, -1, -1, 0, 0]
    yn = _write_ros(tmp_path, img, name="n", negate=1, free_thresh=0.25)
    # negate: occ = v/255 -> dark is free.
    data_n = load_ros_map(yn, start=(0.25, 0.25), goal=(0.25, 0.25)).grid.data[0].tolist()
    assert data_n == [0, 0, -1, -1, 100, 100, 100]
    # Exactly at the threshold is not beyond it (strict comparisons, as map_server).
    occ = ros_occupancy(np.array([0.25, 0.75, 0.2, 0.8]), np.ones(4, dtype=bool), "trinary",
                        False, 0.75, 0.25)
    assert occ.tolist() == [-1, -1, 100, 0]


def test_ros_scale_and_raw_modes(tmp_path: Path) -> None:
    gray = np.array([[0, 128, 200, 255]], dtype=np.uint8)
    alpha = np.array([[255, 255, 255, 0]], dtype=np.uint8)
    la = np.stack([gray, alpha], axis=-1)
    y = _write_ros(tmp_path, la, name="s", ext="png", mode="scale", free_thresh=0.25)
    d = load_ros_map(y, start=(1.25, 0.25), goal=(1.25, 0.25),
                     robot=RobotSpec.preset("omni", radius=0.1)).grid.data[0].tolist()
    # occ: 1.0 -> 100; 0.498 -> rint((0.498 - .25) / .4 * 100) = 62; 0.216 -> 0; transparent -> -1.
    assert d == [100, 62, 0, -1]
    raw = np.array([[0, 50, 100, 101, 255]], dtype=np.uint8)
    yr = _write_ros(tmp_path, raw, name="r", mode="raw", negate=1)  # raw ignores negate
    m = load_ros_map(yr, start=(0.25, 0.25), goal=(0.25, 0.25), unknown_as_occupied=False)
    assert m.grid.data[0].tolist() == [0, 50, 100, -1, -1]
    assert len(m.scenario.obstacles) == 1  # only the 100 cell when unknowns count as free
    # Trinary averages an alpha channel in: a transparent white pixel is half occupied.
    rgba = np.zeros((1, 2, 4), dtype=np.uint8)
    rgba[0, 0] = (255, 255, 255, 255)
    rgba[0, 1] = (255, 255, 255, 0)
    yt = _write_ros(tmp_path, rgba, name="t", ext="png", free_thresh=0.25)
    dt = load_ros_map(yt, start=(0.25, 0.25), goal=(0.25, 0.25)).grid.data[0].tolist()
    assert dt == [0, -1]


def test_ros_errors(tmp_path: Path) -> None:
    img = _map_saver_image()
    with pytest.raises(MapImportError, match="resolution: required"):
        load_ros_map(_write_ros(tmp_path, img, resolution=None))
    with pytest.raises(MapImportError, match="resolution: must be > 0"):
        load_ros_map(_write_ros(tmp_path, img, resolution=0))
    with pytest.raises(MapImportError, match="origin"):
        load_ros_map(_write_ros(tmp_path, img, origin=[1, 2]))
    with pytest.raises(MapImportError, match="mode"):
        load_ros_map(_write_ros(tmp_path, img, mode="fancy"))
    with pytest.raises(MapImportError, match="thresh"):
        load_ros_map(_write_ros(tmp_path, img, free_thresh=0.9))
    with pytest.raises(MapImportError, match="image"):
        load_ros_map(_write_ros(tmp_path, img, image=None))
    y = _write_ros(tmp_path, img, name="gone")
    (tmp_path / "gone.pgm").unlink()
    with pytest.raises(MapImportError, match="not found"):
        load_ros_map(y)
    # Defaults: negate 0, thresholds 0.65 / 0.25 (nav2 map_saver); 205 then reads as free.
    m = load_ros_map(_write_ros(tmp_path, img, name="d", negate=None, occupied_thresh=None,
                                free_thresh=None))
    assert m.meta["occupied_thresh"] == 0.65 and m.meta["free_thresh"] == 0.25
    assert m.meta["negate"] is False and m.grid.data[0, 7] == 0


def test_default_goal_is_reachable(tmp_path: Path) -> None:
    img = np.full((10, 10), 254, dtype=np.uint8)
    img[0:4, 5] = 0  # wall off the top-right 4 x 4 corner
    img[3, 5:] = 0
    m = load_ros_map(_write_ros(tmp_path, img, resolution=1.0, origin=[0, 0, 0]))
    s = m.scenario
    assert s.start == (0.5, 0.5)
    # The enclosed top-right corner is free but unreachable: the goal is not there.
    assert not (s.goal[0] > 5 and s.goal[1] > 6)
    assert s.goal == (9.5, 5.5)


# --------------------------------------------------------------------------------- MovingAI
MOVINGAI = """type octile
height 4
width 6
map
@@@@@@
.T..GO
..@@.W
S.....
"""


def test_movingai_map(tmp_path: Path) -> None:
    p = tmp_path / "tiny.map"
    p.write_text(MOVINGAI)
    blocked = parse_movingai_map(MOVINGAI)
    assert blocked.tolist() == [
        [True] * 6,
        [False, True, False, False, False, True],
        [False, False, True, True, False, True],
        [False] * 6,
    ]
    m = load_movingai_map(p, resolution=0.5)
    g = m.grid
    assert g.shape == (4, 6) and g.resolution == 0.5
    np.testing.assert_array_equal(m.blocked, blocked[::-1])  # text row 0 is the top
    s = m.scenario
    assert s.size == (3.0, 2.0) and s.name == "tiny"
    # 0.5 m cells: only cells not 4-adjacent to a blocked one keep 0.155 m + half a diagonal;
    # the lower-left region is (0, 0), (1, 0), (0, 1) and its farthest cell comes first by row
    assert s.start == (0.25, 0.25)
    assert s.goal == (0.75, 0.25)
    # top wall, 'T' below it and 'O' over 'W': one polygon; the '@@' block: another
    assert len(s.obstacles) == 2
    assert {len(o.points or ()) for o in s.obstacles} == {10, 4}
    spec = GridSpec((0, 0), 0.5, g.shape)
    np.testing.assert_array_equal(rasterize(obstacle_set(s.obstacles), spec), m.blocked)
    assert movingai_cell_center(0, 3, 4, 0.5) == (0.25, 0.25)
    assert movingai_cell_center(4, 1, 4) == (4.5, 2.5)
    m2 = load_movingai_map(
        p, start=movingai_cell_center(0, 3, 4), goal=movingai_cell_center(4, 1, 4)
    )
    assert m2.scenario.goal == (4.5, 2.5) and m2.scenario.problems() == []


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("type octile\nheight 2\nwidth 2\nmap\n..\n.x\n", "line 6, column 2"),
        ("type octile\nheight 3\nwidth 2\nmap\n..\n..\n",
         "the header says height 3 but the grid has 2 lines"),
        ("type octile\nheight 2\nwidth 3\nmap\n...\n..\n",
         "line 6: 2 characters, but the header says width 3"),
        ("type octile\nheight 2\nwidth 2\nmap\n....\n....\n", "line 5: 4 characters"),
        ("type octile\nheight 2\nwidth 2\nmap\n..\n..\n..\n",
         "line 7: more grid lines than the header's height 2"),
        ("type octile\nwidth 2\nmap\n..\n..\n", "'height' line required"),
        ("type octile\nheight 2\nwidth 2\n..\n..\n", "missing the 'map' line"),
        ("type octile\nheight two\nwidth 2\nmap\n..\n..\n", "integers"),
    ],
)
def test_movingai_errors(text: str, message: str) -> None:
    with pytest.raises(MapImportError, match=message):
        parse_movingai_map(text)


def test_movingai_all_blocked(tmp_path: Path) -> None:
    p = tmp_path / "solid.map"
    p.write_text("type octile\nheight 2\nwidth 2\nmap\n@@\n@@\n")
    with pytest.raises(MapImportError, match="no cell keeps a clearance"):
        load_movingai_map(p)
