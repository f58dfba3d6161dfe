"""``minimize``: run an optimizer on a benchmark function for a batch of seeded runs."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmpath.functions import BenchmarkFunction, get_function
from swarmpath.optimizers.base import Optimizer, ParameterError
from swarmpath.optimizers.problem import BenchmarkProblem, Problem
from swarmpath.optimizers.registry import get_optimizer
from swarmpath.optimizers.streams import RunStreams

Array = NDArray[np.float64]

MAX_DIM = 1000
MAX_AGENTS = 1000
MAX_ITERATIONS = 100_000
#: Coordinates per population array of one chunk of runs (about 110 runs of 30 agents x 30 dims):
#: measured fastest per run on the project machine; larger batches are split (see ``minimize``).
CHUNK_ELEMENTS = 100_000


@dataclass
class Result:
    algorithm: str
    function: str
    dim: int
    agents: int
    iterations: int
    seed: int
    run_ids: list[int]
    best_fitness: Array  # (runs,)
    best_position: Array  # (runs, dim)
    curve: Array  # (runs, iterations): best-so-far after each iteration
    evaluations: NDArray[np.int64]  # (runs,)
    seconds: float
    shifts: Array | None = None  # (runs, dim) when shifted
    params: dict[str, Any] | None = None


def create(
    algorithm: str,
    problem: Problem,
    agents: int,
    iterations: int,
    streams: RunStreams,
    params: Mapping[str, Any] | None = None,
) -> Optimizer:
    """A steppable optimizer for any :class:`Problem` (planners and workers use this)."""
    cls = get_optimizer(algorithm)
    return cls(problem, agents, iterations, streams, params)


def _check_sizes(dim: int, agents: int, iterations: int) -> None:
    for label, value, top in (
        ("dim", dim, MAX_DIM),
        ("agents", agents, MAX_AGENTS),
        ("iterations", iterations, MAX_ITERATIONS),
    ):
        integral = isinstance(value, int | np.integer) and not isinstance(value, bool)
        if not integral or not 1 <= value <= top:
            raise ParameterError(f"{label} must be an integer in [1, {top}], got {value!r}")


def minimize(
    algorithm: str,
    function: str | BenchmarkFunction,
    dim: int = 30,
    agents: int = 30,
    iterations: int = 500,
    runs: int = 30,
    seed: int = 1,
    params: Mapping[str, Any] | None = None,
    shifted: bool = False,
    run_ids: Sequence[int] | None = None,
    on_iteration: Callable[[Optimizer], None] | None = None,
) -> Result:
    """Minimise ``function`` with ``algorithm`` for runs 0..runs-1 (or the given ``run_ids``).

    Run r depends only on (algorithm, function, dim, agents, iterations, params, shifted, seed, r).
    Batches larger than about ``CHUNK_ELEMENTS`` coordinates per population run as several
    optimizers stepped in turn; ``on_iteration`` is still called once per iteration, after every
    chunk made it, with the last chunk's optimizer.
    """
    fn = get_function(function) if isinstance(function, str) else function
    _check_sizes(dim, agents, iterations)
    ids = list(range(runs)) if run_ids is None else [int(r) for r in run_ids]
    if not ids:
        raise ParameterError("runs must be >= 1")
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ParameterError(f"seed must be a non-negative integer, got {seed!r}")
    cls = get_optimizer(algorithm)
    started = time.perf_counter()
    # Large batches run as chunks of about CHUNK_ELEMENTS coordinates per population array,
    # stepped in turn every iteration: the arrays of a step stay in the CPU caches. Runs are
    # independent and each has its own streams, so chunking changes no number.
    size = max(1, CHUNK_ELEMENTS // (agents * dim))
    chunks = [ids[i : i + size] for i in range(0, len(ids), size)]
    problems = [BenchmarkProblem.build(fn, dim, c, int(seed), shifted) for c in chunks]
    opts = [
        cls(pr, agents, iterations, RunStreams.for_runs(int(seed), c), params)
        for pr, c in zip(problems, chunks, strict=True)
    ]
    spans = [slice(i, i + len(c)) for i, c in zip(range(0, len(ids), size), chunks, strict=True)]
    curve = np.empty((len(ids), iterations))
    for opt in opts:
        opt.initialize()
    for i in range(iterations):
        for opt, span in zip(opts, spans, strict=True):
            opt.step()
            curve[span, i] = opt.best_fitness
        if on_iteration is not None:
            on_iteration(opts[-1])
    shifts = None if problems[0].shifts is None else np.concatenate([pr.shifts for pr in problems])
    return Result(
        algorithm=cls.name,
        function=fn.name,
        dim=dim,
        agents=agents,
        iterations=iterations,
        seed=int(seed),
        run_ids=ids,
        best_fitness=np.concatenate([opt.best_fitness for opt in opts]),
        best_position=np.concatenate([opt.best_position for opt in opts]),
        curve=curve,
        evaluations=np.concatenate([opt.evaluations for opt in opts]),
        seconds=time.perf_counter() - started,
        shifts=shifts,
        params=dict(opts[0].p),
    )
