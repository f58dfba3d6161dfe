"""The steppable optimizer: state arrays shaped (runs, agents, dim), one iteration per ``step``.

Subclasses implement ``_initialize`` (draw and evaluate the first population) and ``_iterate`` (one
iteration of the algorithm). Every objective evaluation goes through :meth:`Optimizer.evaluate`,
which counts it and keeps the best point ever evaluated per run: that record, not an algorithm's
internal leader, is what ``best_fitness``/``best_position`` report (see docs/algorithms.md, COOT).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from swarmpath.optimizers.problem import Problem
from swarmpath.optimizers.streams import RunStreams
from swarmpath.registry import ParamValue, resolve_params

Array = NDArray[np.float64]


class ParameterError(ValueError):
    """A bad algorithm parameter; the message names it and lists what is valid."""


class Optimizer(ABC):
    #: Registered name (exact, as users type it).
    name: ClassVar[str]
    #: One line for catalogues.
    summary: ClassVar[str] = ""
    #: Paper and equation numbers.
    reference: ClassVar[str] = ""
    #: Parameter defaults; the keys are the only parameters accepted.
    defaults: ClassVar[Mapping[str, ParamValue]] = {}
    #: Allowed values for string-valued (choice) parameters.
    choices: ClassVar[Mapping[str, tuple[str, ...]]] = {}
    #: Smallest population the algorithm works with.
    min_agents: ClassVar[int] = 2
    #: Where the points it evaluates lie: ``"box"`` (every point inside the box: the
    #: conformance gate checks it), or a sentence saying where else and why (then shown, not
    #: checked).
    bound_rule: ClassVar[str] = "box"

    def __init__(
        self,
        problem: Problem,
        agents: int,
        iterations: int,
        streams: RunStreams,
        params: Mapping[str, Any] | None = None,
    ):
        if streams.runs != problem.runs:
            raise ValueError(f"{streams.runs} random streams for {problem.runs} runs")
        if agents < self.min_agents:
            raise ParameterError(f"{self.name} needs agents >= {self.min_agents}, got {agents}")
        if iterations < 1:
            raise ParameterError(f"iterations must be >= 1, got {iterations}")
        self.problem = problem
        self.N = int(agents)
        self.T = int(iterations)
        self.R = problem.runs
        self.d = problem.dim
        self.rng = streams
        self.p: dict[str, ParamValue] = self.resolve_params(params)
        self.t = 0  # iterations completed
        self.evaluations = np.zeros(self.R, dtype=np.int64)
        self.best_fitness = np.full(self.R, np.inf)
        self.best_position = np.zeros((self.R, self.d))
        self.lb = problem.lower[:, None, :]  # (R, 1, d): broadcasts over agents
        self.ub = problem.upper[:, None, :]
        self._initialized = False
        self._run_index = np.arange(self.R)
        self._full_bounds: dict[int, tuple[Array, Array]] = {}
        #: True once a masked evaluation happened (some computed points were not used).
        self.masked_evaluation = False
        #: Evaluations each run may count (None: no limit): points past it, in row order, count
        #: as not evaluated (+inf, not counted, never the best), so a run's record is that of
        #: its first ``max_evaluations`` evaluations (``--budget-evals``; optimizers.budget).
        self.max_evaluations: int | None = None

    # ----------------------------------------------------------------------------------- params
    @classmethod
    def resolve_params(cls, params: Mapping[str, Any] | None) -> dict[str, ParamValue]:
        merged = resolve_params(cls.name, cls.defaults, cls.choices, params, ParameterError)
        cls.check_params(merged)
        return merged

    @classmethod  # noqa: B027 - an optional hook, empty on purpose
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        """Range checks of a subclass; raise ParameterError naming the parameter."""

    # ---------------------------------------------------------------------------- stepping API
    def initialize(self) -> None:
        if self._initialized:
            raise RuntimeError("already initialized")
        self._initialize()
        self._initialized = True

    def step(self) -> None:
        """Run one iteration (initializing first if needed)."""
        if not self._initialized:
            self.initialize()
        if self.t >= self.T:
            raise RuntimeError(f"all {self.T} iterations are done")
        self.t += 1
        self._iterate()

    def expected_evaluations(self) -> tuple[int, int]:
        """(fewest, most) evaluations a run counts over all ``T`` iterations: by default the
        first population and one per agent per iteration, N (T + 1). An algorithm that spends
        more (or a number that varies by run) says so here; the conformance gate holds it to
        this (``swarmpath check optimizer``)."""
        n = self.N * (self.T + 1)
        return n, n

    @property
    def done(self) -> bool:
        return self.t >= self.T

    @abstractmethod
    def _initialize(self) -> None: ...

    @abstractmethod
    def _iterate(self) -> None:
        """One iteration; ``self.t`` is its 1-based index (1..T)."""

    # ----------------------------------------------------------------------------------- tools
    def evaluate(self, X: Array, mask: NDArray[np.bool_] | None = None) -> Array:
        """Objective at X (R, m, d) -> (R, m), counted; updates the best ever evaluated.

        With ``mask`` (R, m), only the masked points count as evaluated: the others get +inf and are
        not counted (for algorithms whose number of evaluations differs per agent).
        """
        return self.record(X, np.asarray(self.problem.objective(X, self.rng), dtype=float), mask)

    def record(self, X: Array, F: Array, mask: NDArray[np.bool_] | None = None) -> Array:
        """The bookkeeping of :meth:`evaluate` for values ``F`` (R, m) already computed at X:
        count them and update the best ever evaluated (first index wins ties)."""
        if self.max_evaluations is not None:
            mask = self._within_budget(X.shape[1], mask)
        if mask is not None:
            self.masked_evaluation = True
            F = np.where(mask, F, np.inf)
            self.evaluations += np.count_nonzero(mask, axis=1)
        else:
            self.evaluations += X.shape[1]
        nan = np.isnan(F)
        if nan.any():
            F = np.where(nan, np.inf, F)
        idx = np.argmin(F, axis=1)
        rows = self._run_index
        cand = F[rows, idx]
        better = cand < self.best_fitness
        if better.any():
            self.best_fitness = np.where(better, cand, self.best_fitness)
            self.best_position = np.where(better[:, None], X[rows, idx], self.best_position)
        return F

    def _within_budget(self, m: int, mask: NDArray[np.bool_] | None) -> NDArray[np.bool_] | None:
        """``mask`` narrowed to the points that still fit ``max_evaluations`` (None: all do)."""
        assert self.max_evaluations is not None
        counted = np.ones((self.R, m), dtype=bool) if mask is None else np.asarray(mask)
        remaining = self.max_evaluations - self.evaluations
        allowed = counted & (np.cumsum(counted, axis=1) <= remaining[:, None])
        if mask is None and allowed.all():
            return None
        return allowed

    def clip(self, X: Array) -> Array:
        return np.clip(X, self.lb, self.ub)

    def full_bounds(self, m: int) -> tuple[Array, Array]:
        """(lower, upper) spelled out as contiguous (R, m, d) arrays, cached per m.

        numpy 1.26 runs elementwise operations on equal-shaped contiguous operands much faster
        than on broadcast ones (which it copies through buffers): hot clipping uses these.
        """
        cached = self._full_bounds.get(m)
        if cached is None:
            shape = (self.R, m, self.d)
            cached = (
                np.ascontiguousarray(np.broadcast_to(self.lb, shape)),
                np.ascontiguousarray(np.broadcast_to(self.ub, shape)),
            )
            self._full_bounds[m] = cached
        return cached

    def clip_inplace(self, X: Array) -> Array:
        """Clip X (R, m, d) to the box in place and return it."""
        lower, upper = self.full_bounds(X.shape[1])
        np.maximum(X, lower, out=X)
        np.minimum(X, upper, out=X)
        return X

    def random_population(self, m: int | None = None) -> Array:
        """Uniform positions in the box: (R, m, d)."""
        m = self.N if m is None else m
        return self.lb + (self.ub - self.lb) * self.rng.random(m, self.d)
