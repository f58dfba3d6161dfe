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

from swarmpath.world.grid_import import (
    ENDPOINT_MARGIN,
    MAX_CELLS,
    MAX_OBSTACLES,
    ImportedMap,
    MapImportError,
    MapLimitError,
    blocked_rectangles,
    check_limits,
    default_endpoints,
)
from swarmpath.world.movingai import load_movingai_map, movingai_cell_center, parse_movingai_map
from swarmpath.world.ros_map import load_ros_map, ros_occupancy

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

