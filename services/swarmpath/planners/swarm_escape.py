"""Escape from a local minimum of the swarm local planner (``escape``; docs/planners.md,
"Escaping a local minimum").

The progress monitor (:meth:`Escape.stalled`) starts both rules of ``escape_plan``; the long-term
points and their use below are the ``"hulls"`` rule (the default before tree ``c36007d``); the
default ``"memory"`` follows the way on an occupancy memory instead
(:mod:`swarmpath.planners.swarm_memory`).

The swarm's aim is the shortest path to the goal in the *sensed* map, and that map remembers the
points of the last ``memory`` seconds only. Beside a long obstacle across the way (a thin wall
whose far side holds the goal, ``tests/data/thin_wall.json``) the part of the wall sensed a few
seconds ago is forgotten, unseen space is assumed free, and the known path flips between the
wall's two ends, or leads through its forgotten part: the robot creeps along the wall face.

:class:`Escape` is a progress monitor and a long-term map of static points:

* **Progress.** The record is the robot's least distance to the goal, renewed whenever the
  distance falls below it by more than ``escape_progress``. No new record for ``escape``
  seconds is a *stall*. The stall ends with the next new record, that is, when the robot is
  closer to the goal than anywhere before (the leave rule of Bug2: Lumelsky & Stepanov 1987).
  Each stall thus ends at least ``escape_progress`` closer to the goal than the one before, so
  there are finitely many.
* **Map.** Every scan's points that were not seen moving are kept, one per ``map_cell`` grid
  cell (the grid of the known path), for the whole run; cells where this scan sees motion are
  dropped. The number of cells is bounded by the world's area.
* **Escape.** During a stall the known shortest path (and so the aim) avoids these remembered
  points too: the robot follows the exact shortest path in everything it has sensed since the
  start (navigation with the free-space assumption: Koenig, Tovey & Smirnov, "Performance
  bounds for planning in unknown terrain", Artificial Intelligence 147, 2003). Static
  knowledge only grows, so the path no longer flips back to a way already seen blocked.

Only the aim changes: the candidates' feasibility, the repairs and every clearance check use
the recent points exactly as without the escape, so the escape cannot bring the robot closer to
anything than the planner allows. A run without a stall is the same as with ``escape = 0``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


class Escape:
    """The progress record and the static points remembered for a stall (see module docstring)."""

    def __init__(self, window: float, progress: float, cell: float) -> None:
        self.window = float(window)  # s without a new record: a stall (0: never)
        self.progress = float(progress)  # m: what counts as a new record
        self.cell = float(cell)
        self._record = np.inf
        self._record_time = 0.0
        self._keys = np.zeros(0, dtype=np.int64)
        self._points = np.zeros((0, 2))
        self.stalls = 0  # how many stalls began (for tests and traces)
        self._stalled = False

    def remember(self, points: Array, moving: NDArray[np.bool_]) -> None:
        """Add this scan's static points (one per cell, the first one seen is kept) and drop the
        cells of its moving ones."""
        if self.window <= 0 or not len(points):
            return
        keys = self._key(points)
        fresh = points[~moving]
        if len(fresh):
            both = np.concatenate([self._keys, keys[~moving]])
            _, first = np.unique(both, return_index=True)
            first = np.sort(first)
            self._keys = both[first]
            self._points = np.concatenate([self._points, fresh])[first]
        if moving.any():
            kept = ~np.isin(self._keys, keys[moving])
            self._keys, self._points = self._keys[kept], self._points[kept]

    def stalled(self, time: float, distance: float) -> bool:
        """Update the record with the robot's distance to the goal; True during a stall."""
        if self.window <= 0:
            return False
        if distance < self._record - self.progress or not np.isfinite(self._record):
            self._record, self._record_time = distance, time
        stalled = time - self._record_time > self.window
        if stalled and not self._stalled:
            self.stalls += 1
        self._stalled = stalled
        return stalled

    def points(self) -> Array:
        """The static points remembered so far."""
        return self._points

    def _key(self, points: Array) -> NDArray[np.int64]:
        # one integer per cell: 2**31 cells per axis are far more than any map has
        ij = np.floor(points / self.cell).astype(np.int64)
        return (ij[:, 0] << 32) + ij[:, 1]
