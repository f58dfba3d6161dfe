"""Scenario files: the hand-written JSON (or YAML) format, its JSON Schema, and the conversion to
the core :class:`~swarmpath.world.scenario.Scenario`.

Example (every field is documented in docs/maps.md and in schemas/scenario.schema.json)::

    {"name": "demo", "size": [10, 10], "start": [0, 0], "goal": [10, 10],
     "goal_motion": {"speed": 0.1, "heading_deg": 45},
     "robot": {"model": "omni", "radius": 0.5},
     "obstacles": [
        {"shape": "circle", "center": [2, 2.3], "radius": 0.5},
        {"shape": "circle", "center": [4, 2], "radius": 0.3, "speed": 0.3, "heading_deg": 111.8},
        {"shape": "polygon", "points": [[1, 5], [2, 5], [2, 6.5]], "random": true}]}

Errors are collected and raised together as one :class:`ScenarioError` whose lines each start with
the field path, e.g. ``obstacles[2].radius: must be > 0``. Structural problems (types, ranges,
unknown fields) come from pydantic; geometric ones (self-intersecting polygons, start or goal
colliding or outside the world) from :func:`swarmpath.world.scenario.scenario_problems`, the same
check the presets are tested with.
"""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from swarmpath.world.safe_yaml import load_yaml
from swarmpath.world.scenario import (
    DEFAULT_RANDOM_MAX_SPEED,
    DEFAULT_TIME_STEP,
    ROBOT_PRESETS,
    GridSource,
    Motion,
    MotionSpec,
    Obstacle,
    RandomMotion,
    RobotSpec,
    Scenario,
    scenario_problems,
)

__all__ = [
    "SCHEMA_PATH",
    "ScenarioError",
    "ScenarioModel",
    "load_scenario",
    "save_scenario",
    "scenario_from_dict",
    "scenario_json_schema",
    "scenario_to_dict",
    "write_scenario_schema",
]

#: Where the committed schema lives in a source checkout (repo/schemas/scenario.schema.json).
SCHEMA_PATH = Path(__file__).resolve().parents[3] / "schemas" / "scenario.schema.json"


class ScenarioError(ValueError):
    """An invalid scenario; ``problems`` lists ``(field path, message)`` pairs."""

    def __init__(self, problems: list[tuple[str, str]], source: str | None = None):
        self.problems = problems
        self.source = source
        head = f"invalid scenario{f' {source}' if source else ''}"
        lines = [f"{p}: {m}" if p else m for p, m in problems]
        super().__init__(head + ":\n  " + "\n  ".join(lines))


# ------------------------------------------------------------------------------ pydantic models
Pos = Annotated[float, Field(gt=0)]
NonNeg = Annotated[float, Field(ge=0)]
Vec2 = Annotated[tuple[float, float], Field(description="[x, y] in metres")]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class MotionFields(_Strict):
    speed: NonNeg | None = Field(
        None, description="Constant speed in m/s (needs heading_deg); MFB eqs 1-2."
    )
    heading_deg: float | None = Field(
        None, description="Direction of constant motion, degrees counter-clockwise from +x."
    )
    random: bool = Field(
        False,
        description="Random walk of the ICOOT/IHPO papers (eqs 7-10): every time step a new "
        "heading 360 U(0,1) deg and speed max_speed U(0,1) m/s. Excludes speed/heading_deg.",
    )
    max_speed: Pos | None = Field(
        None,
        description=f"Top speed of the random walk in m/s (default {DEFAULT_RANDOM_MAX_SPEED}); "
        "only with random: true.",
    )


class GoalMotionModel(MotionFields):
    """Goal motion: constant ({speed, heading_deg}) or random ({random: true})."""


class CircleModel(MotionFields):
    """A circular obstacle; static unless it has speed+heading_deg or random: true."""

    shape: Literal["circle"]
    center: Vec2
    radius: Pos = Field(description="Radius in metres (not inflated by the robot).")


class PolygonModel(MotionFields):
    """A simple polygon obstacle (not self-intersecting; first point not repeated)."""

    shape: Literal["polygon"]
    points: list[Vec2] = Field(min_length=3, description="Vertices [[x, y], ...], any order.")


ObstacleModel = Annotated[CircleModel | PolygonModel, Field(discriminator="shape")]


class RobotModel(_Strict):
    """The robot. Fields left out come from ``preset`` (default: the preset named like ``model``,
    or ``diff-drive``)."""

    preset: Literal["diff-drive", "turtlebot3-burger", "omni"] | None = Field(
        None,
        description="diff-drive: ICOOT/IHPO settings (0.5 m/s, wheel radius 0.034 m, w_max = "
        "v/r, TurtleBot3 Burger body r=0.105 m); turtlebot3-burger: ROBOTIS values; omni: MFB "
        "paper, r=0.5 m.",
    )
    model: Literal["diff-drive", "omni"] | None = None
    radius: Pos | None = Field(None, description="Footprint radius in metres.")
    linear_speed: Pos | None = Field(None, description="Max linear speed, m/s.")
    angular_speed: Pos | None = Field(None, description="Max angular speed, rad/s.")
    wheel_radius: Pos | None = Field(None, description="Wheel radius, m (diff-drive only).")
    wheel_separation: Pos | None = Field(
        None, description="Distance between the wheels, m (diff-drive only)."
    )


class GridModel(_Strict):
    """The grid map a scenario was imported from (written by the importers)."""

    frame: str = Field(min_length=1, max_length=64,
                       description="Name of the map's own frame, e.g. map (ROS).")
    origin: Vec2 = Field(description="Position of the scenario's (0, 0) in that frame, metres "
                         "(a ROS map's YAML origin x, y).")
    resolution: Pos = Field(description="Cell size in metres.")
    unknown: list[Annotated[list[tuple[int, int]], Field(min_length=3)]] = Field(
        default_factory=list, description="Cells of unknown occupancy as polygons in cell "
        "units (corner (i, j) is the scenario point (i, j) * resolution); drawn grey, used by "
        "the costmap metrics; not obstacles by themselves.")


class ScenarioModel(_Strict):
    """A swarmpath scenario: a w x h world [0, w] x [0, h] in metres, origin at the lower left."""

    model_config = ConfigDict(title="swarmpath scenario")

    name: str = Field(min_length=1)
    description: str = ""
    size: tuple[Pos, Pos] = Field(description="[w, h] of the world in metres.")
    start: Vec2
    goal: Vec2
    goal_motion: GoalMotionModel | None = None
    robot: RobotModel = Field(default_factory=lambda: RobotModel.model_validate({}))
    obstacles: list[ObstacleModel] = Field(default_factory=list)
    sensors: str | None = Field(
        None, description="Sensor model of swarmpath.robot.sensors, e.g. icoot-80 or mfb-12."
    )
    time_step: Pos = Field(DEFAULT_TIME_STEP, description="Simulator step in seconds.")
    grid: GridModel | None = Field(
        None, description="The grid map the scenario was imported from: its frame, "
        "resolution and unknown cells (set by the nav2 importer).")


# ---------------------------------------------------------------------------- error formatting
def _path(loc: tuple[int | str, ...]) -> str:
    out = ""
    prev_index = False
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
            prev_index = True
            continue
        if prev_index and part in ("circle", "polygon"):  # discriminated-union tag
            prev_index = False
            continue
        out += f".{part}" if out else part
        prev_index = False
    return out


def _field_names() -> list[str]:
    """Every field name of the scenario document (for "did you mean" on unknown fields)."""
    models = (ScenarioModel, RobotModel, CircleModel, PolygonModel, GoalMotionModel,
              GridModel)
    return list(dict.fromkeys(name for m in models for name in m.model_fields))


def _message(err: Any) -> tuple[str, str]:
    kind = err["type"]
    ctx = err.get("ctx") or {}
    path = _path(tuple(err["loc"]))
    if kind == "greater_than":
        return path, f"must be > {ctx['gt']:g}"
    if kind == "greater_than_equal":
        return path, f"must be >= {ctx['ge']:g}"
    if kind == "extra_forbidden":
        from swarmpath.names import did_you_mean

        return path, "unknown field" + did_you_mean(str(err["loc"][-1]), _field_names())
    if kind == "missing":
        return path, "required"
    if kind == "finite_number":
        return path, "must be a finite number"
    if kind == "too_short":
        return path, f"needs at least {ctx['min_length']} items"
    if kind == "too_long":
        return path, f"allows at most {ctx['max_length']} items"
    if kind == "union_tag_not_found":
        return (f"{path}.shape" if path else "shape"), "required: 'circle' or 'polygon'"
    from swarmpath.errors import near_miss, plain_message

    if kind == "union_tag_invalid":
        return f"{path}.shape", (f"must be one of {ctx['expected_tags']}, got {ctx['tag']!r}"
                                 + near_miss(ctx["tag"], ctx["expected_tags"]))
    if kind == "literal_error":
        return path, f"must be {ctx['expected']}" + near_miss(err.get("input"), ctx["expected"])
    if kind == "string_too_short":
        return path, "must not be empty"

    return path, plain_message(err)


# ----------------------------------------------------------------------------------- conversion
def _motion(path: str, m: MotionFields, problems: list[tuple[str, str]]) -> MotionSpec | None:
    if m.random:
        for name in ("speed", "heading_deg"):
            if getattr(m, name) is not None:
                problems.append((f"{path}{name}", "cannot be combined with random: true"))
        return RandomMotion(DEFAULT_RANDOM_MAX_SPEED if m.max_speed is None else m.max_speed)
    if m.max_speed is not None:
        problems.append((f"{path}max_speed", "only valid with random: true"))
    if m.speed is None and m.heading_deg is None:
        return None
    if m.speed is None:
        problems.append((f"{path}speed", "required when heading_deg is given"))
        return None
    if m.heading_deg is None:
        problems.append((f"{path}heading_deg", "required when speed is given"))
        return None
    return Motion(m.speed, m.heading_deg)


def _robot(r: RobotModel, problems: list[tuple[str, str]]) -> RobotSpec:
    """The robot; on a problem, the bare preset (so that the other checks can still run)."""
    preset = r.preset or r.model or "diff-drive"
    base = ROBOT_PRESETS[preset]
    if r.model is not None and r.model != base.model:
        problems.append(("robot.model", f"preset {preset!r} is a {base.model} robot"))
        return base
    overrides = {
        k: v
        for k in ("radius", "linear_speed", "angular_speed", "wheel_radius", "wheel_separation")
        if (v := getattr(r, k)) is not None
    }
    if base.model == "omni":
        for k in ("wheel_radius", "wheel_separation"):
            if overrides.pop(k, None) is not None:
                problems.append((f"robot.{k}", "not used by an omni robot"))
    return RobotSpec.preset(preset, **overrides)


def _sensor_problems(name: str | None) -> list[tuple[str, str]]:
    if name is None:
        return []
    from swarmpath.robot.sensors import SENSOR_MODELS  # the registry of sensor names

    if name not in SENSOR_MODELS:
        return [("sensors", f"unknown sensor model {name!r}; valid: {', '.join(SENSOR_MODELS)}")]
    return []


def scenario_from_dict(data: Mapping[str, Any], source: str | None = None) -> Scenario:
    """Validate a parsed scenario document and convert it; raises :class:`ScenarioError`."""
    if not isinstance(data, Mapping):
        raise ScenarioError([("", f"expected a JSON object, got {type(data).__name__}")], source)
    try:
        m = ScenarioModel.model_validate(dict(data))
    except ValidationError as e:
        raise ScenarioError([_message(err) for err in e.errors()], source) from None
    problems: list[tuple[str, str]] = []
    goal_motion = _motion("goal_motion.", m.goal_motion, problems) if m.goal_motion else None
    robot = _robot(m.robot, problems)
    obstacles = []
    for k, o in enumerate(m.obstacles):
        motion = _motion(f"obstacles[{k}].", o, problems)
        if isinstance(o, CircleModel):
            obstacles.append(Obstacle.circle(o.center, o.radius, motion))
        else:
            obstacles.append(Obstacle.polygon(o.points, motion))
    problems += _sensor_problems(m.sensors)
    scenario = Scenario(
        name=m.name,
        size=m.size,
        start=m.start,
        goal=m.goal,
        goal_motion=goal_motion,
        robot=robot,
        obstacles=tuple(obstacles),
        sensors=m.sensors,
        time_step=m.time_step,
        description=m.description,
        grid=None if m.grid is None else GridSource(
            m.grid.frame, m.grid.origin, m.grid.resolution,
            tuple(tuple(p) for p in m.grid.unknown)),
    )
    problems += scenario_problems(scenario)
    if problems:
        raise ScenarioError(problems, source)
    return scenario


def load_scenario(path_or_dict: str | os.PathLike[str] | Mapping[str, Any]) -> Scenario:
    """A scenario from a parsed dict or a file (``.yaml``/``.yml`` as YAML, anything else JSON)."""
    if isinstance(path_or_dict, Mapping):
        return scenario_from_dict(path_or_dict)
    path = Path(path_or_dict)
    try:
        text = path.read_text(encoding="utf-8")
        if path.suffix.lower() in (".yaml", ".yml"):
            data = load_yaml(text)
        else:
            data = json.loads(text)
    except UnicodeDecodeError:
        raise ScenarioError([("", "not a text file (UTF-8)")], str(path)) from None
    except RecursionError:
        raise ScenarioError([("", "cannot parse: the JSON nests too deeply")], str(path)
                            ) from None
    except (json.JSONDecodeError, yaml.YAMLError) as e:
        raise ScenarioError([("", f"cannot parse: {e}")], str(path)) from None
    return scenario_from_dict(data, str(path))


def _motion_dict(m: MotionSpec | None) -> dict[str, Any]:
    if isinstance(m, Motion):
        return {"speed": m.speed, "heading_deg": m.heading_deg}
    if isinstance(m, RandomMotion):
        return {"random": True, "max_speed": m.max_speed}
    return {}


def scenario_to_dict(s: Scenario) -> dict[str, Any]:
    """The JSON document for ``s`` (``load_scenario(scenario_to_dict(s)) == s``)."""
    r = s.robot
    robot: dict[str, Any] = {
        "model": r.model,
        "radius": r.radius,
        "linear_speed": r.linear_speed,
        "angular_speed": r.angular_speed,
    }
    if r.wheel_radius is not None:
        robot["wheel_radius"] = r.wheel_radius
    if r.wheel_separation is not None:
        robot["wheel_separation"] = r.wheel_separation
    obstacles: list[dict[str, Any]] = []
    for o in s.obstacles:
        if o.shape == "circle":
            assert o.center is not None
            d: dict[str, Any] = {"shape": "circle", "center": list(o.center), "radius": o.radius}
        else:
            d = {"shape": "polygon", "points": [list(p) for p in o.points or ()]}
        d.update(_motion_dict(o.motion))
        obstacles.append(d)
    out: dict[str, Any] = {"name": s.name}
    if s.description:
        out["description"] = s.description
    out |= {"size": list(s.size), "start": list(s.start), "goal": list(s.goal)}
    if s.goal_motion is not None:
        out["goal_motion"] = _motion_dict(s.goal_motion)
    out |= {"robot": robot, "obstacles": obstacles}
    if s.sensors is not None:
        out["sensors"] = s.sensors
    out["time_step"] = s.time_step
    if s.grid is not None:
        out["grid"] = {"frame": s.grid.frame, "origin": list(s.grid.origin),
                       "resolution": s.grid.resolution,
                       "unknown": [[list(p) for p in poly] for poly in s.grid.unknown]}
    return out


def save_scenario(s: Scenario, path: str | os.PathLike[str]) -> Path:
    """Write ``s`` as pretty JSON."""
    p = Path(path)
    p.write_text(json.dumps(scenario_to_dict(s), indent=2) + "\n", encoding="utf-8")
    return p


# ---------------------------------------------------------------------------------------- schema
def scenario_json_schema() -> dict[str, Any]:
    """JSON Schema (draft 2020-12) of the scenario format, as committed in SCHEMA_PATH."""
    schema = ScenarioModel.model_json_schema()
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", **schema}


def write_scenario_schema(path: str | os.PathLike[str] | None = None) -> Path:
    """(Re)write the committed schema file (default :data:`SCHEMA_PATH`)."""
    p = Path(path) if path is not None else SCHEMA_PATH
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(json.dumps(scenario_json_schema(), indent=2) + "\n", encoding="utf-8")
    return p


if __name__ == "__main__":  # python -m swarmpath.world.scenario_io [PATH]
    print(write_scenario_schema(sys.argv[1] if len(sys.argv) > 1 else None))
