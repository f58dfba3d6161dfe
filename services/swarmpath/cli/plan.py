"""``swarmpath plan``: planners x maps x runs, printed as the papers' run tables.

For each planner and map it runs ``--runs`` episodes (run r of ``--seed`` s is the same path on
any machine, see :mod:`swarmpath.planners.episode`) and prints Run / Distance / Error / Elapsed
time plus success, collisions and the gap to the exact optimum, with a Mean row. ``--json``
prints ``{"runs": [...], "summary": [...]}`` (the summary from
:func:`swarmpath.planners.summary.summarize`), ``--plot DIR`` writes one PNG per planner x map
(:mod:`swarmpath.evidence.plots`) and box plots of length, gap and time per map.

``--maps`` takes preset names (``--list-maps``) and paths: scenario JSON/YAML, ROS map_server /
nav2 YAML (recognised by its ``image`` key) or MovingAI ``.map`` files (``--resolution`` metres
per cell, default 1); ``--start`` / ``--goal`` override every map's endpoints, ``--scen`` turns a
MovingAI map into one map per scenario pair (:mod:`swarmpath.cli.plan_maps`).
``--backend numpy|numba`` sets the ``backend`` parameter of every selected planner that has
one (:mod:`swarmpath.cli.plan_backend`).
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from swarmpath import parallel, plan_runs
from swarmpath.cli.core import (
    InputError,
    app,
    parse_params_option,
    plot_dir,
    resolve_names,
)
from swarmpath.cli.plan_maps import (
    MapOptions,
    compute_optima,
    make_options,
    resolve_maps,
)
from swarmpath.cli.plan_tables import print_tables
from swarmpath.cli.study_options import TableFormatOpt, check_format
from swarmpath.world.optimum_base import DEFAULT_BUDGET

MAX_RUNS = 10_000


@dataclass
class PlanSpec:
    planners: list[str]
    maps: list[Any]  # Scenario objects, in order, with distinct names
    runs: int = 10
    seed: int = 1
    params: dict[str, dict[str, Any]] = field(default_factory=dict)
    #: the planner the statistical tests compare against (None: the last of ``planners``)
    reference: str | None = None
    #: seconds the exact optimum of a map may take (None: no limit)
    optimum_budget: float | None = DEFAULT_BUDGET
    #: MovingAI octile optimum (m) of the maps made from --scen pairs, by map name
    octile: dict[str, float] = field(default_factory=dict)
    #: MovingAI bucket of the maps made from --scen pairs, by map name
    buckets: dict[str, int] = field(default_factory=dict)
    #: (exact optimum or None, reason or None) by map name, filled by the command
    optima: dict[str, tuple[float | None, str | None]] = field(default_factory=dict)

    def cells(self) -> list[tuple[str, Any]]:
        return [(p, m) for p in self.planners for m in self.maps]


@dataclass
class CellResult:
    planner: str
    scenario: Any
    runs: list[dict[str, Any]]
    seed: int  # the study seed (plots rebuild run 0's moving obstacles from it)


# ------------------------------------------------------------------------------ input parsing
def _names(spec: str) -> list[str]:
    return [p.strip() for p in spec.split(",") if p.strip()]


def resolve_planners(spec: str) -> list[str]:
    """'ICOOT,mfb,swarm:MyGWO' -> registered names (case-insensitive, duplicates dropped);
    'all' = all registered; ``swarm:<optimizer>`` names the swarm local planner driven by any
    registered optimizer."""
    from swarmpath.planners import PlannerError, get_planner, list_planners

    out: list[str] = []
    for part in (p.strip() for p in spec.split(",")):
        if part.lower().startswith("swarm:"):
            try:
                name = get_planner("swarm:" + part[len("swarm:"):]).name
            except PlannerError as exc:
                raise InputError("--planners", str(exc)) from None
            names = [name]
        elif part:
            names = resolve_names(part, list_planners(), "--planners", "planner")
        else:
            continue
        out += [n for n in names if n not in out]
    if not out:
        raise InputError("--planners", "no planner given")
    return out


def parse_params(text: str | None, planners: Sequence[str]) -> dict[str, dict[str, Any]]:
    """'{"OMPL-RRTstar": {"time": 0.5}}' -> params per planner, each checked by the planner."""
    from swarmpath.planners import get_planner

    return parse_params_option(
        text, planners, "--planners", '{"MFB": {"agents": 10}}',
        lambda name, values: get_planner(name).resolve_params(values),
    )


def make_spec(planners: str, maps: str, runs: int = 10, seed: int = 1,
              params: str | None = None, reference: str | None = None,
              map_options: MapOptions | None = None,
              optimum_budget: float | None = DEFAULT_BUDGET,
              note: Callable[[str], None] | None = None,
              backend: str | None = None) -> PlanSpec:
    """Validate the command's options; raises :class:`InputError` naming the bad one.
    ``backend``: ``--backend``, set in the params of every planner that has one
    (:func:`swarmpath.cli.plan_backend.apply_backend`)."""
    from swarmpath.cli.plan_backend import apply_backend
    from swarmpath.evidence.stats import resolve_reference

    names = resolve_planners(planners)
    try:
        ref = resolve_reference(names, reference)
    except ValueError as exc:
        raise InputError("--reference", str(exc)) from None
    if optimum_budget is not None and not (math.isfinite(optimum_budget) and optimum_budget > 0):
        raise InputError("--optimum-budget", f"{optimum_budget} is not a positive number of s")
    resolved = resolve_maps(maps, map_options, note)
    if not 1 <= runs <= MAX_RUNS:
        raise InputError("--runs", f"{runs} is not in [1, {MAX_RUNS}]")
    if seed < 0:
        raise InputError("--seed", f"{seed} is negative")
    by_planner = apply_backend(backend, names, parse_params(params, names))
    return PlanSpec(names, resolved.maps, runs, seed, by_planner, ref, optimum_budget,
                    resolved.octile, resolved.buckets)


# -------------------------------------------------------------------------------------- running
def run_episode(spec: PlanSpec, planner: str, scenario: Any, run: int,
                on_step: Callable[[], None] | None = None) -> dict[str, Any]:
    """One run as a JSON-ready dict (:func:`swarmpath.plan_runs.run_episode`)."""
    return plan_runs.run_episode(_task(spec, planner, scenario, run), on_step)


def _task(spec: PlanSpec, planner: str, scenario: Any, run: int) -> plan_runs.EpisodeTask:
    return plan_runs.EpisodeTask(scenario, planner, spec.seed, run, spec.params.get(planner),
                                 spec.optimum_budget)


def run_plan(
    spec: PlanSpec,
    on_step: Callable[[int], None] | None = None,
    jobs: int = 1,
    on_done: Callable[[int], None] | None = None,
) -> list[CellResult]:
    """Every run of every planner x map, in table order, in this process (``jobs`` = 1) or in
    ``jobs`` spawned processes (:mod:`swarmpath.cli.parallel`). A run depends only on (scenario,
    planner, seed, run), so the results are the same for any ``jobs``; with more processes than
    cores the planning times grow, and the planners that plan against a wall-clock budget (OMPL)
    get less done. ``on_step(n)``: n simulated steps done; ``on_done(runs)``: runs finished."""
    # each task carries its own run's inputs only (not the spec), so the children import the
    # planners and nothing of the command line
    tasks = [_task(spec, planner, scenario, run)
             for planner, scenario in spec.cells() for run in range(spec.runs)]
    finished = 0

    def done(_task: Any) -> None:
        nonlocal finished
        finished += 1
        if on_done is not None:
            on_done(finished)

    outcomes = parallel.run_tasks(plan_runs.episode_task, tasks, jobs, on_step, done)
    cells = []
    for i, (planner, scenario) in enumerate(spec.cells()):
        runs = outcomes[i * spec.runs:(i + 1) * spec.runs]
        cells.append(CellResult(planner, scenario, runs, spec.seed))
    return cells


def simulated_world(scenario: Any, seed: int, run: int) -> Any:
    """The moving obstacles and goal of run ``run`` as its simulator saw them (the episode draws
    its world from stream (seed, run, SIMULATION)): for the plots, rebuilt when one is drawn
    rather than sent back from the process that ran the episode."""
    from swarmpath.optimizers.streams import SIMULATION, run_generator

    return scenario.instantiate(run_generator(seed, run, SIMULATION))


def document(cells: Sequence[CellResult], reference: str | None = None,
             spec: PlanSpec | None = None) -> dict[str, Any]:
    """The ``--json`` document: exactly {"runs": [...], "summary": [...], "statistics": {...},
    "maps": [...], "buckets": [...], "extensions": {...}} (extensions: each planner's origin
    and code digest, swarmpath.plugins.pins.study_pins; statistics:
    :meth:`swarmpath.evidence.compare_maps.MapStatistics.to_json`; maps: per map its exact
    optimum, the reason when there is none, the .scen octile optimum and bucket; buckets: success
    and gap per planner and MovingAI bucket, :func:`swarmpath.evidence.buckets.bucket_rows`,
    empty without --scen)."""
    from swarmpath.evidence.buckets import bucket_rows
    from swarmpath.evidence.compare_maps import map_statistics
    from swarmpath.planners.summary import summarize

    runs = [r for c in cells for r in c.runs]
    planners = list(dict.fromkeys(c.planner for c in cells))
    names = list(dict.fromkeys(c.scenario.name for c in cells))
    optima = spec.optima if spec is not None else {}
    octile = spec.octile if spec is not None else {}
    buckets = spec.buckets if spec is not None else {}
    by_name = {c.scenario.name: c.runs for c in cells}
    maps = []
    for name in names:
        value, reason = optima.get(name, (None, None))
        if name not in optima:  # the runs carry the optimum (without the reason)
            value = next((r["optimum"] for r in by_name[name] if r["optimum"] is not None), None)
        scenario = next(c.scenario for c in cells if c.scenario.name == name)
        maps.append({"map": name, "optimum": value, "optimum_reason": reason,
                     "octile": octile.get(name), "bucket": buckets.get(name),
                     **frame_entry(scenario)})
    from swarmpath.plugins.pins import study_pins

    return {"runs": runs, "summary": summarize(runs),
            "statistics": map_statistics(runs, planners, reference).to_json(), "maps": maps,
            "buckets": bucket_rows(runs, buckets), "extensions": study_pins(planners=planners)}


def frame_entry(scenario: Any) -> dict[str, Any]:
    """The frame a map's positions are reported in (``--json`` ``maps[]``): ``frame`` (a nav2
    map's "map", else "scenario"), the scenario's (0, 0) in it (``origin``) and the start and
    goal in it; the runs' paths stay in the scenario frame (``frame_origin`` on each run)."""
    grid = getattr(scenario, "grid", None)
    if grid is None:
        return {"frame": "scenario", "origin": [0.0, 0.0], "start": list(scenario.start),
                "goal": list(scenario.goal)}
    return {"frame": grid.frame, "origin": list(grid.origin),
            "start": grid.to_map_frame(scenario.start).tolist(),
            "goal": grid.to_map_frame(scenario.goal).tolist()}


# ---------------------------------------------------------------------------------------- plots
def write_plots(cells: Sequence[CellResult], directory: Path,
                buckets: Mapping[str, int] | None = None) -> list[Path]:
    """One PNG per planner x map (every run's path on the map) and one per map (box plots of
    length, gap and planning time): :func:`swarmpath.evidence.plots.write_map_plots`; with
    MovingAI ``buckets`` (map name -> bucket) the difficulty curve ``difficulty.png``."""
    from swarmpath.evidence import plots
    from swarmpath.evidence.buckets import bucket_rows

    scenarios = {c.scenario.name: c.scenario for c in cells}
    seeds = {c.scenario.name: c.seed for c in cells}
    runs = [r for c in cells for r in c.runs]
    out = plots.write_map_plots(
        runs, scenarios, lambda sc, run: simulated_world(sc, seeds[sc.name], run), directory)
    rows = bucket_rows(runs, buckets or {})
    if rows:
        out.append(plots.save_figure(plots.difficulty_figure(rows), directory / "difficulty.png"))
    return out


# -------------------------------------------------------------------------------------- command
def _run_with_progress(spec: PlanSpec, stderr: Console, jobs: int) -> list[CellResult]:
    total = len(spec.cells()) * spec.runs
    columns = (
        TextColumn("{task.description:<12}"),
        BarColumn(),
        TextColumn("runs {task.completed:.0f}/{task.total:.0f}"),
        TextColumn("steps {task.fields[steps]}"),
        TimeElapsedColumn(),
    )
    with Progress(*columns, console=stderr, transient=stderr.is_terminal) as progress:
        task = progress.add_task(f"plan x{jobs}", total=total, steps=0)
        steps = 0

        def on_step(n: int) -> None:
            nonlocal steps
            steps += n
            if steps // 10 != (steps - n) // 10:  # a redraw per 10 steps is plenty
                progress.update(task, steps=steps)

        def on_done(runs: int) -> None:
            progress.update(task, completed=runs)

        cells = run_plan(spec, on_step, jobs, on_done)
        progress.update(task, completed=total, description="done", steps=steps)
    return cells


def _list_maps() -> None:
    from swarmpath.world import get_map, list_maps

    for name in list_maps():
        typer.echo(f"{name:<14} {get_map(name).description}")


def _list_planners() -> None:
    from swarmpath.planners import get_planner, list_planners

    for name in list_planners():
        cls = get_planner(name)
        typer.echo(f"{name:<14} {cls.kind:<7} {cls.description}")


@app.command()
def plan(
    planners: Annotated[
        str, typer.Option("--planners", "-p", help="Comma-separated planner names, or 'all'.")
    ] = "all",
    maps: Annotated[
        str,
        typer.Option("--maps", "-m", help="Comma-separated presets or paths (scenario JSON/YAML, "
                     "nav2 map YAML, MovingAI .map)."),
    ] = "mfb-static",
    runs: Annotated[int, typer.Option(help="Runs per planner x map.")] = 10,
    seed: Annotated[int, typer.Option(help="Study seed; run r uses its own streams of it.")] = 1,
    as_json: Annotated[
        bool, typer.Option("--json", help='Print one JSON document {"runs", "summary"}.')
    ] = False,
    plot: Annotated[
        Path | None,
        typer.Option("--plot", metavar="DIR",
                     help="Write PNGs into DIR: paths per planner x map, box plots per map."),
    ] = None,
    params: Annotated[
        str | None,
        typer.Option(help='Planner parameters: \'{"OMPL-RRTstar": {"time": 0.5}}\'.'),
    ] = None,
    list_maps: Annotated[
        bool, typer.Option("--list-maps", help="List the preset maps and exit.")
    ] = False,
    list_planners: Annotated[
        bool, typer.Option("--list-planners", help="List the registered planners and exit.")
    ] = False,
    jobs: Annotated[
        int,
        typer.Option("--jobs", "-j", help="Processes running the episodes (0: one per CPU). "
                     "Results do not change; planning times are per process."),
    ] = 0,
    reference: Annotated[
        str | None,
        typer.Option("--reference", metavar="NAME", help="Planner the +/=/- markers compare "
                     "against (default: the last one listed)."),
    ] = None,
    start: Annotated[
        str | None, typer.Option("--start", metavar="X,Y", help="Start of every map (metres, "
                                 "in --frame).")
    ] = None,
    goal: Annotated[
        str | None, typer.Option("--goal", metavar="X,Y", help="Goal of every map (metres, in "
                                 "--frame).")
    ] = None,
    frame: Annotated[
        str, typer.Option("--frame", metavar="map|scenario", help="Frame of --start/--goal: "
                          "map (a nav2 map's own frame, its YAML origin honoured; the same as "
                          "scenario for other maps) or scenario (metres from the map's "
                          "lower-left corner).")
    ] = "map",
    resolution: Annotated[
        float | None, typer.Option("--resolution", metavar="M",
                                   help="Cell size of MovingAI .map files (default 1 m).")
    ] = None,
    scen: Annotated[
        Path | None, typer.Option("--scen", metavar="FILE", help="MovingAI .scen: one map per "
                                  "start/goal pair of the .map in --maps, its octile optimum "
                                  "shown beside the exact one.")
    ] = None,
    scen_ids: Annotated[
        str | None, typer.Option("--scen-ids", metavar="I,J,...",
                                 help="Rows of --scen to use (0 = first pair).")
    ] = None,
    optimum_budget: Annotated[
        float, typer.Option("--optimum-budget", metavar="S",
                            help="Seconds the exact optimum of one map may take.")
    ] = DEFAULT_BUDGET,
    max_cells: Annotated[
        int | None, typer.Option("--max-cells", help="Largest grid map accepted (cells; "
                                 "default 4,194,304).")
    ] = None,
    max_obstacles: Annotated[
        int | None, typer.Option("--max-obstacles", help="Most polygons an imported grid map "
                                 "may make (default 5,000).")
    ] = None,
    backend: Annotated[
        str | None, typer.Option("--backend", metavar="numpy|numba", help="The backend "
                                 "parameter of every selected planner that has one (numba: "
                                 "the 'fast' extra; the same runs); a different one in "
                                 "--params is refused.")
    ] = None,
    fmt: TableFormatOpt = "table",
) -> None:
    """Run path planners on maps; print the papers' run tables (Run / Distance / Error / Elapsed
    time) with success, collisions and the gap to the exact optimum."""
    import time

    check_format(fmt, ("table", "latex"))
    if list_maps or list_planners:
        if list_maps:
            _list_maps()
        if list_planners:
            _list_planners()
        return
    stderr = Console(stderr=True)

    def note(text: str) -> None:
        stderr.print(f"swarmpath plan: {text}", highlight=False, markup=False, soft_wrap=True)

    options = make_options(start, goal, resolution, scen, scen_ids, max_cells, max_obstacles,
                           frame)
    spec = make_spec(planners, maps, runs, seed, params, reference, options, optimum_budget,
                     note, backend)
    if not 0 <= jobs <= parallel.MAX_JOBS:
        raise InputError("--jobs", f"{jobs} is not in [0, {parallel.MAX_JOBS}]")
    if plot is not None:
        plot_dir(plot, "--plot")
    spec.optima = compute_optima(spec.maps, spec.optimum_budget, note)
    started = time.perf_counter()
    total = len(spec.cells()) * spec.runs
    from swarmpath.cli.plan_backend import compile_first

    compile_first(note)  # the map kernels once, before the worker processes start
    cells = _run_with_progress(spec, stderr, jobs or min(parallel.usable_cpus(), total))
    seconds = time.perf_counter() - started
    if plot is not None:
        for out in write_plots(cells, plot, spec.buckets):
            stderr.print(f"wrote {out}", highlight=False)
    if as_json:
        sys.stdout.write(json.dumps(document(cells, spec.reference, spec), allow_nan=False)
                         + "\n")
        return
    if fmt == "latex":
        sys.stdout.write(latex_table(cells, spec))
        return
    print_tables(cells, spec, seconds)


def latex_table(cells: Sequence[CellResult], spec: PlanSpec) -> str:
    """The comparison of a study as a booktabs table (one planner: its rows without tests)."""
    from swarmpath.evidence import latex, tables
    from swarmpath.planners.summary import summarize
    from swarmpath.service.summary_stats import map_statistics

    rows = [{**summarize(c.runs)[0], "planner": c.planner, "map": c.scenario.name}
            for c in cells]
    doc = map_statistics(rows, [c.runs for c in cells], spec.planners, spec.reference)
    reference = doc["reference"] if len(spec.planners) > 1 else None
    grid = tables.map_grid(rows, spec.planners, reference)
    maps = ", ".join(dict.fromkeys(c.scenario.name for c in cells))
    caption = (f"swarmpath plan: {maps}; {spec.runs} runs per planner and map, seed {spec.seed}."
               " Length and gap over successful runs, time: planning wall time.")
    if reference:
        caption += (f" Against {reference}: superscript +/=/- significantly better / no "
                    "difference / worse (success: Fisher's exact test; length, gap, time: "
                    "two-sided Wilcoxon rank-sum test; each Holm-adjusted, alpha 0.05); A12: "
                    "Vargha-Delaney effect size; P(b/e/w): posterior probabilities of better / "
                    "practically equivalent / worse (Bayesian bootstrap of the mean, rope 1 % "
                    "of the larger value).")
    return latex.grid_to_latex(grid, caption, "tab:swarmpath-plan")
