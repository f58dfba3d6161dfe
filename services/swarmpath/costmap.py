"""nav2's costmap of an imported grid map and the planner benchmark's costs along a path.

nav2's planner benchmark (``navigation2/tools/planner_benchmarking/process_data.py``) reports,
per path, the *average* and the *maximum* cost of the costmap cells its poses fall in. The
costmap is what nav2's global costmap makes of a static map: the static layer (occupied cells
lethal, unknown cells NO_INFORMATION) and the inflation layer
(``nav2_costmap_2d/inflation_layer.hpp``, ``computeCost``), for a cell at Euclidean distance d
(in cells, between cell centres) from the nearest lethal cell:

* d = 0: LETHAL_OBSTACLE (254);
* d * resolution <= inscribed radius (the robot's radius): INSCRIBED_INFLATED_OBSTACLE (253);
* otherwise, up to ceil(inflation_radius / resolution) cells:
  floor(252 * exp(-cost_scaling_factor * (d * resolution - inscribed radius)));
* farther: FREE_SPACE (0).

An unknown cell keeps NO_INFORMATION (255) unless the inflation gives it 253 or more (nav2's
``inflate_unknown: false``). Parameters: nav2_params.yaml's global costmap,
``inflation_radius`` 0.55 m and ``cost_scaling_factor`` 3.0; the inscribed radius is the
scenario robot's radius. Only the static obstacles are in it (the static layer); the grid is the
scenario's :class:`~swarmpath.world.scenario.GridSource` (resolution, unknown cells), and the
blocked cells are recovered exactly from the obstacles, whose polygons cover whole cells.

The path's poses: the executed path resampled every ``resolution`` metres of arc length (a nav2
planner's path has a pose per cell), each looked up in the cell containing it.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

from swarmpath.path_metrics import resample

LETHAL = 254
INSCRIBED = 253
NO_INFORMATION = 255
FREE = 0
#: nav2_params.yaml, global_costmap inflation_layer
INFLATION_RADIUS = 0.55
COST_SCALING_FACTOR = 3.0

__all__ = ["COST_SCALING_FACTOR", "INFLATION_RADIUS", "Costmap", "inflation_costs",
           "path_costs", "scenario_costmap"]


@dataclass(frozen=True, eq=False)
class Costmap:
    """nav2 costs (uint8, rows x cols, row 0 at the bottom) of cells ``resolution`` m wide, the
    lower-left corner at the scenario's (0, 0)."""

    costs: NDArray[np.uint8]
    resolution: float


def inflation_costs(lethal: ArrayLike, unknown: ArrayLike, resolution: float,
                    inscribed_radius: float, inflation_radius: float = INFLATION_RADIUS,
                    cost_scaling_factor: float = COST_SCALING_FACTOR) -> NDArray[np.uint8]:
    """The static and inflation layers' costs of a grid (see the module docstring)."""
    lethal = np.asarray(lethal, dtype=bool)
    unknown = np.asarray(unknown, dtype=bool) & ~lethal
    if lethal.any():
        d = ndimage.distance_transform_edt(~lethal)
    else:
        d = np.full(lethal.shape, np.inf)
    metres = d * resolution
    with np.errstate(over="ignore"):
        decay = np.floor((INSCRIBED - 1) * np.exp(-cost_scaling_factor
                                                   * (metres - inscribed_radius)))
    reach = math.ceil(inflation_radius / resolution)
    cost = np.where(d <= reach, decay, FREE)
    cost = np.where(metres <= inscribed_radius, INSCRIBED, cost)
    cost = np.where(d == 0, LETHAL, cost)
    cost = np.where(unknown & (cost < INSCRIBED), NO_INFORMATION, cost)
    return np.asarray(cost, dtype=np.uint8)


def _cells_inside(shape: tuple[int, int], resolution: float, polygons: Any,
                  circles: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Cells whose centre lies inside a polygon or a circle (the importers' polygons cover
    whole cells, so their centres are never on an edge)."""
    from matplotlib.path import Path

    rows, cols = shape
    mask = np.zeros(shape, dtype=bool)
    for poly in polygons:
        p = np.asarray(poly, dtype=float) / resolution
        c0, r0 = np.maximum(np.floor(p.min(axis=0)).astype(int), 0)
        c1, r1 = np.minimum(np.ceil(p.max(axis=0)).astype(int), (cols, rows))
        if c1 <= c0 or r1 <= r0:
            continue
        yy, xx = np.mgrid[r0:r1, c0:c1]
        centres = np.column_stack([xx.ravel() + 0.5, yy.ravel() + 0.5])
        inside = Path(p).contains_points(centres).reshape(yy.shape)
        mask[r0:r1, c0:c1] |= inside
    if len(circles):
        yy, xx = np.mgrid[0:rows, 0:cols]
        cx, cy = (xx + 0.5) * resolution, (yy + 0.5) * resolution
        for x, y, r in circles:
            mask |= np.hypot(cx - x, cy - y) <= r
    return mask


@functools.lru_cache(maxsize=8)
def scenario_costmap(scenario: Any) -> Costmap:
    """The costmap of a scenario imported from a grid (``scenario.grid`` set): its static
    obstacles lethal, its unknown cells NO_INFORMATION, inflated for its robot."""
    grid = scenario.grid
    if grid is None:
        raise ValueError(f"scenario {scenario.name!r} was not imported from a grid map")
    res = float(grid.resolution)
    shape = (round(scenario.size[1] / res), round(scenario.size[0] / res))
    static = scenario.static_obstacles()
    blocked = _cells_inside(shape, res, static.polygons, static.circles)
    unknown = _cells_inside(shape, res, grid.unknown_polygons(), np.zeros((0, 3)))
    costs = inflation_costs(blocked & ~unknown, unknown, res, scenario.robot.radius)
    return Costmap(costs, res)


def path_costs(costmap: Costmap, path: ArrayLike) -> tuple[float, float]:
    """(mean, max) cost of the cells of the path's poses, one every ``resolution`` metres of
    arc length (nav2's planner benchmark: averagePathCost, maxPathCost)."""
    P = np.asarray(path, dtype=float)
    poses = resample(P, costmap.resolution)[:, :2] if P.shape[1] == 3 else P[:, :2]
    rows, cols = costmap.costs.shape
    c = np.clip(np.floor(poses[:, 0] / costmap.resolution).astype(int), 0, cols - 1)
    r = np.clip(np.floor(poses[:, 1] / costmap.resolution).astype(int), 0, rows - 1)
    values = costmap.costs[r, c].astype(float)
    return float(values.mean()), float(values.max())
