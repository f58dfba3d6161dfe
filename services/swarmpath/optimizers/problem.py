"""A batch of minimisation problems, one per run, evaluated together.

The objective maps positions shaped (runs, m, dim) to values shaped (runs, m). Bounds are shaped
(runs, dim) so that each run may have its own box (the planners search around each robot).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from swarmpath.functions import BenchmarkFunction
from swarmpath.functions.transforms import random_rotation, rotates, shifts
from swarmpath.optimizers.streams import ROTATE, SHIFT, RunStreams, run_generator

Array = NDArray[np.float64]
Objective = Callable[[Array, RunStreams], Array]


@dataclass
class Problem:
    objective: Objective
    lower: Array  # (runs, dim)
    upper: Array  # (runs, dim)
    #: True when the objective's value at a point does not depend, to the last bit, on the other
    #: points evaluated with it (no matrix products, no draws from the streams): an optimizer may
    #: then evaluate points of a sequential sweep in one batch (HPO's ``_sweep``).
    rowwise: bool = False

    def __post_init__(self) -> None:
        self.lower = np.atleast_2d(np.asarray(self.lower, dtype=float))
        self.upper = np.atleast_2d(np.asarray(self.upper, dtype=float))
        if self.lower.shape != self.upper.shape:
            raise ValueError("lower and upper bounds must have the same shape (runs, dim)")
        if np.any(self.upper <= self.lower):
            raise ValueError("every upper bound must exceed its lower bound")

    @property
    def runs(self) -> int:
        return int(self.lower.shape[0])

    @property
    def dim(self) -> int:
        return int(self.lower.shape[1])

    @property
    def span(self) -> Array:
        return self.upper - self.lower


@dataclass
class BenchmarkProblem(Problem):
    """A registered function on its box for each run, optionally transformed per run
    (``transform``: none, shift, rotate, shift+rotate; see :mod:`swarmpath.functions.transforms`).
    The shift comes from the run's ``SHIFT`` stream, the rotation from its ``ROTATE`` stream, so
    a run's function does not depend on the batch, the algorithm or the other transform."""

    function: BenchmarkFunction | None = None
    shifts: Array | None = None  # (runs, dim) or None
    rotations: Array | None = None  # (runs, dim, dim) or None
    transform: str = "none"

    @classmethod
    def build(
        cls,
        function: BenchmarkFunction,
        dim: int,
        run_ids: list[int],
        seed: int,
        transform: str | bool = "none",
    ) -> BenchmarkProblem:
        """``transform`` True/False are the former ``shifted`` flag ("shift"/"none")."""
        if isinstance(transform, bool):
            transform = "shift" if transform else "none"
        runs = len(run_ids)
        box = function.bounds(dim)  # ValueError naming the function if dim does not fit
        lower = np.broadcast_to(box[0], (runs, dim)).copy()
        upper = np.broadcast_to(box[1], (runs, dim)).copy()
        moved = None
        if function.shift is not None:  # a function shifted by its caller keeps its shift
            moved = np.broadcast_to(function._shift_for(dim), (runs, dim)).copy()
            function = replace_shift(function)
        if shifts(transform):
            drawn = np.stack(
                [function.random_shift(dim, run_generator(seed, r, SHIFT)) for r in run_ids]
            )
            moved = drawn if moved is None else moved + drawn
        rotations = None
        if rotates(transform):
            rotations = np.stack(
                [random_rotation(dim, run_generator(seed, r, ROTATE)) for r in run_ids]
            )
        problem = cls(objective=_unset, lower=lower, upper=upper, function=function,
                      shifts=moved, rotations=rotations, transform=transform)
        problem.objective = problem._evaluate
        return problem

    def _evaluate(self, X: Array, streams: RunStreams) -> Array:
        f = self.function
        assert f is not None
        x = X
        if self.rotations is not None:
            # x* + Q (x - m), m = x* + shift the minimiser: rotation about the optimum
            m = self.optimum()
            x = np.matmul(X - m[:, None, :], self.rotations.transpose(0, 2, 1))
            x += f.base_optimum(self.dim)
        elif self.shifts is not None:
            x = X - self.shifts[:, None, :]
        if f.wrap_shifted and (self.shifts is not None or self.rotations is not None):
            lower, upper = self.lower[:, None, :], self.upper[:, None, :]
            x = np.mod(x - lower, upper - lower) + lower
        value = f.kernel(x)
        if f.noisy:
            value = value + streams.random(*value.shape[1:])
        return value

    def optimum(self) -> Array:
        """(runs, dim) minimisers."""
        f = self.function
        assert f is not None
        base = np.broadcast_to(f.base_optimum(self.dim), (self.runs, self.dim)).copy()
        return base if self.shifts is None else base + self.shifts


@dataclass
class StackedProblem(Problem):
    """Several benchmark problems' runs stacked into one batch, rows in the order of ``parts``.

    An optimizer steps every row the same way whatever problem the row belongs to, and each row
    draws from its own run's stream, so a run computed in a stack gives the numbers it gives in
    its own batch; only the objective differs per row block. Noisy functions (F7) draw from the
    streams inside the objective, which would move the other rows' streams: they cannot be
    stacked with anything.
    """

    parts: tuple[BenchmarkProblem, ...] = ()

    @classmethod
    def of(cls, parts: list[BenchmarkProblem]) -> StackedProblem:
        if not parts:
            raise ValueError("nothing to stack")
        if len(parts) > 1 and any(p.function is not None and p.function.noisy for p in parts):
            raise ValueError("a noisy function cannot share a batch with other problems")
        problem = cls(
            objective=_unset,
            lower=np.concatenate([p.lower for p in parts]),
            upper=np.concatenate([p.upper for p in parts]),
            parts=tuple(parts),
        )
        problem.objective = problem._evaluate
        return problem

    def _evaluate(self, X: Array, streams: RunStreams) -> Array:
        out = np.empty(X.shape[:2])
        start = 0
        for part in self.parts:
            stop = start + part.runs
            out[start:stop] = part.objective(X[start:stop], streams)
            start = stop
        return out


def replace_shift(function: BenchmarkFunction) -> BenchmarkFunction:
    """``function`` without its own shift (the problem carries it per run)."""
    return replace(function, shift=None)


def _unset(X: Array, streams: RunStreams) -> Array:  # replaced in BenchmarkProblem.build
    raise RuntimeError("objective not set")
