"""The world the planners run in: geometry, scenarios and their motion, preset maps, occupancy
grids, the scenario file format and map importers.

Core modules (numpy only) are imported eagerly; the adapters with I/O dependencies
(``scenario_io``: pydantic/yaml, ``importers``: Pillow/scipy) load on first use of their names.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from swarmpath.world.geometry import (
    ObstacleSet,
    collides,
    point_polygon_distance,
    point_segment_distance,
    points_in_polygon,
    segment_polygon_distance,
    segment_segment_distance,
)
from swarmpath.world.presets import get_map, list_maps
from swarmpath.world.raster import GridSpec, OccupancyGrid, rasterize, rasterize_scenario
from swarmpath.world.scenario import (
    ROBOT_PRESETS,
    Motion,
    MotionSpec,
    Obstacle,
    RandomMotion,
    RobotSpec,
    Scenario,
    WorldState,
    polygon_problems,
    scenario_problems,
)

if TYPE_CHECKING:
    from swarmpath.world.importers import (
        ImportedMap,
        MapImportError,
        load_movingai_map,
        load_ros_map,
    )
    from swarmpath.world.scenario_io import (
        ScenarioError,
        load_scenario,
        save_scenario,
        scenario_from_dict,
        scenario_json_schema,
        scenario_to_dict,
    )

_LAZY = {
    "ScenarioError": "swarmpath.world.scenario_io",
    "load_scenario": "swarmpath.world.scenario_io",
    "save_scenario": "swarmpath.world.scenario_io",
    "scenario_from_dict": "swarmpath.world.scenario_io",
    "scenario_json_schema": "swarmpath.world.scenario_io",
    "scenario_to_dict": "swarmpath.world.scenario_io",
    "ImportedMap": "swarmpath.world.importers",
    "MapImportError": "swarmpath.world.importers",
    "load_movingai_map": "swarmpath.world.importers",
    "load_ros_map": "swarmpath.world.importers",
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'swarmpath.world' has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)


__all__ = [
    "ROBOT_PRESETS",
    "GridSpec",
    "ImportedMap",
    "MapImportError",
    "Motion",
    "MotionSpec",
    "Obstacle",
    "ObstacleSet",
    "OccupancyGrid",
    "RandomMotion",
    "RobotSpec",
    "Scenario",
    "ScenarioError",
    "WorldState",
    "collides",
    "get_map",
    "list_maps",
    "load_movingai_map",
    "load_ros_map",
    "load_scenario",
    "point_polygon_distance",
    "point_segment_distance",
    "points_in_polygon",
    "polygon_problems",
    "rasterize",
    "rasterize_scenario",
    "save_scenario",
    "scenario_from_dict",
    "scenario_json_schema",
    "scenario_problems",
    "scenario_to_dict",
    "segment_polygon_distance",
    "segment_segment_distance",
]
