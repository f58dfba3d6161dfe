"""Algorithms whose generations are not the study's agents: iterations as evaluation quanta.

The frame counts a run in iterations of ``agents`` evaluations (:class:`Optimizer`): one curve
point per iteration, ``agents (T + 1)`` evaluations in all. CMA-ES samples lambda points per
generation (and doubles lambda at each IPOP restart), L-SHADE and jSO shrink their population
as the evaluations go by: their generations have sizes of their own. :class:`Generational` maps
them onto the frame without changing either:

* a run keeps a queue, the points of its current generation; the algorithm fills it
  (:meth:`Generational._begin`) and is told when every point of it has a value
  (:meth:`Generational._end`), exactly as it would be without the frame;
* the first population and every iteration evaluate the next ``agents`` points of each run's
  queue: a generation larger than ``agents`` spans several iterations, a smaller one ends inside
  an iteration and the next generation fills the rest of that iteration's quantum;
* so each run counts exactly ``agents`` evaluations per iteration (``agents (T + 1)`` in all,
  fewer only for a run the algorithm stopped), the curve point of iteration t is the best of its
  first ``agents (t + 1)`` evaluations (the fixed-budget view of COCO and IOHprofiler), and the
  budget the algorithm plans with (L-SHADE's MAX_NFE) is ``agents (T + 1)``, or
  ``max_evaluations`` when a study gives fewer (``--budget-evals``).

Reproducibility: a run's queue is consumed in segments that end where its own generations end,
so which points are evaluated together depends only on the run itself. Every call of the
objective is at least two points wide: a matrix product of one row takes another BLAS path
than two or more, whose rows come out the same at any width (measured on the suites).
"""

from __future__ import annotations

from abc import abstractmethod

import numpy as np
from numpy.typing import NDArray

from swarmpath.optimizers.base import Array, Optimizer

#: The narrowest objective call (see the module docstring).
MIN_WIDTH = 2


class Generational(Optimizer):
    """An :class:`Optimizer` whose subclass works in generations of any size per run.

    A subclass implements :meth:`_begin` (the first queues) and :meth:`_end` (a finished
    generation of some runs: update, then put their next generation in the queue, or stop them).
    ``self.queue`` (R, M, d) holds the points, ``self.queue_size`` (R,) how many of them make the
    generation (0: the run has stopped), ``self.queue_values`` (R, M) their values as they come.
    """

    min_agents = 1

    def _initialize(self) -> None:
        cap = self.N * (self.T + 1)
        #: the evaluations this run plans with (``agents (T + 1)``, or a smaller study budget)
        self.planned = cap if self.max_evaluations is None else min(cap, self.max_evaluations)
        self.queue = np.zeros((self.R, 0, self.d))
        self.queue_size = np.zeros(self.R, dtype=np.int64)
        self.queue_values = np.zeros((self.R, 0))
        self.queue_done = np.zeros(self.R, dtype=np.int64)
        #: evaluations of each run since its start, as the algorithm counts them
        self.spent = np.zeros(self.R, dtype=np.int64)
        self._begin()
        self._consume()

    def _iterate(self) -> None:
        self._consume()

    def expected_evaluations(self) -> tuple[int, int]:
        """``agents (T + 1)``; a subclass whose runs may stop early lowers the fewest."""
        n = self.N * (self.T + 1)
        return n, n

    @abstractmethod
    def _begin(self) -> None:
        """Fill the first queues (:meth:`put`)."""

    @abstractmethod
    def _end(self, runs: NDArray[np.int64]) -> None:
        """The generation of ``runs`` is evaluated (``queue_values``): update them and
        :meth:`put` their next generation (or :meth:`stop` them)."""

    # ------------------------------------------------------------------------------- queues
    def put(self, runs: NDArray[np.int64], points: Array) -> None:
        """The next generation of ``runs``: ``points`` (len(runs), m, d)."""
        m = points.shape[1]
        if m > self.queue.shape[1]:
            grown = np.zeros((self.R, m, self.d))
            grown[:, : self.queue.shape[1]] = self.queue
            self.queue = grown
            values = np.zeros((self.R, m))
            values[:, : self.queue_values.shape[1]] = self.queue_values
            self.queue_values = values
        self.queue[runs, :m] = points
        self.queue_size[runs] = m
        self.queue_done[runs] = 0

    def stop(self, runs: NDArray[np.int64]) -> None:
        """``runs`` evaluate nothing more (their curves stay flat)."""
        self.queue_size[runs] = 0
        self.queue_done[runs] = 0

    def _consume(self) -> None:
        """Evaluate the next ``agents`` points of every run's queue (see the module doc)."""
        quota = np.full(self.R, self.N, dtype=np.int64)
        rows = self._run_index
        while True:
            take = np.minimum(quota, self.queue_size - self.queue_done)
            width = int(take.max())
            if width == 0:
                return
            cols = np.arange(max(width, MIN_WIDTH))
            # runs with less to take pad with points of their own queue (valid, never counted)
            last = np.maximum(self.queue_size - 1, 0)
            index = np.minimum(self.queue_done[:, None] + cols, last[:, None])
            used = cols[None, :] < take[:, None]
            values = self.evaluate(self.queue[rows[:, None], index],
                                   None if used.all() else used)
            r, c = np.nonzero(used)
            self.queue_values[r, index[r, c]] = values[r, c]
            self.queue_done += take
            self.spent += take
            quota -= take
            ended = np.flatnonzero((self.queue_done == self.queue_size) & (self.queue_size > 0))
            if ended.size:
                self._end(ended)
