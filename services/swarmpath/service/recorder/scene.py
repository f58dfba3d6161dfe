"""How a map job is drawn for Foxglove: each map's frame, occupancy grid and obstacles, the
scenario and world of a run, the markers and colours of the scene topics."""

from __future__ import annotations

import logging
from typing import Any

from swarmpath.service import foxglove as fg
from swarmpath.service.recorder.common import _topic_name

log = logging.getLogger(__name__)

MAX_SCENE_FRAMES = 200  # per run: path samples drawn as robot positions
GRID_MAX_CELLS = 400  # per side of the occupancy raster
MAP_GAP = 2.0  # m between two maps laid side by side in the world frame
WORLD_FRAME = "world"
ROBOT_HEIGHT = 0.2
OBSTACLE_HEIGHT = 0.5
OBSTACLE_RGBA = fg.color(0.45, 0.45, 0.5, 0.9)
ROBOT_RGBA = fg.color(0.95, 0.35, 0.1, 0.9)
START_RGBA = fg.color(0.1, 0.4, 1.0)
GOAL_RGBA = fg.color(0.1, 0.8, 0.2)


def map_frame(name: str) -> str:
    """The frame of one map (its origin at the map's (0, 0)); ``/tf`` places it in ``world``."""
    return f"map/{_topic_name(name)}"


def source_frame(name: str, frame: str) -> str:
    """The frame of an imported map's own frame (a nav2 map's ``map``): its origin is the YAML
    origin's, and ``/tf`` places the map's scenario frame (:func:`map_frame`) in it at the
    origin's (x, y), so positions can be read in the frame the ROS user thinks in."""
    return f"{map_frame(name)}/{_topic_name(frame)}"


def _run_about(record: dict[str, Any], planner: str, map_: str,
               bucket: int | None = None) -> dict[str, str]:
    """What identifies a map run, as strings (scene entity metadata, the run's metadata); the
    map's MovingAI ``bucket`` only when it has one (a reader of an older file finds no key)."""
    metrics = record.get("metrics") or {}
    about = {"run": str(int(record["run"])), "run_id": str(record["run_id"]), "planner": planner,
             "map": map_, "success": str(bool(metrics.get("success"))).lower(),
             "reason": str(metrics.get("reason") or record.get("failure") or "")}
    if bucket is not None:
        about["bucket"] = str(bucket)
    return about


def _marker(x: float, y: float, rgba: dict[str, float], size: float = 0.3) -> dict[str, Any]:
    return {"pose": fg.pose(x, y, size / 3), "size": fg.vec3(size, size, size), "color": rgba}


# ------------------------------------------------------------------------------ scenario shapes
def scenario_for(cell_spec: dict[str, Any]) -> Any | None:
    """The :class:`swarmpath.world.scenario.Scenario` of a map cell (inline JSON object or preset
    name); None when the world layer is unavailable or the scenario is invalid (the scene topics
    are then left out, /results is still written)."""
    try:
        from swarmpath.world.presets import get_map
        from swarmpath.world.scenario_io import scenario_from_dict
    except ImportError as exc:
        log.warning("no scenario geometry (world layer unavailable): %s", exc)
        return None
    inline = cell_spec.get("scenario")
    try:
        if isinstance(inline, dict):
            return scenario_from_dict(inline)
        return get_map(str(cell_spec.get("map")))
    except (KeyError, ValueError, TypeError) as exc:
        log.warning("no scenario geometry for map %r: %s", cell_spec.get("map"), exc)
        return None


def world_for(scenario: Any, seed: int, run: int) -> Any:
    """The world of run ``run``: the same moving obstacles and goal the simulator saw (the world
    draws from stream (seed, run, SIMULATION), see swarmpath.planners.episode)."""
    from swarmpath.optimizers.streams import SIMULATION, run_generator

    return scenario.instantiate(run_generator(seed, run, SIMULATION))


def occupancy(scenario: Any) -> tuple[bytes, int, float]:
    """The scenario's static obstacles rasterized by the world layer (moving ones are drawn per
    run where they are, never baked into the grid): uint8 0 free / 100 occupied, row-major from
    y = 0 up. Returns (data, columns, resolution)."""
    import dataclasses

    import numpy as np

    from swarmpath.world.raster import rasterize_scenario

    width, height = (float(v) for v in scenario.size)
    static = dataclasses.replace(
        scenario, obstacles=tuple(o for o in scenario.obstacles if not o.is_moving))
    grid = rasterize_scenario(static, max(width, height) / GRID_MAX_CELLS)
    data = np.where(grid.data < 0, 50, grid.data).astype(np.uint8)  # unknown -> 50
    return data.tobytes(), grid.shape[1], grid.resolution


def _obstacle_entity(ns: int, entity_id: str, obstacles: Any, frame: str) -> dict[str, Any]:
    """An ObstacleSet as one entity: cylinders for circles, line loops for polygons."""
    return fg.entity(
        ns, entity_id, frame,
        cylinders=[fg.cylinder(cx, cy, r, OBSTACLE_HEIGHT, OBSTACLE_RGBA)
                   for cx, cy, r in obstacles.circles],
        lines=[fg.line([(float(x), float(y)) for x, y in poly], OBSTACLE_RGBA, 0.04, loop=True)
               for poly in obstacles.polygons],
    )
