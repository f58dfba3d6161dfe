"""A scenario unfolding in time (:class:`WorldState`): obstacle and goal positions at any time,
reflected at the world's walls, random walks drawn on the scenario's step grid (the rules are in
the docstring of :mod:`swarmpath.world.scenario`). Pure numpy."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from swarmpath.world.geometry import (
    ObstacleSet,
)
from swarmpath.world.scenario_parts import Array, Motion, MotionSpec, RandomMotion, obstacle_set

if TYPE_CHECKING:
    from swarmpath.world.scenario import Scenario


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
        self._any_moving = any(o.is_moving for o in obs)  # else every snapshot is ``_base``

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
        if not self._any_moving:
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
