"""Planners and their registry.

A planner decides where the robot goes next from an :class:`Observation`. Local planners see the
world only through the robot's sensors (the papers' "unknown environment"); global planners are
handed the static part of the map once, at construction, and say so (``kind = "global"``). A local
planner may be given the static map too when its parameters ask for it (``knows_static_map``).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from swarmpath.registry import ParamValue, Registry, caller_module, origin_for, resolve_params
from swarmpath.robot.kinematics import Pose
from swarmpath.robot.sensors import SensorReading
from swarmpath.world.geometry import ObstacleSet
from swarmpath.world.scenario import Scenario

Array = NDArray[np.float64]


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
    #: Follow the straight segment to ``target`` exactly: a differential drive turns in place
    #: until it faces the target, then drives straight (global planners whose segments were
    #: collision-checked); otherwise it turns while driving and its path bulges off the segment.
    align: bool = False


class Planner(ABC):
    name: ClassVar[str]
    kind: ClassVar[str] = "local"  # "local" (sensors only) or "global" (static map given)
    description: ClassVar[str] = ""
    reference: ClassVar[str] = ""
    defaults: ClassVar[Mapping[str, ParamValue]] = {}
    choices: ClassVar[Mapping[str, tuple[str, ...]]] = {}
    #: Sensor model used when the scenario names none (local planners).
    default_sensors: ClassVar[str | None] = None
    #: Whether the simulator's motion guard executes this planner's decisions: no step whose
    #: swept body would touch a static obstacle is driven as is (:meth:`Simulator._guarded`).
    guarded: ClassVar[bool] = False

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
        owner = f"planner {cls.name}"
        merged = resolve_params(owner, cls.defaults, cls.choices, params, PlannerError)
        cls.check_params(merged)
        return merged

    @classmethod  # noqa: B027 - an optional hook, empty on purpose
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        """Range checks; raise PlannerError naming the parameter."""

    @classmethod
    def knows_static_map(cls, p: Mapping[str, ParamValue]) -> bool:
        """Whether a planner with resolved parameters ``p`` is handed the static map."""
        return cls.kind == "global"

    @property
    def planned_length(self) -> float | None:
        """Length of the path a global planner planned (None: no plan, or a local planner)."""
        return None

    @abstractmethod
    def decide(self, obs: Observation) -> Decision: ...


# ----------------------------------------------------------------------------------- registry
_MODULES = ("swarm_local", "swarm_family", "rfo_gwo", "ompl_baselines")
REGISTRY: Registry[type[Planner]] = Registry(
    "planner", "swarmpath.planners", _MODULES, PlannerError, group="swarmpath.planners"
)


def register_planner(cls: type[Planner]) -> type[Planner]:
    """Class decorator: add a :class:`Planner` subclass under its ``name`` (a name taken by
    other code is refused, naming both origins)."""
    if not (isinstance(cls, type) and issubclass(cls, Planner)):
        raise TypeError(f"register_planner takes a Planner subclass, got {cls!r}")
    return REGISTRY.register(cls, origin_for(caller_module()))


register = register_planner  # the name the built-in modules use


def list_planners(builtin: bool | None = None) -> list[str]:
    """Registered names, built-ins first (``builtin``: only built-ins, or only plugins)."""
    return REGISTRY.names(builtin)


def get_planner(name: str) -> type[Planner]:
    return REGISTRY.get(name)
