"""Why a run failed: one class per failed run, read from the executed trajectory and the truth.

The reason a run ended (``RunOutcome.reason``: "time limit", "step limit", "planner gave up:
...") says when it stopped, not what the robot was doing. :func:`classify` says that, from
what the simulator knows (never from the planner):

* ``collision`` - the robot touched an obstacle (the product's first rule; whatever else);
* ``gave-up`` - the planner returned no move (its words are in the reason);
* ``error`` - the planner raised (set by the callers that catch it);
* ``short-of-goal`` - the run ended within the goal tolerance of a static goal without getting
  onto it (the last straight stretch was never free);
* a time or step limit, by the robot's progress toward the goal: the distance still to go,
  ``d(t)``, along free space on the static map (:class:`~swarmpath.planners.cost_to_go.
  CostToGo`, cells keeping the robot radius) or, for a moving goal or where that field has no
  finite value, in a straight line:

  - ``progressing`` - the least ``d`` of the last :data:`WINDOW_SHARE` of the run (at least
    :data:`MIN_WINDOW` s, at most half the run) is :data:`PROGRESS` below the least before it:
    the budget ran out while the robot was still getting closer;
  - else the robot is *stuck* from the first moment it came within :data:`PROGRESS` of its
    least ``d`` to the end, and over that stretch:

    - ``blocked-by-mover`` - a moving obstacle's body gap was at most :data:`MOVER_NEAR` in at
      least half of the sampled moments;
    - ``boxed-in`` - it drove less than :data:`BOXED` (at least 4 robot radii): it found no move;
    - ``oscillating`` - it drove more but stayed within :data:`LOCAL` (at least 4 radii) of the
      stretch's centroid: back and forth in a local minimum;
    - ``wandering`` - it went farther without getting closer (dead ends, detours).

``detail`` says where and for how long (docs/planners.md, "Why runs fail").
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from swarmpath.failure_classes import FAILURE_CLASSES, count_classes
from swarmpath.world.geometry import ObstacleSet

Array = NDArray[np.float64]

#: m: a new least distance to the goal counts as progress when it is at least this much lower.
PROGRESS = 0.5
#: The last share of the run (simulated time) in which progress means ``progressing``...
WINDOW_SHARE = 0.1
#: ... and that window's least length, s.
MIN_WINDOW = 30.0
#: m driven while stuck below which the robot is boxed in (at least 4 robot radii).
BOXED = 1.0
#: m from the stuck stretch's centroid within which it oscillates (at least 4 robot radii).
LOCAL = 2.0
#: m of body gap to a moving obstacle that counts as being held up by it.
MOVER_NEAR = 0.5
#: moments sampled (evenly in time) to measure a stuck stretch's distance to the movers.
MOVER_SAMPLES = 200


class Failure(NamedTuple):
    kind: str  # one of FAILURE_CLASSES
    detail: str


def _xy(p: Array) -> str:
    return f"({p[0]:.2f}, {p[1]:.2f})"


def classify(
    path: Array,
    reason: str,
    collisions: int,
    radius: float,
    to_go: Array,
    along_free_space: bool,
    goal_moves: bool,
    goal_tolerance: float,
    end_distance: float,
    mover_gap: Callable[[float, Array], float] | None = None,
) -> Failure:
    """The class of a failed run (see the module docstring).

    ``path`` rows [x, y, t]; ``to_go`` the distance still to go at each row (``along_free_space``
    says which measure, for the detail); ``end_distance`` the straight distance from the last
    row to the goal (what the acceptance radius ``goal_tolerance`` is measured with);
    ``mover_gap(t, xy)`` the least body gap from the robot at ``xy`` to the moving obstacles at
    time ``t`` (None: nothing moves)."""
    if collisions:
        return Failure("collision", f"{collisions} colliding steps")
    if reason.startswith("planner gave up"):
        return Failure("gave-up", reason.removeprefix("planner gave up: "))
    if reason.startswith("internal error"):
        return Failure("error", reason)
    end = path[-1]
    if not goal_moves and end_distance <= goal_tolerance + 1e-9:
        return Failure("short-of-goal", f"ended {end_distance:.3f} m from the goal, at "
                                        f"{_xy(end)}")
    measure = "along free space" if along_free_space else "in a straight line"
    t = path[:, 2]
    duration = float(t[-1])
    window = min(max(MIN_WINDOW, WINDOW_SHARE * duration), 0.5 * duration)
    late = t >= duration - window
    best = float(np.min(to_go))
    if late.any() and (~late).any():
        before, after = float(np.min(to_go[~late])), float(np.min(to_go[late]))
        if after < before - PROGRESS:
            return Failure("progressing", f"{before - after:.1f} m closer in the last "
                                          f"{window:.0f} s; {to_go[-1]:.1f} m to go ({measure})")
    first = int(np.argmax(to_go <= best + PROGRESS))
    stuck = path[first:]
    since = float(stuck[0, 2])
    driven = float(np.sum(np.hypot(*np.diff(stuck[:, :2], axis=0).T))) if len(stuck) > 1 else 0.0
    centre = stuck[:, :2].mean(axis=0)
    spread = float(np.max(np.hypot(*(stuck[:, :2] - centre).T)))
    where = (f"no progress for {duration - since:.0f} s, {best:.1f} m from the goal "
             f"({measure}); {driven:.1f} m driven within {spread:.2f} m of {_xy(centre)}")
    if mover_gap is not None and len(stuck):
        rows = np.unique(np.linspace(0, len(stuck) - 1, min(MOVER_SAMPLES, len(stuck)))
                         .astype(int))
        near = [mover_gap(float(stuck[i, 2]), stuck[i, :2]) <= MOVER_NEAR for i in rows]
        if 2 * sum(near) >= len(near):
            return Failure("blocked-by-mover", f"{where}; a moving obstacle within "
                                               f"{MOVER_NEAR} m in {sum(near)} of {len(near)} "
                                               "moments")
    if driven < max(BOXED, 4 * radius):
        return Failure("boxed-in", where)
    if spread <= max(LOCAL, 4 * radius):
        return Failure("oscillating", where)
    return Failure("wandering", where)


def movers_of(obstacles: ObstacleSet, moving: NDArray[np.bool_]) -> ObstacleSet:
    """The entries of ``obstacles`` (circles first, then polygons) that ``moving`` marks."""
    k = obstacles.circles.shape[0]
    circles = obstacles.circles[moving[:k]]
    polygons = tuple(p for p, m in zip(obstacles.polygons, moving[k:], strict=True) if m)
    return ObstacleSet(circles, polygons)


def along_free_space(values: Array) -> Array | None:
    """A cost-to-go series with its few non-finite values (a pose whose grid neighbourhood is
    all blocked at the field's resolution, beside a wall) taken from the nearest finite one in
    time; None when fewer than nine in ten are finite (then the straight distance is used)."""
    ok = np.isfinite(values)
    if not ok.any() or ok.mean() < 0.9:
        return None
    idx = np.flatnonzero(ok)
    nearest = idx[np.clip(np.searchsorted(idx, np.arange(len(values))), 0, len(idx) - 1)]
    return np.where(ok, values, values[nearest])


__all__ = ["FAILURE_CLASSES", "Failure", "along_free_space", "classify", "count_classes",
           "movers_of"]
