"""``swarmpath bench``: optimizers x benchmark functions x dimensions, printed as the papers do.

The command is a thin shell over pure functions: :func:`~swarmpath.cli.bench_spec.make_spec`
validates the options into a :class:`BenchSpec` (raising :class:`InputError` naming the option),
:func:`run_bench` runs the
cells through :func:`swarmpath.optimizers.minimize_many` (stacked per algorithm and dimension,
in one process per CPU: :mod:`swarmpath.cli.parallel`), and :mod:`swarmpath.evidence.report` builds
the table and the JSON document.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.measure import Measurement
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from swarmpath import __version__
from swarmpath.cli import bench_race, parallel
from swarmpath.cli.bench_spec import BenchSpec, check_range, make_spec
from swarmpath.cli.core import InputError, app, plot_dir
from swarmpath.cli.study_options import (
    AgentsOpt,
    AlgorithmsOpt,
    BackendOpt,
    BudgetOpt,
    DimsOpt,
    FunctionsOpt,
    InstancesOpt,
    IterationsOpt,
    RopeOpt,
    SeedOpt,
    StatOpt,
    TableFormatOpt,
    check_format,
    check_rope,
    check_stat,
)
from swarmpath.evidence import anytime, audit, report
from swarmpath.evidence.benchmark_stats import bayes_lines, latex_legend
from swarmpath.evidence.race_report import race_line, with_race
from swarmpath.functions import get_function
from swarmpath.optimizers import ParameterError, minimize_many
from swarmpath.parallel import TaskPool
from swarmpath.plugins.pins import study_pins
from swarmpath.provenance import numeric_platform

#: Rough CPU seconds per population element and iteration (23 ms per run of 30 x 30 x 500).
SECONDS_PER_ELEMENT_ITERATION = 5e-8
#: Runs are computed in batches of at most this many array elements per population (functions x
#: runs x agents x dim, and per curve array): memory stays bounded and, runs being independent,
#: results are the same.
BATCH_ELEMENTS = 1 << 22


# -------------------------------------------------------------------------------------- running
@dataclass(frozen=True)
class Task:
    """Runs of one algorithm and dimension on one or several functions, computed as one
    ``minimize_many`` batch: the same numbers as one ``minimize`` per cell, run for run."""

    algorithm: str
    dim: int
    functions: tuple[str, ...]
    run_ids: tuple[int, ...]

    @property
    def rows(self) -> int:
        return len(self.functions) * len(self.run_ids)


CellKey = tuple[str, int, str]  # (function, dim, algorithm)


def plan_tasks(spec: BenchSpec, cells: Sequence[CellKey] | None = None,
               ranges: Mapping[CellKey, tuple[int, int]] | None = None) -> list[Task]:
    """The tasks computing ``cells`` (default: every cell of ``spec``), largest first: runs
    0..runs-1 of each, or ``ranges[cell]`` = (first run, end) (a race's next round).

    Per algorithm, dimension and run range, the noiseless functions share a stack and each noisy
    one (F7) gets its own (``minimize_many`` never stacks it). A task holds at most
    ``BATCH_ELEMENTS`` array elements per population (and per convergence-curve array), so
    memory stays bounded whatever the runs, dimensions or iterations.
    """
    keys = spec.cells() if cells is None else list(cells)
    groups: dict[tuple[str, int, int, int], list[str]] = {}
    for function, dim, algorithm in keys:
        first, end = (0, spec.runs) if ranges is None else ranges[(function, dim, algorithm)]
        groups.setdefault((algorithm, dim, first, end), []).append(function)
    tasks: list[Task] = []
    for (algorithm, dim, first, end), functions in groups.items():
        noisy = [f for f in functions if get_function(f).noisy]
        stacks = [[f for f in functions if f not in noisy], *[[f] for f in noisy]]
        for stack in filter(None, stacks):
            per_row = max(spec.agents * dim, spec.iterations_for(algorithm, dim))
            size = max(1, min(end - first, BATCH_ELEMENTS // (len(stack) * per_row)))
            for start in range(first, end, size):
                ids = tuple(range(start, min(start + size, end)))
                tasks.append(Task(algorithm, dim, tuple(stack), ids))
    # largest first, so that the processes finish together (stable: table order among equals)
    tasks.sort(key=lambda t: -t.rows * t.dim)
    return tasks


def run_bench(
    spec: BenchSpec,
    on_step: Callable[[int], None] | None = None,
    jobs: int = 1,
    cells: Sequence[CellKey] | None = None,
    on_done: Callable[[Task], None] | None = None,
    ranges: Mapping[CellKey, tuple[int, int]] | None = None,
    pool: TaskPool | None = None,
) -> list[report.Cell]:
    """Every cell of the study (or the given ``cells``, each with the runs of ``ranges``), in
    table order and ranked.

    The tasks of :func:`plan_tasks` run in this process (``jobs`` = 1) or in ``jobs`` spawned
    processes (:mod:`swarmpath.cli.parallel`; or on ``pool``'s); each run depends only on
    (spec, seed, run), so the numbers are the same for any ``jobs`` and any ranges.
    ``on_step(rows)`` reports (function, run) rows that advanced one iteration,
    ``on_done(task)`` a finished task; both are called in this process.
    """
    keys = spec.cells() if cells is None else list(cells)
    tasks = plan_tasks(spec, keys, ranges)
    if jobs > 1 or pool is not None:
        compile_first(spec)
    finished = None if on_done is None else (lambda job: on_done(job[1]))
    jobs_ = [(spec, t) for t in tasks]
    done = (parallel.run_tasks(_compute, jobs_, jobs, on_step, finished) if pool is None
            else pool.run(_compute, jobs_, on_step, finished))
    parts: dict[tuple[str, str, int], list[Any]] = {}
    for results in done:
        for res in results:
            parts.setdefault((res.algorithm, res.function, res.dim), []).append(res)
    out = [_cell(algorithm, function, dim, parts[(algorithm, function, dim)])
           for function, dim, algorithm in keys]
    report.assign_ranks(out)
    return out


def _compute(job: tuple[BenchSpec, Task], report_rows: Callable[[int], None]) -> list[Any]:
    """One task: ``minimize_many`` over its functions and runs (in a child process or here)."""
    spec, task = job

    def hook(_optimizer: object) -> None:
        report_rows(task.rows)

    return minimize_many(
        task.algorithm, list(task.functions), dim=task.dim, agents=spec.agents,
        iterations=spec.iterations_for(task.algorithm, task.dim), seed=spec.seed,
        params=spec.params.get(task.algorithm), transform=spec.transform,
        run_ids=list(task.run_ids), on_iteration=hook, backend=spec.backend,
        max_evaluations=spec.evaluations(task.dim),
    )


def compile_first(spec: BenchSpec, note: Callable[[str], None] | None = None) -> None:
    """The kernels the study would run that this tree's numba cache lacks: with backend
    "numba", compiled in this process before the tasks go to other processes (they then load
    them from the cache instead of each compiling the same kernels side by side: seconds of CPU
    per kernel in a fresh environment; :func:`swarmpath.optimizers.compiled.warm.compile_cold`);
    with "auto", asked for in the background, the study running the numpy reference for them
    until they are ready (:func:`~swarmpath.optimizers.compiled.warm.request_cold`). ``note``
    gets one line when anything is missing."""
    if spec.backend == "numpy":
        return
    from swarmpath.optimizers.api import resolve_backend

    compiled = [a for a in spec.algorithms if any(
        resolve_backend(spec.backend, a, spec.functions, spec.transform, spec.params.get(a),
                        spec.evaluations(d), agents=spec.agents,
                        iterations=spec.iterations_for(a, d), dim=d) == "numba"
        for d in spec.dims)]
    if compiled:
        from swarmpath.optimizers.compiled.warm import compile_cold, request_cold

        make = compile_cold if spec.backend == "numba" else request_cold
        make(compiled, list(dict.fromkeys(spec.functions)), False, note or (lambda _text: None))


def auto_jobs(spec: BenchSpec) -> int:
    """Processes for ``--jobs 0``: one per CPU, but one for a study of a few seconds (starting a
    process and importing numpy there costs about half a second)."""
    elements = sum(spec.runs * spec.agents * dim for _, dim, _ in spec.cells())
    seconds = elements * spec.iterations * SECONDS_PER_ELEMENT_ITERATION
    if seconds < 2.0:
        return 1
    return parallel.usable_cpus()


def _cell(algorithm: str, function: str, dim: int, results: list[Any]) -> report.Cell:
    """One table cell from its batches' results, runs in order."""
    results = sorted(results, key=lambda r: r.run_ids[0])
    return report.Cell(
        algorithm=algorithm,
        function=function,
        dim=dim,
        run_ids=[r for res in results for r in res.run_ids],
        best_fitness=[float(v) for res in results for v in res.best_fitness],
        evaluations=[int(v) for res in results for v in res.evaluations],
        seconds=sum(res.seconds for res in results),
        params=dict(results[-1].params or {}),
        curves=[row.tolist() for res in results for row in res.curve],
        cpu_seconds=report.cpu_total(res.cpu_seconds for res in results),
        backends=report.count_backends((res.backend, len(res.run_ids)) for res in results),
    )


def run_cell(
    spec: BenchSpec,
    algorithm: str,
    function: str,
    dim: int,
    on_step: Callable[[int], None] | None = None,
) -> report.Cell:
    """All runs of one cell (in memory-bounded batches); ``on_step(runs)`` after each iteration."""
    (cell,) = run_bench(spec, on_step, jobs=1, cells=[(function, dim, algorithm)])
    return cell


#: What the ranking table's time columns are (under it).
TIME_LEGEND = ("time (s), CPU (s): wall and CPU seconds of the algorithm's runs, summed over "
               "its functions and dimensions (CPU: the computing threads' time, which does not "
               "grow with the machine's load as the wall time does)")


def caption(spec: BenchSpec, seconds: float | None, race: dict[str, Any] | None = None,
            cpu_seconds: float | None = None) -> str:
    """The table's caption: the setting, then (after a run) the study's elapsed wall time and
    ``cpu_seconds``, the CPU time its runs took (their threads', summed over the cells: it
    does not grow with the machine's load as the elapsed time does)."""
    moved = "" if spec.transform == "none" else f", transform {spec.transform}"
    backend = "" if spec.backend in ("numpy", "auto") else f", backend {spec.backend}"
    length = (f"{spec.iterations} iterations" if spec.budget_evals is None else
              f"budget {spec.budget_evals.replace('xD', ' x D')} evaluations per run")
    suites = [f for f in spec.functions if getattr(get_function(f), "suite", "")]
    errors = ""
    if suites:
        floor = any(getattr(get_function(f), "error_floor", 0.0) for f in suites)
        errors = "; suite functions: errors f - f_opt" + (" (CEC: < 1e-8 as 0)" if floor else "")
        if spec.instances is not None:
            errors += (f", instances {_ranges(spec.instances)}"
                       + (" pooled" if spec.pool_instances else ""))
    runs = f"{spec.runs} runs"
    if race is not None:
        used = sum(c["runs"] for b in race["blocks"] for c in b["cells"])
        runs = f"raced: at most {spec.runs} runs a cell, {used} in all"
    setting = (f"{runs}, {spec.agents} agents, {length}, seed {spec.seed}"
               f"{moved}{backend}{errors}")
    if seconds is None:  # a paper's caption: what was run
        dims = ", ".join(str(d) for d in spec.dims)
        return f"swarmpath bench: {', '.join(spec.functions)} in {dims} dimensions; {setting}"
    cpu = "" if cpu_seconds is None else f", {cpu_seconds:.2f} s CPU in the runs"
    return f"{setting}; {report.BEST_MARK} best avg; {seconds:.1f} s elapsed{cpu}"


def _ranges(ids: Sequence[int]) -> str:
    """[1, 2, 3, 7] -> '1-3,7'."""
    out: list[str] = []
    for i in ids:
        if out and out[-1].split("-")[-1] == str(i - 1):
            out[-1] = f"{out[-1].split('-')[0]}-{i}"
        else:
            out.append(str(i))
    return ",".join(out)


# -------------------------------------------------------------------------------------- command
def _run_with_progress(spec: BenchSpec, stderr: Console, jobs: int) -> list[report.Cell]:
    keys = spec.cells()
    total_runs = len(keys) * spec.runs
    steps = sum(spec.runs * spec.iterations_for(a, d) for _, d, a in keys)
    columns = (
        TextColumn("{task.description:<16}"),
        BarColumn(),
        TextColumn("cells {task.fields[cells]}/{task.fields[n_cells]}"),
        TextColumn("runs {task.fields[runs]}/{task.fields[n_runs]}"),
        TimeElapsedColumn(),
    )
    with Progress(*columns, console=stderr, transient=stderr.is_terminal) as progress:
        task = progress.add_task(
            f"bench x{jobs}", total=steps, cells=0, n_cells=len(keys),
            runs=0, n_runs=total_runs,
        )
        done = 0  # run-iterations
        finished: dict[tuple[str, str, int], int] = {}  # runs finished per cell

        def on_done(t: Task) -> None:
            for f in t.functions:
                key = (t.algorithm, f, t.dim)
                finished[key] = finished.get(key, 0) + len(t.run_ids)
            cells = sum(n == spec.runs for n in finished.values())
            progress.update(task, cells=cells)

        def on_step(rows: int) -> None:
            nonlocal done
            done += rows
            progress.update(task, completed=done, runs=done * total_runs // max(steps, 1))

        cells = run_bench(spec, on_step, jobs, on_done=on_done)
        progress.update(task, description="done", cells=len(keys), runs=total_runs)
    return cells


@app.command()
def bench(
    algorithms: AlgorithmsOpt = "all",
    functions: FunctionsOpt = "F1-F13",
    dims: DimsOpt = "30",
    runs: Annotated[int, typer.Option(help="Independent runs per cell.")] = 30,
    agents: AgentsOpt = 30,
    iterations: IterationsOpt = 500,
    seed: SeedOpt = 1,
    shifted: Annotated[
        bool, typer.Option("--shifted", help="Alias of --transform shift.")
    ] = False,
    transform: Annotated[
        str | None,
        typer.Option(
            "--transform", metavar="none|shift|rotate|shift+rotate",
            help="Move each run's optimum randomly in the box (shift) and/or turn the function "
            "about it by a random orthogonal matrix (rotate), from the run's own streams.",
        ),
    ] = None,
    as_json: Annotated[
        bool, typer.Option("--json", help="Print one JSON document (every cell and run).")
    ] = False,
    params: Annotated[
        str | None, typer.Option(help='Algorithm parameters: \'{"GWO": {"a_max": 2}}\'.')
    ] = None,
    jobs: Annotated[
        int,
        typer.Option(
            "--jobs", "-j",
            help="Processes computing the study (0: one per CPU, one for a short study). "
            "Numbers do not change.",
        ),
    ] = 0,
    reference: Annotated[
        str | None,
        typer.Option(
            "--reference", metavar="NAME",
            help="Algorithm the +/=/- markers compare against (default: the last one listed).",
        ),
    ] = None,
    plot: Annotated[
        Path | None,
        typer.Option("--plot", metavar="DIR",
                     help="Write PNGs into DIR: convergence curves and box plots of best "
                     "fitness per function and dimension, a critical-difference diagram per "
                     "dimension."),
    ] = None,
    backend: BackendOpt = "auto",
    instances: InstancesOpt = None,
    budget_evals: BudgetOpt = None,
    pool_instances: Annotated[
        bool, typer.Option("--pool-instances",
                           help="One row per function with the runs of all its instances "
                           "(COCO's practice); default: a row per instance.")
    ] = False,
    stat: StatOpt = "mean",
    rope: RopeOpt = "1%",
    fmt: TableFormatOpt = "table",
    show_anytime: Annotated[
        bool, typer.Option("--anytime", help="Also print per function and dimension the "
                           "fixed-target (ERT) and fixed-budget tables and the ECDF's area.")
    ] = False,
    baselines: Annotated[
        bool, typer.Option("--baselines", help="Add the strong baselines CMA-ES (IPOP), "
                           "L-SHADE, jSO and RS (random search) to the algorithms; the markers "
                           "still compare against the last algorithm you named.")
    ] = False,
    race: bench_race.RaceOpt = False,
    race_alpha: bench_race.RaceAlphaOpt = None,
    race_min_runs: bench_race.RaceMinRunsOpt = None,
    race_batch: bench_race.RaceBatchOpt = None,
    race_margin: bench_race.RaceMarginOpt = None,
    race_pairs: bench_race.RacePairsOpt = None,
    race_final_test: bench_race.RaceFinalOpt = None,
    race_looks: bench_race.RaceLooksOpt = None,
    race_look_share: bench_race.RaceLookShareOpt = None,
    race_sequence_share: bench_race.RaceSequenceShareOpt = None,
    race_spending: bench_race.RaceSpendingOpt = None,
    race_futility: bench_race.RaceFutilityOpt = None,
    race_recycle: bench_race.RaceRecycleOpt = None,
) -> None:
    """Run optimizers on benchmark functions; print min/max/avg/std (or median/IQR) per function
    and dimension, with Wilcoxon rank-sum markers, effect sizes and Bayesian probabilities
    against a reference, and Friedman mean ranks."""
    check_stat(stat)
    the_rope = check_rope(rope)
    check_format(fmt, ("table", "latex"))
    spec = make_spec(algorithms, functions, dims, runs, agents, iterations, seed, shifted, params,
                     reference, transform, backend, instances, budget_evals, pool_instances,
                     baselines)
    check_range("--jobs", jobs, 0, parallel.MAX_JOBS)
    racing = bench_race.race_settings(spec, race, race_alpha, race_min_runs, race_batch,
                                      race_margin, race_pairs, race_final_test, race_looks,
                                      race_look_share, race_sequence_share, race_spending,
                                      race_futility, race_recycle)
    if plot is not None:
        plot = plot_dir(plot, "--plot")
    stderr = Console(stderr=True)
    started = time.perf_counter()
    the_race = None
    try:
        compile_first(spec, lambda text: stderr.print(f"swarmpath bench: {text}",
                                                      highlight=False, markup=False,
                                                      soft_wrap=True))
        if racing is None:
            cells = _run_with_progress(spec, stderr, jobs or auto_jobs(spec))
        else:
            cells, the_race = bench_race.race_with_progress(spec, racing, stderr,
                                                            jobs or auto_jobs(spec))
    except ParameterError as exc:  # a check only the optimizer's constructor makes
        raise InputError("--params", str(exc)) from None
    if spec.pool_instances:
        from swarmpath.evidence.instances import pool_instances as pool

        cells = pool(cells)
    seconds = time.perf_counter() - started
    tests = report.statistics(cells, spec.algorithms, spec.reference, stat=stat, rope=the_rope)
    if the_race is not None:  # the race's decisions, not rank-sum tests after optional stopping
        tests = with_race(tests, the_race)
    groups = (anytime.study_groups(cells, spec.agents, spec.iterations)
              if as_json or plot is not None or show_anytime else {})
    if plot is not None:
        from swarmpath.evidence import plots
        from swarmpath.evidence.anytime_report import write_anytime_plots
        from swarmpath.evidence.cdplot import draw_cd

        for out in [*plots.write_benchmark_plots(report.plot_runs(cells), plot),
                    *write_anytime_plots(groups, plot, spec.algorithms)]:
            stderr.print(f"wrote {out}", highlight=False)
        for dim, f in tests.friedman.items():
            cd = draw_cd(f, plot / f"cd-D{dim}.png", f"D = {dim}")
            if cd is not None:
                stderr.print(f"wrote {cd}", highlight=False)

    if as_json:
        doc = report.study_to_json(spec.settings(), cells, seconds, __version__, tests)
        doc["platform"] = numeric_platform()
        doc["anytime"] = anytime.groups_to_json(groups)
        if the_race is not None:
            doc["settings"]["racing"] = the_race["settings"]
            doc["race"] = the_race
            doc["race_summary"] = bench_race.race_summary(the_race)
        doc["extensions"] = study_pins(spec.algorithms, spec.functions)
        sys.stdout.write(json.dumps(doc, allow_nan=False) + "\n")
        return
    if fmt == "latex":
        sys.stdout.write(latex_table(spec, cells, tests))
        return
    print_tables(spec, cells, seconds, tests)
    if the_race is not None:
        Console().print(race_line(the_race), highlight=False)
    if show_anytime:
        print_anytime(groups, spec.algorithms)


def print_anytime(groups: dict[tuple[str, int], anytime.AnytimeGroup],
                  algorithms: Sequence[str]) -> None:
    from swarmpath.evidence import anytime_report

    console = Console()
    for (function, dim), group in groups.items():
        console.print(anytime_report.fixed_target_table(
            f"{function}, D={dim}: fixed target", group, algorithms))
        console.print(anytime_report.fixed_budget_table(
            f"{function}, D={dim}: fixed budget", group, algorithms))
    console.print(anytime_report.LEGEND, highlight=False)


def latex_table(spec: BenchSpec, cells: Sequence[report.Cell], tests: report.Statistics) -> str:
    """The study's table as LaTeX, its caption naming the setting and the tests."""
    from swarmpath.evidence import latex

    multi = len(spec.algorithms) > 1
    grid = report.study_grid(cells, spec.algorithms, tests=tests if multi else None,
                             origin=spec.transform == "none")
    text = caption(spec, None, tests.race) + (f". {latex_legend(tests)}" if multi else ".")
    return latex.grid_to_latex(grid, text, "tab:swarmpath-bench")


def print_tables(
    spec: BenchSpec,
    cells: Sequence[report.Cell],
    seconds: float,
    tests: report.Statistics | None = None,
) -> None:
    multi = len(spec.algorithms) > 1
    plain = spec.transform == "none"
    table = report.render_table(cells, spec.algorithms, tests=tests if multi else None,
                                origin=plain)
    ranks = report.render_ranking(cells, spec.algorithms, tests) if multi else None
    console = Console()
    if not console.is_terminal:  # pipes and files: never squeeze the numbers to 80 columns
        wide = console.options.update(width=100_000)
        width = max(Measurement.get(console, wide, t).maximum for t in (table, ranks) if t)
        console = Console(width=max(80, width))
    console.print(table)
    console.print(caption(spec, seconds, tests.race if tests else None,
                          report.cpu_total(c.cpu_seconds for c in cells)), highlight=False)
    if plain and report.origin_suspects(cells):
        console.print(audit.ORIGIN_FOOTNOTE, highlight=False)
    if ranks is not None:
        console.print(ranks)
        if tests is not None:
            for line in report.friedman_lines(tests) + bayes_lines(tests):
                console.print(line, highlight=False)
            console.print(report.legend(tests), highlight=False)
        console.print(TIME_LEGEND, highlight=False)
