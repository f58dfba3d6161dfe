"""Import maps users already have: ROS map_server / nav2 maps (YAML + PGM/PNG) and MovingAI grids.

Both importers return an :class:`ImportedMap`: the occupancy grid as read (ROS values, row 0 at the
bottom, see :mod:`swarmpath.world.raster`) and a :class:`~swarmpath.world.scenario.Scenario` whose
obstacles are simple orthogonal polygons covering exactly the blocked cells
(:func:`swarmpath.world.grid_polygons.grid_polygons`: 64 x 64-cell tiles, 4-connected parts, holes
cut open).

Frames: the scenario world is ``[0, w] x [0, h]`` with ``w = cols * resolution`` and
``h = rows * resolution``; its (0, 0) is the lower-left corner of the map. For ROS maps that corner
is the YAML ``origin`` (x, y) in the map frame, kept as :attr:`ImportedMap.offset`:
``map_xy = scenario_xy + offset``. ``start``/``goal`` arguments are in the *scenario* frame (use
:meth:`ImportedMap.to_scenario_frame` on map-frame points). The origin's yaw is ignored (recorded
in ``meta``), as most of the ROS navigation stack does.

Default start and goal (:func:`default_endpoints`): candidates are the cells whose centre keeps a
clearance of at least ``robot radius + endpoint_margin`` (0.05 m) from every blocked cell (and from
the map border) and, on ROS maps, that read free even with ROS 1's ``free_thresh`` (occupancy below
0.19: map_saver's unknown grey 205, which nav2's 0.25 reads as free, is never a candidate, so an
endpoint never lands in the unknown area outside a building). Of the 8-connected regions of
candidates the largest is used; the start is its cell nearest the map's lower-left corner, the goal
its cell farthest (straight line) from the start. Unknown cells (and graded 1..99 cells of scale
maps) count as blocked unless ``unknown_as_occupied=False``.

Limits: a grid of more than ``max_cells`` cells, or whose blocked cells form more than
``max_obstacles`` polygons, is refused with a :class:`MapLimitError` naming the limit (both are
keyword arguments; the CLI has ``--max-cells`` / ``--max-obstacles``). The polygon count is bounded
below by the 4-connected components, counted before any polygon is built, so a huge noisy grid is
refused at once.

ROS rules (nav2 map_io): a pixel's shade is the mean of its colour channels / 255 (in trinary mode
an alpha channel is averaged in too); occupancy ``p = 1 - shade``, or ``shade`` when ``negate``.
trinary: ``p > occupied_thresh`` -> 100, ``p < free_thresh`` -> 0, else -1. scale: like trinary
but in-between values map linearly to 0..100 and non-opaque pixels are unknown. raw: the grey value
``round(shade * 255)`` is the occupancy itself when in 0..100, else unknown (negate is ignored).
Image row 0 is the top of the map (highest y). Missing ``negate`` / thresholds default to 0 and
0.65 / 0.25 (what map_saver writes). MovingAI: ``.``, ``G``, ``S`` are passable; ``@``, ``O``,
``T``, ``W`` blocked; any other character is an error; text row 0 is the top of the map.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray
from PIL import Image
from scipy import ndimage

from swarmpath.world.grid_polygons import blocked_components, grid_polygons
from swarmpath.world.raster import FREE, OCCUPIED, UNKNOWN, GridSpec, OccupancyGrid
from swarmpath.world.scenario import (
    MAX_METRES,
    ROBOT_PRESETS,
    Obstacle,
    RobotSpec,
    Scenario,
    scenario_problems,
)
from swarmpath.world.scenario_io import ScenarioError

__all__ = [
    "ENDPOINT_MARGIN",
    "MAX_CELLS",
    "MAX_OBSTACLES",
    "ImportedMap",
    "MapImportError",
    "MapLimitError",
    "blocked_rectangles",
    "check_limits",
    "default_endpoints",
    "load_movingai_map",
    "load_ros_map",
    "movingai_cell_center",
    "parse_movingai_map",
    "ros_occupancy",
]

MAX_CELLS = 4_194_304  # 2048 x 2048
MAX_OBSTACLES = 5_000
ENDPOINT_MARGIN = 0.05  # m of clearance above the robot radius for default start and goal
SURE_FREE = 0.19  # ROS occupancy below which a cell may hold a default endpoint (205 grey: 0.196)
MOVINGAI_PASSABLE = frozenset(".GS")
MOVINGAI_BLOCKED = frozenset("@OTW")
_MOVINGAI_KIND = np.full(256, 2, dtype=np.int8)  # byte -> 0 passable, 1 blocked, 2 unknown
_MOVINGAI_KIND[[ord(ch) for ch in MOVINGAI_PASSABLE]] = 0
_MOVINGAI_KIND[[ord(ch) for ch in MOVINGAI_BLOCKED]] = 1


class MapImportError(ValueError):
    """A map file that cannot be imported; the message names the file and the key or line."""


class MapLimitError(MapImportError):
    """A map over a size limit; the message names the limit and how to raise it."""


@dataclass(frozen=True, eq=False)
class ImportedMap:
    scenario: Scenario
    grid: OccupancyGrid  # values as read, scenario frame (origin (0, 0)), row 0 at the bottom
    blocked: NDArray[np.bool_]  # the cells turned into obstacles
    offset: tuple[float, float] = (0.0, 0.0)  # map-frame position of scenario (0, 0)
    meta: dict[str, Any] = field(default_factory=dict)

    def to_scenario_frame(self, xy: Sequence[float]) -> tuple[float, float]:
        return (float(xy[0]) - self.offset[0], float(xy[1]) - self.offset[1])

    def to_map_frame(self, xy: Sequence[float]) -> tuple[float, float]:
        return (float(xy[0]) + self.offset[0], float(xy[1]) + self.offset[1])


# --------------------------------------------------------------------------------- rectangles
def blocked_rectangles(blocked: NDArray[np.bool_]) -> list[tuple[int, int, int, int]]:
    """Cover the True cells of ``blocked`` (rows, cols) with disjoint rectangles.

    Returns ``(row0, col0, row1, col1)`` with exclusive ends. Runs of True cells along each row are
    merged with the identical run (same columns) of the next row, so a solid block of any size is
    one rectangle.
    """
    b = np.asarray(blocked, dtype=bool)
    rows = b.shape[0]
    out: list[tuple[int, int, int, int]] = []
    active: dict[tuple[int, int], int] = {}  # (col0, col1) -> first row
    pad = np.zeros((rows, 1), dtype=np.int8)
    edges = np.diff(np.hstack([pad, b.astype(np.int8), pad]), axis=1)
    for r in range(rows + 1):
        if r < rows:
            starts = np.flatnonzero(edges[r] == 1)
            ends = np.flatnonzero(edges[r] == -1)
            runs = set(zip(starts.tolist(), ends.tolist(), strict=True))
        else:
            runs = set()
        for key in [k for k in active if k not in runs]:
            out.append((active.pop(key), key[0], r, key[1]))
        for key in runs:
            active.setdefault(key, r)
    out.sort()
    return out


def _polygon_obstacles(
    blocked: NDArray[np.bool_], res: float, progress: Callable[[float], None] | None = None
) -> tuple[Obstacle, ...]:
    return tuple(
        Obstacle.polygon([(float(x) * res, float(y) * res) for x, y in poly])
        for poly in grid_polygons(blocked, progress=progress)
    )


def check_limits(
    blocked: NDArray[np.bool_], source: str, max_cells: int, max_obstacles: int
) -> None:
    """Refuse a grid over the limits before any polygon is built (:class:`MapLimitError`)."""
    cells = int(blocked.size)
    if cells > max_cells:
        raise MapLimitError(
            f"{source}: {blocked.shape[1]} x {blocked.shape[0]} = {cells:,} cells exceed "
            f"max_cells={max_cells:,} (raise it with max_cells= / --max-cells)"
        )
    parts = blocked_components(blocked)
    if parts > max_obstacles:
        raise MapLimitError(
            f"{source}: the blocked cells form at least {parts:,} obstacles (4-connected "
            f"components), more than max_obstacles={max_obstacles:,} (raise it with "
            "max_obstacles= / --max-obstacles)"
        )


def default_endpoints(
    blocked: NDArray[np.bool_],
    res: float,
    radius: float,
    margin: float = ENDPOINT_MARGIN,
    allowed: NDArray[np.bool_] | None = None,
) -> tuple[tuple[float, float], tuple[float, float]]:
    """Default start and goal of a grid map (scenario frame); the rule is in the module docstring.

    The clearance of a cell centre is bounded from below by its distance to the nearest blocked
    cell centre minus half a cell diagonal, so the chosen cells keep at least
    ``radius + margin``. ``allowed`` (default: every cell) restricts the candidates further
    (ROS maps: cells that read free even at ROS 1's free_thresh, see :data:`SURE_FREE`).
    Raises :class:`MapImportError` if no cell qualifies.
    """
    need = radius + margin
    if blocked.any():
        edt = ndimage.distance_transform_edt(~blocked)
        ok = (edt - 0.5 * math.sqrt(2.0)) * res >= need
    else:
        ok = np.ones(blocked.shape, dtype=bool)
    # the world border is no obstacle, but the robot's body stays inside the map
    rows, cols = blocked.shape
    ys = (np.arange(rows) + 0.5) * res
    xs = (np.arange(cols) + 0.5) * res
    ok &= ((ys >= need) & (ys <= rows * res - need))[:, None]
    ok &= ((xs >= need) & (xs <= cols * res - need))[None, :]
    if allowed is not None:
        ok &= allowed
    if not ok.any():
        raise MapImportError(
            f"no cell keeps a clearance of robot radius {radius:g} + margin {margin:g} m; "
            "give start and goal explicitly"
        )
    labels, n = ndimage.label(ok, structure=np.ones((3, 3), dtype=bool))
    sizes = np.bincount(labels.ravel(), minlength=n + 1)
    sizes[0] = 0
    region = int(np.argmax(sizes))
    rr, cc = np.nonzero(labels == region)  # row-major: ties resolve to the lowest row, column
    i = int(np.argmin(np.hypot(rr + 0.5, cc + 0.5)))
    j = int(np.argmax(np.hypot(rr - rr[i], cc - cc[i])))
    start = (float((cc[i] + 0.5) * res), float((rr[i] + 0.5) * res))
    goal = (float((cc[j] + 0.5) * res), float((rr[j] + 0.5) * res))
    return start, goal


def _build(
    name: str,
    data: NDArray[np.int8],
    res: float,
    *,
    start: Sequence[float] | None,
    goal: Sequence[float] | None,
    robot: RobotSpec | None,
    unknown_as_occupied: bool,
    sensors: str | None,
    time_step: float,
    source: str,
    offset: tuple[float, float] = (0.0, 0.0),
    meta: dict[str, Any] | None = None,
    max_obstacles: int = MAX_OBSTACLES,
    endpoint_margin: float = ENDPOINT_MARGIN,
    allowed: NDArray[np.bool_] | None = None,
    progress: Callable[[float], None] | None = None,
) -> ImportedMap:
    spec = GridSpec((0.0, 0.0), res, (data.shape[0], data.shape[1]))
    grid = OccupancyGrid(spec, data)
    blocked = grid.blocked(unknown_as_occupied)
    check_limits(blocked, source, blocked.size, max_obstacles)
    robot = robot or ROBOT_PRESETS["turtlebot3-burger"]
    obstacles = _polygon_obstacles(blocked, res, progress)
    if len(obstacles) > max_obstacles:
        raise MapLimitError(
            f"{source}: the blocked cells make {len(obstacles):,} polygons, more than "
            f"max_obstacles={max_obstacles:,} (raise it with max_obstacles= / --max-obstacles)"
        )
    if start is None or goal is None:
        try:
            s0, g0 = default_endpoints(blocked, res, robot.radius, endpoint_margin, allowed)
        except MapImportError as e:
            raise MapImportError(f"{source}: {e}") from None
        start = s0 if start is None else start
        goal = g0 if goal is None else goal
    scenario = Scenario(
        name=name,
        size=(spec.cols * res, spec.rows * res),
        start=(float(start[0]), float(start[1])),
        goal=(float(goal[0]), float(goal[1])),
        robot=robot,
        obstacles=obstacles,
        sensors=sensors,
        time_step=time_step,
        description=f"imported from {Path(source).name}",
    )
    problems = scenario_problems(scenario)
    if problems:
        raise ScenarioError(problems, source)
    return ImportedMap(scenario, grid, blocked, offset, dict(meta or {}))


# ------------------------------------------------------------------------------------ ROS maps
def _image_shade(
    path: Path, with_alpha: bool, max_cells: int = MAX_CELLS
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Per-pixel shade in [0, 1] (image order, row 0 = top) and an 'is opaque' mask."""
    try:
        im_ctx = Image.open(path)
    except (OSError, Image.DecompressionBombError) as e:
        raise MapImportError(f"{path}: cannot read the image: {e}") from None
    with im_ctx as im:
        w, h = im.size
        if w * h > max_cells:
            raise MapLimitError(
                f"{path}: {w} x {h} = {w * h:,} cells exceed max_cells={max_cells:,} "
                "(raise it with max_cells= / --max-cells)"
            )
        im.load()
        has_alpha = im.mode in ("LA", "RGBA", "PA", "La", "RGBa") or (
            im.mode == "P" and "transparency" in im.info
        )
        if im.mode in ("I", "I;16", "I;16B", "I;16L", "F"):
            a = np.asarray(im, dtype=np.float64)
            top = 65535.0 if a.max() > 255 else 255.0
            return a / top, np.ones(a.shape, dtype=bool)
        rgba = np.asarray((im.convert("L") if im.mode == "1" else im).convert("RGBA"), np.float64)
    alpha = rgba[..., 3] if has_alpha else np.full(rgba.shape[:2], 255.0)
    channels = [rgba[..., 0], rgba[..., 1], rgba[..., 2]]
    if with_alpha and has_alpha:
        channels.append(alpha)
    shade = np.mean(channels, axis=0) / 255.0
    return shade, alpha >= 255.0


def ros_occupancy(
    shade: NDArray[np.float64],
    opaque: NDArray[np.bool_],
    mode: str,
    negate: bool,
    occupied_thresh: float,
    free_thresh: float,
) -> NDArray[np.int8]:
    """ROS occupancy values for an image (image row order kept), following nav2's map_io rules."""
    occ = shade if negate else 1.0 - shade
    if mode == "trinary":
        out = np.where(occ > occupied_thresh, OCCUPIED, np.where(occ < free_thresh, FREE, UNKNOWN))
    elif mode == "scale":
        mid = np.rint((occ - free_thresh) / (occupied_thresh - free_thresh) * 100.0)
        out = np.where(occ > occupied_thresh, OCCUPIED, np.where(occ < free_thresh, FREE, mid))
        out = np.where(opaque, out, UNKNOWN)
    elif mode == "raw":
        v = np.round(shade * 255.0)
        out = np.where((v >= 0) & (v <= 100), v, UNKNOWN)
    else:
        raise ValueError(f"mode must be trinary, scale or raw, got {mode!r}")
    return np.asarray(out).astype(np.int8)


def _number(doc: dict[str, Any], key: str, src: str, default: float | None = None) -> float:
    if key not in doc:
        if default is None:
            raise MapImportError(f"{src}: {key}: required")
        return default
    v = doc[key]
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise MapImportError(f"{src}: {key}: must be a number, got {v!r}")
    return float(v)


def load_ros_map(
    yaml_path: str | os.PathLike[str],
    *,
    start: Sequence[float] | None = None,
    goal: Sequence[float] | None = None,
    robot: RobotSpec | None = None,
    name: str | None = None,
    unknown_as_occupied: bool = True,
    sensors: str | None = None,
    time_step: float = 0.1,
    max_cells: int = MAX_CELLS,
    max_obstacles: int = MAX_OBSTACLES,
    endpoint_margin: float = ENDPOINT_MARGIN,
    progress: Callable[[float], None] | None = None,
) -> ImportedMap:
    """Import a ROS map_server / nav2 map (YAML + PGM/PNG/BMP image).

    ``start``/``goal`` in the scenario frame (metres from the map's lower-left corner); defaults
    as in the module docstring. ``robot`` defaults to the ``turtlebot3-burger`` preset.
    """
    ypath = Path(yaml_path)
    src = str(ypath)
    try:
        doc = yaml.safe_load(ypath.read_text(encoding="utf-8"))
    except yaml.YAMLError as e:
        raise MapImportError(f"{src}: cannot parse YAML: {e}") from None
    if not isinstance(doc, dict):
        raise MapImportError(f"{src}: expected a YAML mapping")
    if not isinstance(doc.get("image"), str) or not doc["image"]:
        raise MapImportError(f"{src}: image: required (path of the map image)")
    image = Path(doc["image"])
    if not image.is_absolute():
        image = ypath.parent / image
    res = _number(doc, "resolution", src)
    if not res > 0:
        raise MapImportError(f"{src}: resolution: must be > 0")
    origin = doc.get("origin")
    if (
        not isinstance(origin, list | tuple)
        or len(origin) != 3
        or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in origin)
    ):
        raise MapImportError(f"{src}: origin: must be [x, y, yaw]")
    occ_t = _number(doc, "occupied_thresh", src, 0.65)
    free_t = _number(doc, "free_thresh", src, 0.25)
    if not (0.0 <= free_t < occ_t <= 1.0):
        raise MapImportError(
            f"{src}: occupied_thresh/free_thresh: need 0 <= free_thresh < occupied_thresh <= 1"
        )
    neg = doc.get("negate", 0)
    if neg not in (0, 1, True, False):
        raise MapImportError(f"{src}: negate: must be 0 or 1")
    mode = str(doc.get("mode", "trinary")).lower()
    if mode not in ("trinary", "scale", "raw"):
        raise MapImportError(f"{src}: mode: must be trinary, scale or raw, got {mode!r}")
    if not image.is_file():
        raise MapImportError(f"{src}: image: file not found: {image}")
    shade, opaque = _image_shade(image, with_alpha=(mode == "trinary"), max_cells=max_cells)
    values = ros_occupancy(shade, opaque, mode, bool(neg), occ_t, free_t)
    data = values[::-1]  # image row 0 is the top of the map; grid row 0 is the bottom
    occ = shade if neg else 1.0 - shade
    sure_free = np.ascontiguousarray(((occ < SURE_FREE) & opaque)[::-1])
    if mode == "raw":
        sure_free = data == FREE
    return _build(
        name or ypath.stem,
        np.ascontiguousarray(data),
        res,
        start=start,
        goal=goal,
        robot=robot,
        unknown_as_occupied=unknown_as_occupied,
        sensors=sensors,
        time_step=time_step,
        source=src,
        offset=(float(origin[0]), float(origin[1])),
        meta={
            "format": "ros",
            "image": str(image),
            "origin": [float(v) for v in origin],
            "mode": mode,
            "negate": bool(neg),
            "occupied_thresh": occ_t,
            "free_thresh": free_t,
        },
        max_obstacles=max_obstacles,
        endpoint_margin=endpoint_margin,
        allowed=sure_free,
        progress=progress,
    )


# ------------------------------------------------------------------------------------ MovingAI
def parse_movingai_map(
    text: str, source: str = "<map>", max_cells: int = MAX_CELLS
) -> NDArray[np.bool_]:
    """Blocked mask of a MovingAI ``.map`` in *text* order (row 0 = top line of the grid)."""
    lines = text.splitlines()
    header: dict[str, str] = {}
    i = 0
    while i < len(lines):
        line = lines[i].strip()
        i += 1
        if not line:
            continue
        if line.lower() == "map":
            break
        key, _, value = line.partition(" ")
        header[key.lower()] = value.strip()
    else:
        raise MapImportError(f"{source}: missing the 'map' line before the grid")
    for key in ("type", "height", "width"):
        if key not in header:
            raise MapImportError(f"{source}: header: '{key}' line required")
    try:
        height, width = int(header["height"]), int(header["width"])
    except ValueError:
        raise MapImportError(f"{source}: header: height and width must be integers") from None
    if height < 1 or width < 1:
        raise MapImportError(f"{source}: header: height and width must be >= 1")
    if height * width > max_cells:
        raise MapLimitError(
            f"{source}: {width} x {height} = {height * width:,} cells exceed "
            f"max_cells={max_cells:,} (raise it with max_cells= / --max-cells)"
        )
    grid = [ln.rstrip("\r\n") for ln in lines[i : i + height]]
    if len(grid) < height:
        raise MapImportError(f"{source}: expected {height} grid lines, found {len(grid)}")
    for r, row in enumerate(grid):
        if len(row) < width:
            raise MapImportError(
                f"{source}: line {i + r + 1}: expected {width} characters, got {len(row)}"
            )
    raw = "".join(row[:width] for row in grid).encode("utf-8", errors="replace")
    codes = np.frombuffer(raw, dtype=np.uint8)
    if len(codes) != height * width:  # a multi-byte character somewhere: find it
        for r, row in enumerate(grid):
            for c, ch in enumerate(row[:width]):
                if ch not in MOVINGAI_BLOCKED and ch not in MOVINGAI_PASSABLE:
                    raise MapImportError(
                        f"{source}: line {i + r + 1}, column {c + 1}: unknown terrain {ch!r}"
                    )
    kind = _MOVINGAI_KIND[codes].reshape(height, width)
    bad = np.flatnonzero(kind.ravel() == 2)
    if len(bad):
        r, c = divmod(int(bad[0]), width)
        raise MapImportError(
            f"{source}: line {i + r + 1}, column {c + 1}: unknown terrain {grid[r][c]!r}"
        )
    return np.asarray(kind == 1)


def movingai_cell_center(
    x: int, y: int, height: int, resolution: float = 1.0
) -> tuple[float, float]:
    """Scenario-frame centre of MovingAI cell (x, y): x = column, y = row from the top (.scen)."""
    return ((x + 0.5) * resolution, (height - y - 0.5) * resolution)


def load_movingai_map(
    path: str | os.PathLike[str],
    *,
    resolution: float = 1.0,
    start: Sequence[float] | None = None,
    goal: Sequence[float] | None = None,
    robot: RobotSpec | None = None,
    name: str | None = None,
    sensors: str | None = None,
    time_step: float = 0.1,
    max_cells: int = MAX_CELLS,
    max_obstacles: int = MAX_OBSTACLES,
    endpoint_margin: float = ENDPOINT_MARGIN,
    progress: Callable[[float], None] | None = None,
) -> ImportedMap:
    """Import a MovingAI ``.map`` grid; each cell is ``resolution`` metres wide.

    ``start``/``goal`` in the scenario frame (use :func:`movingai_cell_center` for .scen cells).
    ``robot`` defaults to ``turtlebot3-burger``.
    """
    p = Path(path)
    if not (resolution > 0):
        raise MapImportError(f"{p}: resolution must be > 0")
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise MapImportError(f"{p}: not a text file (UTF-8)") from None
    blocked_text = parse_movingai_map(text, str(p), max_cells)
    rows, cols = blocked_text.shape
    if max(rows, cols) * resolution > MAX_METRES:
        raise MapImportError(
            f"{p}: {cols} x {rows} cells of resolution={resolution:g} m make a map "
            f"{cols * resolution:g} x {rows * resolution:g} m, more than {MAX_METRES:g} m across"
        )
    data = np.where(blocked_text[::-1], OCCUPIED, FREE).astype(np.int8)
    return _build(
        name or p.stem,
        data,
        float(resolution),
        start=start,
        goal=goal,
        robot=robot,
        unknown_as_occupied=True,
        sensors=sensors,
        time_step=time_step,
        source=str(p),
        meta={"format": "movingai", "height": data.shape[0], "width": data.shape[1]},
        max_obstacles=max_obstacles,
        endpoint_margin=endpoint_margin,
        progress=progress,
    )
