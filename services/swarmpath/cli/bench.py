"""``swarmpath bench``: optimizers x benchmark functions x dimensions, printed as the papers do.

The command is a thin shell over pure functions: :func:`make_spec` validates the options into a
:class:`BenchSpec` (raising :class:`InputError` naming the option), :func:`run_bench` runs the
cells through :func:`swarmpath.optimizers.minimize`, and :mod:`swarmpath.report` builds the table
and the JSON document.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Annotated, Any

import numpy as np
import typer
from rich.console import Console
from rich.measure import Measurement
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from swarmpath import __version__, report
from swarmpath.cli.core import InputError, app, parse_params_option, resolve_names
from swarmpath.functions import expand_function_names, get_function
from swarmpath.optimizers import ParameterError, get_optimizer, list_optimizers, minimize
from swarmpath.optimizers.api import MAX_AGENTS, MAX_DIM, MAX_ITERATIONS

MAX_RUNS = 10_000
#: Runs of one cell are computed in batches of at most this many array elements per population
#: (runs x agents x dim): memory stays bounded and, runs being independent, results are the same.
BATCH_ELEMENTS = 1 << 22


@dataclass(frozen=True)
class BenchSpec:
    algorithms: list[str]
    functions: list[str]
    dims: list[int]
    runs: int = 30
    agents: int = 30
    iterations: int = 500
    seed: int = 1
    shifted: bool = False
    params: dict[str, dict[str, Any]] = field(default_factory=dict)

    def cells(self) -> list[tuple[str, int, str]]:
        """(function, dim, algorithm) in table order."""
        return [(f, d, a) for f in self.functions for d in self.dims for a in self.algorithms]

    def settings(self) -> dict[str, Any]:
        return asdict(self)


# ------------------------------------------------------------------------------ input parsing
def _names(spec: str) -> list[str]:
    return [p.strip() for p in spec.split(",") if p.strip()]


def resolve_algorithms(spec: str) -> list[str]:
    """'ICOOT,coot,GWO' -> registered names (case-insensitive, duplicates dropped); 'all' = all."""
    return resolve_names(spec, list_optimizers(), "--algorithms", "algorithm")


def resolve_functions(spec: str) -> list[str]:
    try:
        names = expand_function_names(spec)
    except KeyError as exc:
        raise InputError("--functions", str(exc.args[0])) from None
    names = list(dict.fromkeys(names))
    if not names:
        raise InputError("--functions", "no function given")
    return names


def parse_dims(spec: str) -> list[int]:
    dims: list[int] = []
    for part in _names(spec):
        try:
            d = int(part)
        except ValueError:
            raise InputError("--dims", f"{part!r} is not an integer") from None
        check_range("--dims", d, 1, MAX_DIM)
        if d not in dims:
            dims.append(d)
    if not dims:
        raise InputError("--dims", "no dimension given")
    return dims


def check_range(option: str, value: int, low: int, high: int) -> int:
    if not low <= value <= high:
        raise InputError(option, f"{value} is not in [{low}, {high}]")
    return value


def parse_params(text: str | None, algorithms: Sequence[str]) -> dict[str, dict[str, Any]]:
    """'{"ICOOT": {"p": 0.5}}' -> params per algorithm, each checked by the algorithm itself."""
    return parse_params_option(
        text, algorithms, "--algorithms", '{"GWO": {"a_max": 2}}',
        lambda name, values: get_optimizer(name).resolve_params(values),
    )


def make_spec(
    algorithms: str,
    functions: str,
    dims: str,
    runs: int = 30,
    agents: int = 30,
    iterations: int = 500,
    seed: int = 1,
    shifted: bool = False,
    params: str | None = None,
) -> BenchSpec:
    """Validate the command's options; raises :class:`InputError` naming the bad one."""
    algos = resolve_algorithms(algorithms)
    fns = resolve_functions(functions)
    ds = parse_dims(dims)
    check_range("--runs", runs, 1, MAX_RUNS)
    check_range("--agents", agents, 1, MAX_AGENTS)
    check_range("--iterations", iterations, 1, MAX_ITERATIONS)
    if seed < 0:
        raise InputError("--seed", f"{seed} is negative")
    for a in algos:
        need = get_optimizer(a).min_agents
        if agents < need:
            raise InputError("--agents", f"{a} needs at least {need} agents, got {agents}")
    for f in fns:  # e.g. F5, F12, F13 need 2 dimensions: ask the function itself
        for d in ds:
            try:
                get_function(f).evaluate(np.zeros((1, d)))
            except ValueError as exc:
                raise InputError("--dims", f"{d}: {exc}") from None
    return BenchSpec(
        algorithms=algos,
        functions=fns,
        dims=ds,
        runs=runs,
        agents=agents,
        iterations=iterations,
        seed=seed,
        shifted=shifted,
        params=parse_params(params, algos),
    )


# -------------------------------------------------------------------------------------- running
def run_cell(
    spec: BenchSpec,
    algorithm: str,
    function: str,
    dim: int,
    on_step: Callable[[int], None] | None = None,
) -> report.Cell:
    """All runs of one cell (in memory-bounded batches); ``on_step(runs)`` after each iteration."""
    batch = max(1, min(spec.runs, BATCH_ELEMENTS // (spec.agents * dim)))
    best: list[float] = []
    evaluations: list[int] = []
    seconds = 0.0
    params: dict[str, Any] = {}
    for start in range(0, spec.runs, batch):
        ids = list(range(start, min(start + batch, spec.runs)))
        res = minimize(
            algorithm,
            function,
            dim=dim,
            agents=spec.agents,
            iterations=spec.iterations,
            seed=spec.seed,
            params=spec.params.get(algorithm),
            shifted=spec.shifted,
            run_ids=ids,
            on_iteration=None if on_step is None else _StepCounter(on_step, len(ids)),
        )
        best.extend(float(v) for v in res.best_fitness)
        evaluations.extend(int(v) for v in res.evaluations)
        seconds += res.seconds
        params = dict(res.params or {})
    return report.Cell(
        algorithm=algorithm,
        function=function,
        dim=dim,
        run_ids=list(range(spec.runs)),
        best_fitness=best,
        evaluations=evaluations,
        seconds=seconds,
        params=params,
    )


class _StepCounter:
    """``minimize``'s per-iteration hook reporting how many runs advanced one iteration."""

    def __init__(self, on_step: Callable[[int], None], runs: int):
        self.on_step, self.runs = on_step, runs

    def __call__(self, _optimizer: object) -> None:
        self.on_step(self.runs)


def run_bench(
    spec: BenchSpec,
    on_cell: Callable[[int, tuple[str, int, str]], None] | None = None,
    on_step: Callable[[int], None] | None = None,
) -> list[report.Cell]:
    """Every cell of the study, ranked. ``on_cell(i, key)`` before cell i starts."""
    cells = []
    for i, (function, dim, algorithm) in enumerate(spec.cells()):
        if on_cell is not None:
            on_cell(i, (function, dim, algorithm))
        cells.append(run_cell(spec, algorithm, function, dim, on_step))
    report.assign_ranks(cells)
    return cells


def caption(spec: BenchSpec, seconds: float) -> str:
    shifted = ", shifted" if spec.shifted else ""
    return (
        f"{spec.runs} runs, {spec.agents} agents, {spec.iterations} iterations, seed {spec.seed}"
        f"{shifted}; {report.BEST_MARK} best avg; {seconds:.1f} s"
    )


# -------------------------------------------------------------------------------------- command
def _run_with_progress(spec: BenchSpec, stderr: Console) -> list[report.Cell]:
    keys = spec.cells()
    total_runs = len(keys) * spec.runs
    columns = (
        TextColumn("{task.description:<16}"),
        BarColumn(),
        TextColumn("cells {task.fields[cells]}/{task.fields[n_cells]}"),
        TextColumn("runs {task.fields[runs]}/{task.fields[n_runs]}"),
        TimeElapsedColumn(),
    )
    with Progress(*columns, console=stderr, transient=stderr.is_terminal) as progress:
        task = progress.add_task(
            "bench", total=total_runs * spec.iterations, cells=0, n_cells=len(keys), runs=0,
            n_runs=total_runs,
        )
        done = 0  # run-iterations

        def on_cell(i: int, key: tuple[str, int, str]) -> None:
            function, dim, algorithm = key
            progress.update(task, description=f"{algorithm} {function} {dim}D", cells=i)

        def on_step(runs: int) -> None:
            nonlocal done
            done += runs
            progress.update(task, completed=done, runs=done // spec.iterations)

        cells = run_bench(spec, on_cell, on_step)
        progress.update(task, description="done", cells=len(keys), runs=total_runs)
    return cells


@app.command()
def bench(
    algorithms: Annotated[
        str, typer.Option("--algorithms", "-a", help="Comma-separated names, or 'all'.")
    ] = "all",
    functions: Annotated[
        str, typer.Option("--functions", "-f", help="Names and ranges: F1-F13, F1,F5,F6-floor.")
    ] = "F1-F13",
    dims: Annotated[str, typer.Option("--dims", "-d", help="Comma-separated dimensions.")] = "30",
    runs: Annotated[int, typer.Option(help="Independent runs per cell.")] = 30,
    agents: Annotated[int, typer.Option(help="Population size.")] = 30,
    iterations: Annotated[int, typer.Option(help="Iterations per run.")] = 500,
    seed: Annotated[int, typer.Option(help="Study seed; run r uses its own stream of it.")] = 1,
    shifted: Annotated[
        bool, typer.Option("--shifted", help="Move each run's optimum randomly in the box.")
    ] = False,
    as_json: Annotated[
        bool, typer.Option("--json", help="Print one JSON document (every cell and run).")
    ] = False,
    params: Annotated[
        str | None, typer.Option(help='Algorithm parameters: \'{"GWO": {"a_max": 2}}\'.')
    ] = None,
) -> None:
    """Run optimizers on benchmark functions; print min/max/avg/std per function and dimension."""
    spec = make_spec(algorithms, functions, dims, runs, agents, iterations, seed, shifted, params)
    stderr = Console(stderr=True)
    started = time.perf_counter()
    try:
        cells = _run_with_progress(spec, stderr)
    except ParameterError as exc:  # a check only the optimizer's constructor makes
        raise InputError("--params", str(exc)) from None
    seconds = time.perf_counter() - started

    if as_json:
        doc = report.study_to_json(spec.settings(), cells, seconds, __version__)
        sys.stdout.write(json.dumps(doc, allow_nan=False) + "\n")
        return
    print_tables(spec, cells, seconds)


def print_tables(spec: BenchSpec, cells: Sequence[report.Cell], seconds: float) -> None:
    table = report.render_table(cells, spec.algorithms)
    console = Console()
    if not console.is_terminal:  # pipes and files: never squeeze the numbers to 80 columns
        width = Measurement.get(console, console.options.update(width=100_000), table).maximum
        console = Console(width=max(80, width))
    console.print(table)
    console.print(caption(spec, seconds), highlight=False)
    if len(spec.algorithms) > 1:
        console.print(report.render_ranking(cells, spec.algorithms))
