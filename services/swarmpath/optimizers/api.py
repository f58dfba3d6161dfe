"""``minimize``: run an optimizer on a benchmark function for a batch of seeded runs."""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from swarmpath.functions import BenchmarkFunction, get_function
from swarmpath.functions.transforms import TRANSFORMS, shifts
from swarmpath.optimizers.base import Optimizer, ParameterError
from swarmpath.optimizers.problem import BenchmarkProblem, Problem, StackedProblem
from swarmpath.optimizers.registry import get_optimizer
from swarmpath.optimizers.streams import RunStreams

Array = NDArray[np.float64]

MAX_DIM = 1000
MAX_AGENTS = 1000
MAX_ITERATIONS = 100_000
#: Coordinates per population array of one chunk of runs (about 110 runs of 30 agents x 30 dims):
#: measured fastest per run on the project machine; larger batches are split (see ``minimize``).
CHUNK_ELEMENTS = 100_000
#: Ways of computing a study: ``numpy`` is the reference; ``numba`` runs the compiled kernels of
#: :mod:`swarmpath.optimizers.compiled`; ``auto`` (the default) runs the kernels where numba is
#: installed and the study has kernels that give the reference's numbers to the last bit (every
#: kernel does: tolerance 0.0), compiled already (:mod:`.compiled.ready`), numpy otherwise
#: (:func:`resolve_backend`). Each Result records the backend that computed it.
BACKENDS: tuple[str, ...] = ("auto", "numpy", "numba")
#: The backends that compute (``auto`` picks one of them): a planner's ``backend`` parameter.
COMPUTING_BACKENDS: tuple[str, ...] = ("numpy", "numba")


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
    transform: str = "none"
    #: How the numbers were computed (``BACKENDS``) and the largest relative difference from the
    #: numpy reference that backend allows (0.0: equal to the last bit).
    backend: str = "numpy"
    tolerance: float = 0.0
    #: CPU seconds of the computing thread (:func:`time.thread_time`, as a map run's
    #: ``RunOutcome.cpu_seconds``), shared among the functions like ``seconds``: beside the wall
    #: time, what the runs cost whatever else the machine does. None: not measured (a Result
    #: made elsewhere). A timing: never part of a run's identity or of a rerun's comparison.
    cpu_seconds: float | None = None


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
    on_iteration: Callable[[Optimizer | None], None] | None = None,
    chunk_elements: int | None = None,
    transform: str | None = None,
    backend: str = "auto",
    *,
    max_evaluations: int | None = None,
) -> Result:
    """Minimise ``function`` with ``algorithm`` for runs 0..runs-1 (or the given ``run_ids``).

    ``transform`` (``none``, ``shift``, ``rotate``, ``shift+rotate``; see
    :mod:`swarmpath.functions.transforms`) moves and/or turns each run's function with numbers
    drawn from that run's own streams; ``shifted=True`` is the former spelling of
    ``transform="shift"``. Run r depends only on (algorithm, function, dim, agents, iterations,
    params, transform, seed, r).
    Batches larger than about ``chunk_elements`` coordinates per population (default
    ``CHUNK_ELEMENTS``; 0: never split) run as several optimizers stepped in turn;
    ``on_iteration`` is still called once per iteration, after every chunk made it, with the last
    chunk's optimizer. Chunking changes no number. ``backend``: see :func:`minimize_many`.
    """
    return minimize_many(
        algorithm, [function], dim, agents, iterations, runs, seed, params, shifted, run_ids,
        on_iteration, chunk_elements, transform, backend, max_evaluations=max_evaluations,
    )[0]


def minimize_many(
    algorithm: str,
    functions: Sequence[str | BenchmarkFunction],
    dim: int = 30,
    agents: int = 30,
    iterations: int = 500,
    runs: int = 30,
    seed: int = 1,
    params: Mapping[str, Any] | None = None,
    shifted: bool = False,
    run_ids: Sequence[int] | None = None,
    on_iteration: Callable[[Optimizer | None], None] | None = None,
    chunk_elements: int | None = None,
    transform: str | None = None,
    backend: str = "auto",
    *,
    function_runs: Sequence[Sequence[int]] | None = None,
    max_evaluations: int | None = None,
) -> list[Result]:
    """``minimize`` for several functions at once: one :class:`Result` per function, in order.

    Every result equals ``minimize(algorithm, function, ...)`` with the same arguments, run for
    run. The functions' runs are stacked into one batch (:class:`StackedProblem`), chunked like
    one function's runs: fewer, larger array operations per iteration (on two threads, the ICOOT
    paper's Table 2 takes about a fifth less time stacked: docs/benchmarks.md). A noisy function
    (F7) is never stacked with another. ``seconds`` of each result is the call's wall time
    shared among the functions in proportion to their runs; ``cpu_seconds`` the call's CPU
    time of this thread, shared the same way.

    ``chunk_elements``: see :func:`minimize`. One thread runs fastest with the default; threads
    sharing the process run faster with larger chunks (fewer numpy calls, so fewer hand-offs of
    the GIL for the same work: docs/benchmarks.md, Table 2).

    ``backend="auto"`` (the default) is ``"numba"`` when :func:`resolve_backend` finds kernels
    for the whole study and they are compiled (in this process, or in the tree's numba cache:
    :mod:`swarmpath.optimizers.compiled.ready`), else ``"numpy"``: the same numbers either way,
    faster where it can. Kernels not compiled yet are compiled by a background process
    meanwhile, never in this call.
    ``backend="numba"`` computes each run with its algorithm's compiled kernel
    (:mod:`swarmpath.optimizers.compiled`), the same numbers as the reference (``"numpy"``)
    within the kernel's ``tolerance`` (recorded in each Result; 0.0 is equal to the last bit). An
    algorithm, transform, function or parameter without a kernel is a ParameterError naming it,
    never a fallback. ``on_iteration`` is then called ``iterations`` times in all as runs finish,
    with ``None``; ``chunk_elements`` does not apply.

    ``function_runs``: the run ids of each function (one list per entry of ``functions``, which
    may then name a function more than once), instead of the same ``runs``/``run_ids`` for all;
    a service worker stacks the leases of several cells this way. Each result's runs are still
    those of ``minimize(algorithm, function, ..., run_ids=its runs)``, number for number.

    ``max_evaluations``: no run counts an evaluation past this many (the field's budget:
    :mod:`swarmpath.optimizers.budget` picks the iterations that spend it). On ``numba`` the
    kernels give the same numbers under it where they can (the cap cannot bind, or the kernel
    counts it: ``compiled.run.check_budget``), else ParameterError; ``auto`` then runs numpy.
    """
    if backend not in BACKENDS:
        raise ParameterError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
    kind = resolve_transform(shifted, transform)
    fns = [get_function(f) if isinstance(f, str) else f for f in functions]
    if not fns:
        raise ParameterError("functions must name at least one function")
    _check_sizes(dim, agents, iterations)
    for fn in fns:
        try:
            fn.check_study(dim, kind)
        except ValueError as exc:
            raise ParameterError(str(exc)) from None
    if function_runs is None:
        ids = list(range(runs)) if run_ids is None else [int(r) for r in run_ids]
        cell_ids = [ids] * len(fns)
    else:
        cell_ids = [[int(r) for r in rs] for rs in function_runs]
        if len(cell_ids) != len(fns):
            raise ParameterError(f"function_runs must have one list per function ({len(fns)}), "
                                 f"got {len(cell_ids)}")
    if not all(cell_ids):
        raise ParameterError("runs must be >= 1")
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ParameterError(f"seed must be a non-negative integer, got {seed!r}")
    elements = CHUNK_ELEMENTS if chunk_elements is None else chunk_elements
    if isinstance(elements, bool) or not isinstance(elements, int | np.integer) or elements < 0:
        raise ParameterError(f"chunk_elements must be an integer >= 0, got {elements!r}")
    cls = get_optimizer(algorithm)
    asked = backend
    backend = _resolve(backend, cls.name, fns, kind, params,
                       _Budget(max_evaluations, agents, iterations, dim))
    if backend == "numba" and asked == "auto" and not _compiled_now(cls.name, fns):
        backend = "numpy"  # the same numbers, no compile in this call
    if backend == "numba":  # run by run: one call per distinct run list, progress spread
        if all(ids == cell_ids[0] for ids in cell_ids):
            groups = [(fns, cell_ids[0])]
        else:
            groups = [([fn], ids) for fn, ids in zip(fns, cell_ids, strict=True)]
        hook = _spread(on_iteration, iterations, iterations * len(groups))
        return [
            res for group, ids in groups for res in _minimize_compiled(
                cls.name, group, dim, agents, iterations, ids, int(seed), params, kind, hook,
                max_evaluations)
        ]
    started, cpu_started = time.perf_counter(), time.thread_time()
    # Large batches run as chunks of about ``elements`` coordinates per population array,
    # stepped in turn every iteration: the arrays of a step stay in the CPU caches. Runs are
    # independent and each has its own streams, so chunking changes no number.
    total = sum(len(ids) for ids in cell_ids)
    size = max(1, elements // (agents * dim)) if elements else total
    chunks = _chunk_rows(fns, cell_ids, size)
    problems = [_chunk_problem(chunk, dim, int(seed), kind) for chunk in chunks]
    opts = [
        cls(pr, agents, iterations, RunStreams.for_runs(int(seed), [r for _, r in c]), params)
        for pr, c in zip(problems, chunks, strict=True)
    ]
    bounds = np.cumsum([0] + [len(c) for c in chunks])
    spans = [slice(int(a), int(b)) for a, b in itertools.pairwise(bounds)]
    curve = np.empty((int(bounds[-1]), iterations))
    for opt in opts:
        opt.max_evaluations = max_evaluations
        opt.initialize()
    for i in range(iterations):
        for opt, span in zip(opts, spans, strict=True):
            opt.step()
            curve[span, i] = opt.best_fitness
        if on_iteration is not None:
            on_iteration(opts[-1])
    seconds = time.perf_counter() - started
    cpu_seconds = time.thread_time() - cpu_started
    best = np.concatenate([opt.best_fitness for opt in opts])
    position = np.concatenate([opt.best_position for opt in opts])
    evaluations = np.concatenate([opt.evaluations for opt in opts])
    shifts = None
    if all(part.shifts is not None for pr in problems for part in _parts(pr)):
        shifts = np.concatenate([part.shifts for pr in problems for part in _parts(pr)])
    offsets = np.cumsum([0] + [len(ids) for ids in cell_ids])
    results = []
    for k, (fn, ids) in enumerate(zip(fns, cell_ids, strict=True)):
        rows = slice(int(offsets[k]), int(offsets[k + 1]))  # function-major, as the chunks keep
        results.append(
            Result(
                algorithm=cls.name,
                function=fn.name,
                dim=dim,
                agents=agents,
                iterations=iterations,
                seed=int(seed),
                run_ids=list(ids),
                best_fitness=fn.report(best[rows]),
                best_position=position[rows].copy(),
                curve=fn.report(curve[rows]),
                evaluations=evaluations[rows].copy(),
                seconds=seconds * len(ids) / total,
                cpu_seconds=cpu_seconds * len(ids) / total,
                shifts=None if shifts is None else shifts[rows].copy(),
                params=dict(opts[0].p),
                transform=kind,
            )
        )
    return results


def resolve_backend(
    backend: str,
    algorithm: str,
    functions: Sequence[str | BenchmarkFunction],
    transform: str = "none",
    params: Mapping[str, Any] | None = None,
    max_evaluations: int | None = None,
    *,
    agents: int = 30,
    iterations: int = 500,
    dim: int = 30,
) -> str:
    """The backend that computes a study: ``backend`` itself unless it is ``"auto"``, which is
    ``"numba"`` when numba is installed and the study has kernels equal to the reference to the
    last bit (the algorithm with these ``params`` and ``transform``, each function, and under
    ``max_evaluations`` with these ``agents``, ``iterations`` and ``dim``:
    ``compiled.run.check_budget``), else ``"numpy"``. Never an error for ``"auto"``: what the
    kernels do not cover runs on the reference. Whether they are compiled yet is not asked:
    until they are, ``minimize_many``'s auto runs the reference (the same numbers)."""
    if backend not in BACKENDS:
        raise ParameterError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
    fns = [get_function(f) if isinstance(f, str) else f for f in functions]
    return _resolve(backend, get_optimizer(algorithm).name, fns, transform, params,
                    _Budget(max_evaluations, agents, iterations, dim))


class _Budget(NamedTuple):
    """An evaluation budget and the run shape it is spent in (``check_budget``'s arguments)."""

    evaluations: int | None
    agents: int
    iterations: int
    dim: int


def _resolve(backend: str, algorithm: str, fns: Sequence[BenchmarkFunction], transform: str,
             params: Mapping[str, Any] | None, budget: _Budget) -> str:
    if backend != "auto":
        return backend
    try:
        from swarmpath.optimizers.compiled.run import check_budget, check_function, kernel_for
        from swarmpath.optimizers.compiled.run import check_study as check
    except ImportError:  # numba missing or broken: the reference runs everything
        return "numpy"
    try:
        check(algorithm, params, transform)
        for fn in fns:
            check_function(fn)
        kernel = kernel_for(algorithm, params, transform)[0]
        check_budget(algorithm, params, budget.agents, budget.iterations, budget.dim,
                     budget.evaluations)
    except ParameterError:
        return "numpy"
    return "numba" if kernel.tolerance == 0.0 else "numpy"


def _compiled_now(algorithm: str, fns: Sequence[BenchmarkFunction]) -> bool:
    """Whether backend "auto" runs the kernels of a study they cover now: its kernel and
    objectives are compiled (in this process, or in the tree's cache by any process);
    otherwise they are asked for in the background (:mod:`swarmpath.optimizers.compiled.ready`)
    and the reference runs."""
    from swarmpath.optimizers.compiled.ready import ready_for_auto, study_pieces

    return ready_for_auto(study_pieces(algorithm, fns))


def check_backend(
    backend: str,
    algorithms: Sequence[str],
    transform: str = "none",
    params: Mapping[str, Mapping[str, Any]] | None = None,
    functions: Sequence[str] = (),
) -> None:
    """ParameterError unless every algorithm runs on ``backend`` with ``transform`` and its
    ``params`` (per algorithm), and every one of ``functions`` has a kernel there: what
    ``minimize_many`` would refuse, checked before a study."""
    if backend not in BACKENDS:
        raise ParameterError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
    if backend != "numba":  # the reference, or auto (which falls back to it)
        return
    try:
        from swarmpath.optimizers.compiled.run import check_study
    except ImportError as exc:
        raise ParameterError(
            f"backend 'numba' needs numba (pip install 'swarmpath[fast]'): {exc}"
        ) from None
    for algorithm in algorithms:
        check_study(algorithm, (params or {}).get(algorithm), transform)
    from swarmpath.optimizers.compiled.run import check_function

    for name in functions:
        check_function(get_function(name))


def _minimize_compiled(
    algorithm: str,
    fns: list[BenchmarkFunction],
    dim: int,
    agents: int,
    iterations: int,
    ids: list[int],
    seed: int,
    params: Mapping[str, Any] | None,
    kind: str,
    on_iteration: Callable[[Optimizer | None], None] | None,
    max_evaluations: int | None,
) -> list[Result]:
    try:  # numba is optional and never imported by the reference path
        from swarmpath.optimizers.compiled.run import minimize_compiled
    except ImportError as exc:
        raise ParameterError(
            f"backend 'numba' needs numba (pip install 'swarmpath[fast]'): {exc}"
        ) from None
    parts = minimize_compiled(
        algorithm, fns, dim, agents, iterations, ids, seed, params, kind, on_iteration,
        max_evaluations,
    )
    from swarmpath.optimizers.compiled.ready import made_ready, study_pieces

    made_ready(study_pieces(algorithm, fns), mark=True)  # compiled or loaded: auto may run them
    return [
        Result(algorithm=algorithm, function=fn.name, dim=dim, agents=agents,
               iterations=iterations, seed=seed, run_ids=list(ids), transform=kind,
               backend="numba", **fields)
        for fn, fields in zip(fns, parts, strict=True)
    ]


def _spread(
    on_iteration: Callable[[Optimizer | None], None] | None, iterations: int, calls: int
) -> Callable[[Optimizer | None], None] | None:
    """A hook that, called ``calls`` times, calls ``on_iteration`` ``iterations`` times."""
    if on_iteration is None or calls == iterations:
        return on_iteration
    count = 0

    def hook(optimizer: Optimizer | None) -> None:
        nonlocal count
        count += 1
        for _ in range(iterations * count // calls - iterations * (count - 1) // calls):
            on_iteration(optimizer)

    return hook


Row = tuple[BenchmarkFunction, int]


def _chunk_rows(
    fns: list[BenchmarkFunction], cell_ids: list[list[int]], size: int
) -> list[list[Row]]:
    """(function, run) rows, function-major, cut into chunks of at most ``size`` rows; a noisy
    function's rows never share a chunk with another function's."""
    chunks: list[list[Row]] = []
    current: list[Row] = []
    for fn, ids in zip(fns, cell_ids, strict=True):
        if fn.noisy and current:
            chunks.append(current)
            current = []
        for r in ids:
            current.append((fn, r))
            if len(current) == size:
                chunks.append(current)
                current = []
        if fn.noisy and current:
            chunks.append(current)
            current = []
    if current:
        chunks.append(current)
    return chunks


def resolve_transform(shifted: bool, transform: str | None) -> str:
    """The transform of a study from the ``shifted`` alias and ``transform`` (ParameterError on
    an unknown name or a contradiction)."""
    if transform is None:
        return "shift" if shifted else "none"
    if transform not in TRANSFORMS:
        raise ParameterError(
            f"transform must be one of {', '.join(TRANSFORMS)}, got {transform!r}"
        )
    if shifted and not shifts(transform):
        raise ParameterError(f"shifted=True contradicts transform={transform!r}")
    return transform


def _chunk_problem(chunk: list[Row], dim: int, seed: int, transform: str) -> Problem:
    parts = []
    start = 0
    while start < len(chunk):
        fn = chunk[start][0]
        stop = start
        while stop < len(chunk) and chunk[stop][0] is fn:
            stop += 1
        runs = [r for _, r in chunk[start:stop]]
        parts.append(BenchmarkProblem.build(fn, dim, runs, seed, transform))
        start = stop
    return parts[0] if len(parts) == 1 else StackedProblem.of(parts)


def _parts(problem: Problem) -> tuple[BenchmarkProblem, ...]:
    if isinstance(problem, StackedProblem):
        return problem.parts
    assert isinstance(problem, BenchmarkProblem)
    return (problem,)
