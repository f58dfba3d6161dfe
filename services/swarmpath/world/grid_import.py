"""What both map importers share (:mod:`swarmpath.world.importers`): the limits and their errors,
:class:`ImportedMap`, the blocked-cell rectangles and polygons, the default start and goal, and
the assembly of the scenario from a grid."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from swarmpath.world.grid_polygons import blocked_components, grid_polygons
from swarmpath.world.raster import UNKNOWN, GridSpec, OccupancyGrid
from swarmpath.world.scenario import (
    ROBOT_PRESETS,
    GridSource,
    Obstacle,
    RobotSpec,
    Scenario,
    scenario_problems,
)
from swarmpath.world.scenario_io import ScenarioError

MAX_CELLS = 4_194_304  # 2048 x 2048
MAX_OBSTACLES = 5_000
ENDPOINT_MARGIN = 0.05  # m of clearance above the robot radius for default start and goal
SURE_FREE = 0.19  # ROS occupancy below which a cell may hold a default endpoint (205 grey: 0.196)


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
    frame: str | None = None,
) -> ImportedMap:
    """The scenario of a grid (row 0 at the bottom); with ``frame`` (a ROS map's "map") the
    scenario records that frame, ``offset`` as its origin, the resolution and the unknown
    cells (:class:`~swarmpath.world.scenario.GridSource`)."""
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
    grid_source = None
    if frame is not None:
        # one tile for the whole grid: the fewest polygons (only drawn and rasterized back)
        unknown = tuple(tuple((int(x), int(y)) for x, y in poly)
                        for poly in grid_polygons(data == UNKNOWN, tile=max(data.shape)))
        grid_source = GridSource(frame, offset, res, unknown)
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
        grid=grid_source,
    )
    problems = scenario_problems(scenario)
    if problems:
        raise ScenarioError(problems, source)
    return ImportedMap(scenario, grid, blocked, offset, dict(meta or {}))


