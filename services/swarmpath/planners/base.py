"""Planners and their registry.

A planner decides where the robot goes next from an :class:`Observation`. Local planners see the
world only through the robot's sensors (the papers' "unknown environment"); global planners are
handed the static part of the map once, at construction, and say so (``kind = "global"``).
"""

from __future__ import annotations

import importlib
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from swarmpath.robot.kinematics import Pose
from swarmpath.robot.sensors import SensorReading
from swarmpath.world.geometry import ObstacleSet
from swarmpath.world.scenario import Scenario

Array = NDArray[np.float64]
ParamValue = float | int | bool | str


class PlannerError(ValueError):
    """A bad planner name or parameter; the message names it and lists what is valid."""


@dataclass(frozen=True)
class Observation:
    time: float  # simulated seconds
    pose: Pose
    goal: Array  # (2,) current goal position (the goal is known, e.g. by GPS)
    reading: SensorReading | None  # None for planners that use no sensors
    robot_radius: float
    world_size: tuple[float, float]


@dataclass(frozen=True)
class Decision:
    """Drive toward ``target`` for at most ``duration`` simulated seconds (None: until reached)."""

    target: Array | None  # (2,) or None when the planner gives up
    iterations: int = 0  # optimizer iterations spent on this decision
    duration: float | None = None
    reason: str | None = None  # why target is None
    #: The target is the goal: keep driving onto it instead of stopping at the goal tolerance.
    finish: bool = False


class Planner(ABC):
    name: ClassVar[str]
    kind: ClassVar[str] = "local"  # "local" (sensors only) or "global" (static map given)
    description: ClassVar[str] = ""
    reference: ClassVar[str] = ""
    defaults: ClassVar[Mapping[str, ParamValue]] = {}
    choices: ClassVar[Mapping[str, tuple[str, ...]]] = {}
    #: Sensor model used when the scenario names none (local planners).
    default_sensors: ClassVar[str | None] = None

    def __init__(
        self,
        scenario: Scenario,
        params: Mapping[str, Any] | None,
        rng: np.random.Generator,
        static_map: ObstacleSet | None = None,
    ):
        self.scenario = scenario
        self.p = self.resolve_params(params)
        self.rng = rng
        self.static_map = static_map

    @classmethod
    def resolve_params(cls, params: Mapping[str, Any] | None) -> dict[str, ParamValue]:
        merged: dict[str, ParamValue] = dict(cls.defaults)
        for key, value in (params or {}).items():
            if key not in cls.defaults:
                valid = ", ".join(sorted(cls.defaults)) or "none"
                raise PlannerError(f"planner {cls.name} has no parameter {key!r}; valid: {valid}")
            default = cls.defaults[key]
            if isinstance(default, bool):
                ok = isinstance(value, bool)
            elif isinstance(default, str):
                allowed = cls.choices.get(key, ())
                ok = isinstance(value, str) and (not allowed or value in allowed)
                if not ok:
                    raise PlannerError(
                        f"{cls.name}.{key} must be one of {', '.join(allowed)}; got {value!r}"
                    )
            elif isinstance(default, int):
                ok = isinstance(value, int | float) and not isinstance(value, bool) and float(
                    value
                ) == int(value)
                value = int(value) if ok else value
            else:
                ok = isinstance(value, int | float) and not isinstance(value, bool) and bool(
                    np.isfinite(value)
                )
                value = float(value) if ok else value
            if not ok:
                raise PlannerError(f"{cls.name}.{key} has the wrong type: {value!r}")
            merged[key] = value
        cls.check_params(merged)
        return merged

    @classmethod  # noqa: B027 - an optional hook, empty on purpose
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        """Range checks; raise PlannerError naming the parameter."""

    @abstractmethod
    def decide(self, obs: Observation) -> Decision: ...


# ----------------------------------------------------------------------------------- registry
_MODULES = ("swarm_local", "rfo_gwo", "ompl_baselines")
_REGISTRY: dict[str, type[Planner]] = {}
_SEQUENCE: dict[str, int] = {}
_loaded = False


def register(cls: type[Planner]) -> type[Planner]:
    if cls.name in _REGISTRY and _REGISTRY[cls.name] is not cls:
        raise ValueError(f"planner {cls.name!r} registered twice")
    _REGISTRY[cls.name] = cls
    _SEQUENCE.setdefault(cls.__name__ + "/" + cls.__module__, len(_SEQUENCE))
    return cls


def _load() -> None:
    global _loaded
    if not _loaded:
        for module in _MODULES:
            importlib.import_module(f"swarmpath.planners.{module}")
        _loaded = True


def _position(cls: type) -> tuple[int, int]:
    """Listing order: the module order above, then registration order (whatever was imported
    first, e.g. by a test importing one module directly)."""
    module = cls.__module__.rsplit(".", 1)[-1]
    rank = _MODULES.index(module) if module in _MODULES else len(_MODULES)
    return rank, _SEQUENCE[cls.__name__ + "/" + cls.__module__]


def list_planners() -> list[str]:
    _load()
    return [cls.name for cls in sorted(_REGISTRY.values(), key=_position)]


def get_planner(name: str) -> type[Planner]:
    _load()
    try:
        return _REGISTRY[name]
    except KeyError:
        valid = ", ".join(list_planners())
        raise PlannerError(f"unknown planner {name!r}; valid: {valid}") from None
