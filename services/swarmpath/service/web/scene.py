"""The map of a map cell as plain JSON for the dashboard's SVG: world size, start, goal, robot
radius, obstacles (circles and polygons, moving ones flagged) and, for a given run, the moving
obstacles' and the goal's positions over time (that run's simulated world: random motion differs
between runs, so the job page shows run 0's tracks and says so)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

TRACK_POINTS = 120  # samples of a moving obstacle's or the goal's track


def load_cell_scenario(spec: Mapping[str, Any]) -> Any:
    """The cell's Scenario: its inline scenario, or the preset named by ``map``."""
    if spec.get("scenario") is not None:
        from swarmpath.world.scenario_io import scenario_from_dict

        return scenario_from_dict(dict(spec["scenario"]))
    from swarmpath.world.presets import get_map

    return get_map(str(spec["map"]))


def _r(v: Any) -> Any:
    return np.round(np.asarray(v, dtype=np.float64), 4).tolist()


def scene(scenario: Any) -> dict[str, Any]:
    """Static geometry: size, start, goal, robot radius and every obstacle at t = 0 (scenario
    frame), and the map's own frame with its origin (nav2 maps: "map" and the YAML origin)."""
    obstacles = []
    for ob in scenario.obstacles:
        item: dict[str, Any] = {"shape": ob.shape, "moving": bool(ob.is_moving)}
        if ob.shape == "circle":
            item.update(center=_r(ob.center), radius=round(float(ob.radius), 4))
        else:
            item["points"] = _r(ob.points)
        obstacles.append(item)
    return {
        "name": scenario.name, "size": _r(scenario.size), "start": _r(scenario.start),
        "goal": _r(scenario.goal), "robot_radius": float(scenario.robot.radius),
        "dynamic": bool(scenario.is_dynamic), "obstacles": obstacles,
        # the chart draws the scenario frame; a nav2 map's own frame is this far off
        "frame": scenario.grid.frame if scenario.grid is not None else "scenario",
        "origin": _r(scenario.grid.origin) if scenario.grid is not None else [0.0, 0.0],
    }


def motion(scenario: Any, seed: int, run: int, t_end: float,
           samples: int = TRACK_POINTS) -> dict[str, Any]:
    """Run ``run``'s world from t = 0 to ``t_end``: ``times``, ``offsets[k][i]`` = [dx, dy] of
    scenario obstacle k at times[i] (moving obstacles only; static ones are absent) and ``goal``
    positions (when the goal moves)."""
    movers = [k for k, ob in enumerate(scenario.obstacles) if ob.is_moving]
    if not scenario.is_dynamic or t_end <= 0:
        return {"times": [], "offsets": {}, "goal": []}
    from swarmpath.optimizers.streams import SIMULATION, run_generator

    world = scenario.instantiate(run_generator(seed, run, SIMULATION))
    times = np.linspace(0.0, float(t_end), samples)
    column = {k: j for j, k in enumerate(world.set_order)}
    offsets: dict[str, Any] = {}
    if movers:
        pos = np.array([world.obstacle_positions_at(float(t)) for t in times])
        for k in movers:
            j = column[k]
            offsets[str(k)] = _r(pos[:, j] - pos[0, j])
    goal = (_r([world.goal_at(float(t)) for t in times])
            if scenario.goal_motion is not None else [])
    return {"times": _r(times), "offsets": offsets, "goal": goal}


def collision_points(scenario: Any, seed: int, run: int, path: Any,
                     limit: int = 20) -> list[list[float]]:
    """Where run ``run``'s executed path touched an obstacle: the end point [x, y, t] of the
    first step of each stretch of colliding steps (the product's rule: body gap <= 0, against
    the obstacles' true positions in that run's world), at most ``limit`` of them."""
    from swarmpath.metrics import step_clearances
    from swarmpath.optimizers.streams import SIMULATION, run_generator
    from swarmpath.world.geometry import collides

    p = np.asarray(path, dtype=np.float64).reshape(-1, 3)
    if p.shape[0] < 2:
        return []
    if scenario.is_dynamic:
        world = scenario.instantiate(run_generator(seed, run, SIMULATION))
        hits = collides(step_clearances(p, world.obstacles_at), scenario.robot.radius)
    else:
        hits = collides(step_clearances(p, scenario.initial_obstacles()), scenario.robot.radius)
    starts = np.flatnonzero(hits & ~np.concatenate([[False], hits[:-1]]))[:limit]
    return _r(p[starts + 1])
