"""What a :class:`swarmpath.world.scenario.Scenario` is built from: obstacle and goal motions,
obstacles, the robot (with its presets) and the scenario defaults. Pure numpy."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmpath.world.geometry import (
    ObstacleSet,
)

Array = NDArray[np.float64]
Point = tuple[float, float]

#: Default simulator step (s) when a scenario does not give one.
DEFAULT_TIME_STEP = 0.1
#: Default top speed (m/s) of the papers' random walk, v = U(0, 1) read as m/s.
DEFAULT_RANDOM_MAX_SPEED = 1.0


def _point(p: Iterable[float], what: str) -> Point:
    t = tuple(float(v) for v in p)
    if len(t) != 2:
        raise ValueError(f"{what}: expected 2 numbers, got {len(t)}")
    return (t[0], t[1])


# ------------------------------------------------------------------------------------- motion
@dataclass(frozen=True)
class Motion:
    """Constant-velocity motion (MFB eqs 1-2): ``speed`` m/s along ``heading_deg`` (CCW from +x)."""

    speed: float
    heading_deg: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "speed", float(self.speed))
        object.__setattr__(self, "heading_deg", float(self.heading_deg))

    @property
    def velocity(self) -> Point:
        """(vx, vy) in m/s."""
        a = math.radians(self.heading_deg)
        return (self.speed * math.cos(a), self.speed * math.sin(a))

    @property
    def max_speed(self) -> float:
        return self.speed


@dataclass(frozen=True)
class RandomMotion:
    """The ICOOT/IHPO random walk (eqs 7-10): per step heading 360 U(0,1) deg, speed vmax U(0,1).

    ``max_speed`` is in m/s; a step of ``dt`` seconds moves at most ``max_speed * dt`` metres.
    """

    max_speed: float = DEFAULT_RANDOM_MAX_SPEED

    def __post_init__(self) -> None:
        object.__setattr__(self, "max_speed", float(self.max_speed))


MotionSpec = Motion | RandomMotion


# ----------------------------------------------------------------------------------- obstacles
@dataclass(frozen=True)
class Obstacle:
    """A circle (``center``, ``radius``) or a simple polygon (``points``), optionally moving.

    Coordinates are stored as tuples of floats so scenarios compare and hash by value. Use the
    :meth:`circle`, :meth:`polygon` and :meth:`rectangle` constructors.
    """

    shape: Literal["circle", "polygon"]
    center: Point | None = None
    radius: float | None = None
    points: tuple[Point, ...] | None = None
    motion: MotionSpec | None = None

    def __post_init__(self) -> None:
        if self.shape == "circle":
            if self.center is None or self.radius is None or self.points is not None:
                raise ValueError("a circle needs center and radius and no points")
            object.__setattr__(self, "center", _point(self.center, "center"))
            object.__setattr__(self, "radius", float(self.radius))
        elif self.shape == "polygon":
            if self.points is None or self.center is not None or self.radius is not None:
                raise ValueError("a polygon needs points and no center or radius")
            pts = tuple(_point(p, "points[]") for p in self.points)
            object.__setattr__(self, "points", pts)
        else:
            raise ValueError(f"shape must be 'circle' or 'polygon', got {self.shape!r}")

    @classmethod
    def circle(
        cls, center: Sequence[float], radius: float, motion: MotionSpec | None = None
    ) -> Obstacle:
        return cls("circle", center=(center[0], center[1]), radius=radius, motion=motion)

    @classmethod
    def polygon(
        cls, points: Iterable[Sequence[float]], motion: MotionSpec | None = None
    ) -> Obstacle:
        return cls("polygon", points=tuple((p[0], p[1]) for p in points), motion=motion)

    @classmethod
    def rectangle(
        cls,
        xmin: float,
        ymin: float,
        xmax: float,
        ymax: float,
        motion: MotionSpec | None = None,
    ) -> Obstacle:
        """Axis-aligned rectangle as a counter-clockwise 4-point polygon."""
        return cls.polygon(((xmin, ymin), (xmax, ymin), (xmax, ymax), (xmin, ymax)), motion)

    @property
    def is_moving(self) -> bool:
        return self.motion is not None

    @property
    def vertices(self) -> Array:
        """Polygon vertices as an (m, 2) array (polygons only)."""
        if self.points is None:
            raise ValueError("a circle has no vertices")
        return np.array(self.points, dtype=np.float64)

    def bounds(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) at its initial position."""
        if self.shape == "circle":
            assert self.center is not None and self.radius is not None
            (cx, cy), r = self.center, self.radius
            return (cx - r, cy - r, cx + r, cy + r)
        v = self.vertices
        return (float(v[:, 0].min()), float(v[:, 1].min()), float(v[:, 0].max()),
                float(v[:, 1].max()))


def obstacle_set(obstacles: Sequence[Obstacle]) -> ObstacleSet:
    """ObstacleSet of obstacles at their initial positions (circles first, then polygons)."""
    circles = [(*o.center, o.radius) for o in obstacles if o.shape == "circle"]  # type: ignore[misc]
    polys = tuple(o.vertices for o in obstacles if o.shape == "polygon")
    return ObstacleSet(np.array(circles, dtype=np.float64).reshape(-1, 3), polys)


# ------------------------------------------------------------------------------------- robots
@dataclass(frozen=True)
class RobotSpec:
    """The robot: a disk of ``radius`` m with speed limits (m/s, rad/s) and wheel geometry (m).

    ``wheel_radius``/``wheel_separation`` describe a differential drive and are ``None`` for an
    omnidirectional robot. Presets: :data:`ROBOT_PRESETS` / :meth:`preset`.
    """

    model: Literal["diff-drive", "omni"]
    radius: float
    linear_speed: float
    angular_speed: float
    wheel_radius: float | None = None
    wheel_separation: float | None = None

    def __post_init__(self) -> None:
        if self.model not in ("diff-drive", "omni"):
            raise ValueError(f"model must be 'diff-drive' or 'omni', got {self.model!r}")
        for name in ("radius", "linear_speed", "angular_speed", "wheel_radius", "wheel_separation"):
            v = getattr(self, name)
            if v is not None:
                object.__setattr__(self, name, float(v))

    @classmethod
    def preset(cls, name: str, **overrides: float | str | None) -> RobotSpec:
        """A preset from :data:`ROBOT_PRESETS` with some fields overridden (e.g. ``radius=0.3``)."""
        try:
            base = ROBOT_PRESETS[name]
        except KeyError:
            valid = ", ".join(ROBOT_PRESETS)
            raise KeyError(f"unknown robot preset {name!r}; valid: {valid}") from None
        fields: dict[str, float | str | None] = {
            "model": base.model,
            "radius": base.radius,
            "linear_speed": base.linear_speed,
            "angular_speed": base.angular_speed,
            "wheel_radius": base.wheel_radius,
            "wheel_separation": base.wheel_separation,
        }
        unknown = set(overrides) - set(fields)
        if unknown:
            raise KeyError(f"unknown robot field(s) {sorted(unknown)}; valid: {sorted(fields)}")
        fields.update(overrides)
        return cls(**fields)  # type: ignore[arg-type]


#: Robot presets. ``diff-drive``: the ICOOT/IHPO papers' settings (0.5 m/s, wheel radius 0.034 m,
#: max angular = linear / wheel radius) on a TurtleBot3 Burger body (the papers assume one:
#: footprint radius 0.105 m, wheel separation 0.160 m). ``turtlebot3-burger``: ROBOTIS values.
#: ``omni``: the MFB paper's omnidirectional robot, radius 0.5 m (Table 3 static map; its dynamic
#: map uses 0.3 m); the paper publishes no speeds, 0.5 m/s and 1 rad/s are our choice.
ROBOT_PRESETS: dict[str, RobotSpec] = {
    "diff-drive": RobotSpec("diff-drive", 0.105, 0.5, 0.5 / 0.034, 0.034, 0.160),
    "turtlebot3-burger": RobotSpec("diff-drive", 0.105, 0.22, 2.84, 0.033, 0.160),
    "omni": RobotSpec("omni", 0.5, 0.5, 1.0, None, None),
}



# -------------------------------------------------------------------------------- grid source
@dataclass(frozen=True)
class GridSource:
    """Where an imported grid map came from: its frame and what the grid held beyond obstacles.

    ``frame`` names the map's own frame (``"map"`` for ROS maps, whose YAML ``origin`` places
    the lower-left pixel); ``origin`` is that frame's position of the scenario's (0, 0), so
    ``map_xy = scenario_xy + origin``. ``resolution`` is the cell size (m); ``unknown`` the
    cells of unknown occupancy as orthogonal polygons in cell units (integer corners: vertex
    (i, j) is the scenario point (i, j) * resolution; compact and exact) (drawn grey by the
    plots, used by the costmap metrics; the planners never see it: with the importer's default
    those cells are obstacles too). Not validated beyond its shape: the importer makes it.
    """

    frame: str
    origin: Point
    resolution: float
    unknown: tuple[tuple[tuple[int, int], ...], ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "origin", _point(self.origin, "grid.origin"))
        object.__setattr__(self, "resolution", float(self.resolution))
        object.__setattr__(self, "unknown", tuple(
            tuple((int(p[0]), int(p[1])) for p in poly) for poly in self.unknown))

    def unknown_polygons(self) -> list[Array]:
        """The unknown cells' polygons in scenario-frame metres."""
        return [np.asarray(poly, dtype=np.float64) * self.resolution for poly in self.unknown]

    def to_map_frame(self, xy: ArrayLike) -> Array:
        """Scenario-frame points (..., 2) in the map frame."""
        return np.asarray(xy, dtype=np.float64) + np.asarray(self.origin)

    def to_scenario_frame(self, xy: ArrayLike) -> Array:
        """Map-frame points (..., 2) in the scenario frame."""
        return np.asarray(xy, dtype=np.float64) - np.asarray(self.origin)
