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

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmpath.world.geometry import (
    ObstacleSet,
    collides,
    point_segment_distance,
    segment_segment_distance,
)

Array = NDArray[np.float64]
Point = tuple[float, float]

__all__ = [
    "DEFAULT_RANDOM_MAX_SPEED",
    "DEFAULT_TIME_STEP",
    "ROBOT_PRESETS",
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


# ------------------------------------------------------------------------------------ scenario
def _default_robot() -> RobotSpec:
    return ROBOT_PRESETS["diff-drive"]


@dataclass(frozen=True)
class Scenario:
    """A planning problem: a ``size = (w, h)`` world ``[0, w] x [0, h]``, start, goal, obstacles.

    ``goal_motion`` moves the goal (None: static goal). ``sensors`` names a sensor model of
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


# ------------------------------------------------------------------------------- validation
def polygon_problems(points: ArrayLike) -> list[str]:
    """Why ``points`` is not a valid simple polygon (empty list: valid).

    Checks: at least 3 vertices, finite, no repeated consecutive vertex, non-zero area, and no two
    edges meeting anywhere except adjacent edges at their shared vertex (self-intersection).
    """
    P = np.asarray(points, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != 2:
        return ["must be a list of [x, y] points"]
    m = P.shape[0]
    if m < 3:
        return [f"needs at least 3 points, got {m}"]
    if not np.all(np.isfinite(P)):
        return ["coordinates must be finite"]
    A, B = P, np.roll(P, -1, axis=0)
    span = float(np.ptp(P, axis=0).max())
    tol = 1e-12 * max(span, 1.0)
    lengths = np.hypot(*(B - A).T)
    if np.any(lengths <= tol):
        q = int(np.argmax(lengths <= tol))
        return [f"points {q} and {(q + 1) % m} coincide"]
    # Non-adjacent edges must stay apart.
    i, j = np.triu_indices(m, k=2)
    keep = ~((i == 0) & (j == m - 1))
    i, j = i[keep], j[keep]
    if i.size:
        d = segment_segment_distance(A[i], B[i], A[j], B[j])
        bad = np.flatnonzero(d <= tol)
        if bad.size:
            k = int(bad[0])
            return [f"is self-intersecting (edges {int(i[k])} and {int(j[k])} meet)"]
    # Adjacent edges must not fold back onto each other (a vertex of one lying on the other).
    prev = np.roll(A, 1, axis=0)
    fold = (point_segment_distance(prev, A, B) <= tol) | (point_segment_distance(B, prev, A) <= tol)
    if np.any(fold):
        k = int(np.argmax(fold))
        return [f"is self-intersecting (edges {(k - 1) % m} and {k} overlap)"]
    area2 = float(np.sum(A[:, 0] * B[:, 1] - B[:, 0] * A[:, 1]))
    if abs(area2) <= tol * span:
        return ["has zero area"]
    return []


def scenario_problems(s: Scenario) -> list[tuple[str, str]]:
    """Everything wrong with ``s`` as ``(field path, message)`` pairs; empty when valid.

    Paths use the JSON spelling, e.g. ``("obstacles[2].radius", "must be > 0")``. Checks: positive
    finite size/time_step/robot numbers, radii > 0, simple polygons, non-negative motion speeds,
    start and goal inside the world and - at t = 0 - not in collision with any obstacle
    (clearance <= robot radius counts as a collision, :func:`~swarmpath.world.geometry.collides`).
    """
    out: list[tuple[str, str]] = []

    def positive(path: str, v: float | None) -> bool:
        if v is None or not math.isfinite(v) or v <= 0:
            out.append((path, "must be > 0"))
            return False
        return True

    if not s.name:
        out.append(("name", "must not be empty"))
    w, h = s.size
    size_ok = positive("size[0]", w) & positive("size[1]", h)
    positive("time_step", s.time_step)
    r = s.robot
    robot_ok = positive("robot.radius", r.radius)
    positive("robot.linear_speed", r.linear_speed)
    positive("robot.angular_speed", r.angular_speed)
    if r.model == "diff-drive":
        positive("robot.wheel_radius", r.wheel_radius)
        positive("robot.wheel_separation", r.wheel_separation)

    def motion(path: str, m: MotionSpec | None) -> None:
        if isinstance(m, Motion):
            if not (math.isfinite(m.speed) and m.speed >= 0):
                out.append((f"{path}speed", "must be >= 0"))
            if not math.isfinite(m.heading_deg):
                out.append((f"{path}heading_deg", "must be finite"))
        elif isinstance(m, RandomMotion):
            positive(f"{path}max_speed", m.max_speed)

    motion("goal_motion.", s.goal_motion)
    valid: list[Obstacle] = []  # obstacles well-formed enough for the collision checks
    for k, o in enumerate(s.obstacles):
        p = f"obstacles[{k}]"
        if o.shape == "circle":
            assert o.center is not None
            ok = all(math.isfinite(c) for c in o.center)
            if not ok:
                out.append((f"{p}.center", "coordinates must be finite"))
            if positive(f"{p}.radius", o.radius) and ok:
                valid.append(o)
        else:
            msgs = polygon_problems(o.points or ())
            out.extend((f"{p}.points", msg) for msg in msgs)
            if not msgs:
                valid.append(o)
        motion(f"{p}.", o.motion)
    obs = obstacle_set(valid)

    for label, pt in (("start", s.start), ("goal", s.goal)):
        x, y = pt
        if not (math.isfinite(x) and math.isfinite(y)):
            out.append((label, "coordinates must be finite"))
        elif size_ok and not (0.0 <= x <= w and 0.0 <= y <= h):
            out.append((label, f"({x:g}, {y:g}) is outside the world [0, {w:g}] x [0, {h:g}]"))
        elif robot_ok and not obs.is_empty:
            c = float(obs.point_clearance(np.array(pt)))
            if collides(c, r.radius):
                out.append((
                    label,
                    f"({x:g}, {y:g}) collides with an obstacle inflated by the robot radius "
                    f"{r.radius:g} (clearance {c:.3g} <= {r.radius:g})",
                ))
    return out


# ---------------------------------------------------------------------------------- world state
def _fold(u: Array, lo: Array, hi: Array) -> tuple[Array, Array]:
    """Reflect coordinates ``u`` into ``[lo, hi]`` (mirror at both walls); also the parity (+1/-1).

    Parity -1 means the motion direction is flipped at ``u`` (an odd number of reflections).
    Where ``hi <= lo`` the coordinate is pinned to ``lo``.
    """
    span = hi - lo
    ok = span > 0
    L = np.where(ok, span, 1.0)
    m = np.mod(u - lo, 2.0 * L)
    fwd = m < L
    pos = np.where(fwd, lo + m, lo + 2.0 * L - m)
    sign = np.where(fwd, 1.0, -1.0)
    return np.where(ok, pos, lo), np.where(ok, sign, 0.0)


class WorldState:
    """A scenario unfolding in time: obstacle and goal positions at ``time`` (seconds).

    Create with :meth:`Scenario.instantiate`. Moving things are "movers": moving obstacles and a
    moving goal. Each mover's position is an offset from its initial position; the offsets are a
    pure function of time (constant motion: closed form with reflection; random walk: a history of
    step-boundary offsets extended lazily from the pre-drawn sequence, see the module docstring).
    ``advance`` only moves ``time`` forward; querying any time never changes the random sequence.
    """

    _CHUNK = 64  # steps drawn at once (same values as drawing step by step)

    def __init__(self, scenario: Scenario, rng: np.random.Generator):
        self.scenario = scenario
        self.time = 0.0
        self._dt = scenario.time_step
        if not (math.isfinite(self._dt) and self._dt > 0):
            raise ValueError(f"time_step must be > 0, got {self._dt}")
        try:
            self._rng = rng.spawn(1)[0]
        except (TypeError, ValueError):  # a bit generator without a SeedSequence
            self._rng = np.random.default_rng(int(rng.integers(2**63)))
        w, h = scenario.size
        obs = scenario.obstacles
        circles = [k for k, o in enumerate(obs) if o.shape == "circle"]
        polys = [k for k, o in enumerate(obs) if o.shape == "polygon"]
        #: ``scenario.obstacles`` index of each ObstacleSet entry (circles first, then polygons).
        self.set_order: tuple[int, ...] = tuple(circles + polys)
        self._base = obstacle_set(obs)
        self._static = scenario.static_obstacles()

        # Movers: index 0..n_obs-1 = obstacles in set order, then the goal (if it moves).
        motions: list[MotionSpec | None] = [obs[k].motion for k in self.set_order]
        lo = np.zeros((len(motions), 2))
        hi = np.zeros((len(motions), 2))
        for i, k in enumerate(self.set_order):
            x0, y0, x1, y1 = obs[k].bounds()
            lo[i] = (-x0, -y0)
            hi[i] = (w - x1, h - y1)
        self._goal0 = np.array(scenario.goal, dtype=np.float64)
        motions.append(scenario.goal_motion)
        lo = np.vstack([lo, -self._goal0])
        hi = np.vstack([hi, np.array([w, h]) - self._goal0])
        # Never push a mover that starts outside its band further out: widen to include 0.
        self._lo = np.minimum(lo, 0.0)
        self._hi = np.maximum(hi, 0.0)
        self._n_obs = len(self.set_order)

        self._const_idx = np.array(
            [i for i, m in enumerate(motions) if isinstance(m, Motion)], dtype=np.intp
        )
        self._const_vel = np.array(
            [m.velocity for m in motions if isinstance(m, Motion)], dtype=np.float64
        ).reshape(-1, 2)
        # Random movers in draw order: goal first, then obstacles in scenario order.
        rand_scn = [i for i in range(self._n_obs) if isinstance(motions[i], RandomMotion)]
        rand_scn.sort(key=lambda i: self.set_order[i])
        if isinstance(scenario.goal_motion, RandomMotion):
            rand_scn.insert(0, self._n_obs)
        self._rand_idx = np.array(rand_scn, dtype=np.intp)
        self._rand_vmax = np.array(
            [motions[i].max_speed for i in rand_scn],  # type: ignore[union-attr]
            dtype=np.float64,
        )
        n_r = len(rand_scn)
        # History with spare capacity: *unfolded* offsets at step boundaries 0..K and drawn
        # velocities of steps 0..K-1, where K = self._K steps have been drawn so far.
        self._K = 0
        self._hist = np.zeros((self._CHUNK + 1, n_r, 2))
        self._vel = np.zeros((self._CHUNK, n_r, 2))

    # ----------------------------------------------------------------------------- time
    @property
    def time_step(self) -> float:
        return self._dt

    @property
    def step(self) -> int:
        """Index of the scenario step containing ``time`` (``floor(time / time_step)``)."""
        return self._step_of(self.time)

    def advance(self, dt: float | None = None) -> None:
        """Move time forward by ``dt`` seconds (default: one scenario ``time_step``)."""
        dt = self._dt if dt is None else float(dt)
        if not (math.isfinite(dt) and dt >= 0):
            raise ValueError(f"dt must be a finite number >= 0, got {dt}")
        self.time += dt

    def _step_of(self, t: float) -> int:
        return max(math.floor(t / self._dt + 1e-9), 0)

    def _check_t(self, t: float | None) -> float:
        t = self.time if t is None else float(t)
        if not (math.isfinite(t) and t >= 0):
            raise ValueError(f"time must be a finite number >= 0, got {t}")
        return t

    # ---------------------------------------------------------------------- random walk
    def _extend(self, k: int) -> None:
        """Make sure the random-walk history covers steps 0..k (boundaries 0..k+1)."""
        n_r = self._rand_idx.size
        if n_r == 0 or k < self._K:
            return
        need = k + 1
        if need > self._vel.shape[0]:
            cap = max(need, 2 * self._vel.shape[0])
            cap = -(-cap // self._CHUNK) * self._CHUNK
            vel = np.zeros((cap, n_r, 2))
            hist = np.zeros((cap + 1, n_r, 2))
            vel[: self._K] = self._vel[: self._K]
            hist[: self._K + 1] = self._hist[: self._K + 1]
            self._vel, self._hist = vel, hist
        n_new = -(-(need - self._K) // self._CHUNK) * self._CHUNK  # whole chunks
        u = self._rng.random((n_new, n_r, 2))  # same values as drawing step by step
        theta = np.deg2rad(360.0 * u[..., 0])
        speed = self._rand_vmax * u[..., 1]
        vel = speed[..., None] * np.stack([np.cos(theta), np.sin(theta)], axis=-1)
        K = self._K
        self._vel[K : K + n_new] = vel
        self._hist[K + 1 : K + n_new + 1] = self._hist[K] + np.cumsum(vel * self._dt, axis=0)
        self._K += n_new

    def _movers(self, t: float) -> tuple[Array, Array]:
        """Offsets (n_obs + 1, 2) and velocities (n_obs + 1, 2) of all movers at time t."""
        n = self._n_obs + 1
        off = np.zeros((n, 2))
        vel = np.zeros((n, 2))
        if self._const_idx.size:
            i = self._const_idx
            pos, sign = _fold(self._const_vel * t, self._lo[i], self._hi[i])
            off[i] = pos
            vel[i] = self._const_vel * sign
        if self._rand_idx.size:
            k = self._step_of(t)
            self._extend(k)
            tau = max(t - k * self._dt, 0.0)
            i = self._rand_idx
            lo, hi = self._lo[i], self._hi[i]
            pos, sign = _fold(self._hist[k] + self._vel[k] * tau, lo, hi)
            off[i] = pos
            vel[i] = self._vel[k] * sign
        return off, vel

    # --------------------------------------------------------------------------- queries
    def obstacles_at(self, t: float) -> ObstacleSet:
        """All obstacles (not inflated) at time ``t`` >= 0, past or future."""
        t = self._check_t(t)
        if not any(o.is_moving for o in self.scenario.obstacles):
            return self._base
        off, _ = self._movers(t)
        nc = self._base.circles.shape[0]
        return self._base.translated(off[:nc], off[nc : self._n_obs])

    def obstacles(self) -> ObstacleSet:
        """All obstacles (not inflated) at the current time."""
        return self.obstacles_at(self.time)

    def static_obstacles(self) -> ObstacleSet:
        """Only the non-moving obstacles (what a global planner may plan against)."""
        return self._static

    def velocities(self, t: float | None = None) -> Array:
        """(n_obstacles, 2) velocity (m/s) of each obstacle, in ObstacleSet order, at time ``t``.

        The velocity holds from ``t`` on until the next step boundary or wall reflection (the
        random walk redraws at boundaries; at a boundary the new step's velocity is returned).
        Static obstacles have zero velocity. Default ``t``: the current time.
        """
        _, vel = self._movers(self._check_t(t))
        return vel[: self._n_obs]

    def goal_at(self, t: float) -> Array:
        """Goal position (2,) at time ``t``."""
        off, _ = self._movers(self._check_t(t))
        return self._goal0 + off[self._n_obs]

    @property
    def goal(self) -> Array:
        """Goal position (2,) at the current time."""
        return self.goal_at(self.time)

    def goal_velocity(self, t: float | None = None) -> Array:
        """Goal velocity (2,) in m/s at time ``t`` (default: now)."""
        _, vel = self._movers(self._check_t(t))
        return vel[self._n_obs]

    def obstacle_positions_at(self, t: float) -> Array:
        """(n_obstacles, 2) reference positions in ObstacleSet order at time ``t``.

        Circles: centre; polygons: the initial vertex centroid (mean of vertices) moved along.
        """
        off, _ = self._movers(self._check_t(t))
        ref = np.array(
            [
                self.scenario.obstacles[k].center
                if self.scenario.obstacles[k].shape == "circle"
                else self.scenario.obstacles[k].vertices.mean(axis=0)
                for k in self.set_order
            ],
            dtype=np.float64,
        ).reshape(-1, 2)
        return ref + off[: self._n_obs]
