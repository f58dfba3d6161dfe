"""Scenarios (what a planner is asked to solve) and the world state they unfold into over time.

Pure numpy: no I/O, no global state; randomness only from the ``numpy.random.Generator`` handed to
:meth:`Scenario.instantiate`. Units are metres, seconds and degrees (headings, counter-clockwise
from +x). The JSON adapter lives in :mod:`swarmpath.world.scenario_io`.

Motion of obstacles and of the goal
-----------------------------------
* :class:`Motion` - constant velocity, the MFB paper's eqs 1-2 (Ajeil et al. 2020, Table 6). The
  paper writes ``x_new = x + v cos(phi)`` per step with ``v`` in m/s; we integrate in continuous
  time, ``x(t) = x0 + v t cos(phi)``, so one simulator step of ``dt`` seconds moves ``v dt``.
* :class:`RandomMotion` - the random walk of the ICOOT/IHPO papers' eqs 7-10 (21-24 in IHPO): at
  every step ``theta = 360 U(0,1)`` degrees and ``v = U(0,1)``. The papers' unit is "per time
  step"; we read ``v`` as a speed in m/s scaled by ``max_speed`` (default 1 m/s), i.e.
  ``v_k = max_speed * U(0,1)`` and the step moves ``v_k * time_step`` metres. Headings and speeds
  are redrawn on the scenario's fixed step grid ``t_k = k * time_step`` whatever step the caller
  advances by.

Reproducibility: :meth:`Scenario.instantiate` takes one child stream ``rng.spawn(1)[0]`` (no draws
from ``rng`` itself), so what the caller draws later never changes the world. For step ``k`` the
world draws exactly ``rng.random((M, 2))`` - one ``[u_heading, u_speed]`` row per random mover, the
goal first (if random), then the random obstacles in scenario order - every step, regardless of
queries or of how the caller advances time. Motion is therefore a pure function of time and that
pre-drawn sequence: positions at any past (or future) time are available through the ``*_at(t)``
methods; the random-walk positions at step boundaries are kept as a history, extended lazily.

Walls: moving obstacles and a moving goal are reflected at the world boundary (angle of incidence
equals angle of reflection). A circle's centre is kept in ``[r, w - r] x [r, h - r]``, a polygon's
bounding box inside ``[0, w] x [0, h]``, a moving goal inside the world rectangle. If an obstacle
starts (partly) outside that band along an axis, the band is widened to include its start, so it
can never be pushed further out; an obstacle wider than the world does not move along that axis.
Static obstacles may extend beyond the world; the world boundary itself is not an obstacle.
Reflection is computed by folding the unfolded (wall-free) trajectory into the allowed band, per
axis, which is exact at any time. For the random walk the unfolded trajectory is the running sum
of the drawn steps, so a step's world-frame heading is the drawn ``theta_k`` mirrored by the
reflections so far; ``theta_k`` being uniform and independent of the past, so is the mirrored
heading: this is exactly the papers' process with reflecting walls.

Obstacle order: :class:`~swarmpath.world.geometry.ObstacleSet` stores circles and polygons
separately. Every ObstacleSet built here lists the circles in scenario order, then the polygons in
scenario order; :attr:`WorldState.set_order` maps that order back to ``scenario.obstacles``
indices, and :meth:`WorldState.velocities` uses the same order.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from swarmpath.world.geometry import ObstacleSet
from swarmpath.world.scenario_checks import MAX_METRES, polygon_problems, scenario_problems
from swarmpath.world.scenario_parts import (
    DEFAULT_RANDOM_MAX_SPEED,
    DEFAULT_TIME_STEP,
    ROBOT_PRESETS,
    GridSource,
    Motion,
    MotionSpec,
    Obstacle,
    Point,
    RandomMotion,
    RobotSpec,
    _point,
    obstacle_set,
)
from swarmpath.world.world_state import WorldState

__all__ = [
    "DEFAULT_RANDOM_MAX_SPEED",
    "DEFAULT_TIME_STEP",
    "MAX_METRES",
    "ROBOT_PRESETS",
    "GridSource",
    "Motion",
    "MotionSpec",
    "Obstacle",
    "RandomMotion",
    "RobotSpec",
    "Scenario",
    "WorldState",
    "obstacle_set",
    "polygon_problems",
    "scenario_problems",
]


# ------------------------------------------------------------------------------------ scenario
def _default_robot() -> RobotSpec:
    return ROBOT_PRESETS["diff-drive"]


@dataclass(frozen=True)
class Scenario:
    """A planning problem: a ``size = (w, h)`` world ``[0, w] x [0, h]``, start, goal, obstacles.

    ``goal_motion`` moves the goal (None: static goal). ``grid``: an imported grid map's frame,
    resolution and unknown cells (:class:`GridSource`). ``sensors`` names a sensor model of
    :mod:`swarmpath.robot.sensors` (e.g. ``"icoot-80"``, ``"mfb-12"``) or None. ``time_step`` is the
    simulator step in seconds; random motion is redrawn once per step. Validation is separate
    (:func:`scenario_problems`) so that tools can build and inspect broken scenarios.
    """

    name: str
    size: tuple[float, float]
    start: Point
    goal: Point
    goal_motion: MotionSpec | None = None
    robot: RobotSpec = field(default_factory=_default_robot)
    obstacles: tuple[Obstacle, ...] = ()
    sensors: str | None = None
    time_step: float = DEFAULT_TIME_STEP
    description: str = ""
    #: The grid map the scenario was imported from (frame, resolution, unknown cells), or None.
    grid: GridSource | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "size", _point(self.size, "size"))
        object.__setattr__(self, "start", _point(self.start, "start"))
        object.__setattr__(self, "goal", _point(self.goal, "goal"))
        object.__setattr__(self, "obstacles", tuple(self.obstacles))
        object.__setattr__(self, "time_step", float(self.time_step))

    @property
    def is_dynamic(self) -> bool:
        """True if anything moves (an obstacle or the goal)."""
        return self.goal_motion is not None or any(o.is_moving for o in self.obstacles)

    @property
    def has_random_motion(self) -> bool:
        return isinstance(self.goal_motion, RandomMotion) or any(
            isinstance(o.motion, RandomMotion) for o in self.obstacles
        )

    @property
    def max_obstacle_speed(self) -> float:
        """Upper bound (m/s) of any obstacle's speed: 0 when nothing moves (for swept checks)."""
        return max((o.motion.max_speed for o in self.obstacles if o.motion is not None),
                   default=0.0)

    def initial_obstacles(self) -> ObstacleSet:
        """All obstacles at t = 0 (not inflated)."""
        return obstacle_set(self.obstacles)

    def static_obstacles(self) -> ObstacleSet:
        """Only the obstacles that never move (what a global planner may know in advance)."""
        return obstacle_set([o for o in self.obstacles if not o.is_moving])

    def instantiate(self, rng: np.random.Generator) -> WorldState:
        """A fresh :class:`WorldState` at t = 0; random motion comes from ``rng.spawn(1)[0]``."""
        return WorldState(self, rng)

    def problems(self) -> list[tuple[str, str]]:
        """See :func:`scenario_problems`."""
        return scenario_problems(self)

