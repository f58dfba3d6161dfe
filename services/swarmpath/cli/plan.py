"""``swarmpath plan``: planners x maps x runs, printed as the papers' run tables.

For each planner and map it runs ``--runs`` episodes (run r of ``--seed`` s is the same path on
any machine, see :mod:`swarmpath.planners.episode`) and prints Run / Distance / Error / Elapsed
time plus success, collisions and the gap to the exact optimum, with a Mean row. ``--json``
prints ``{"runs": [...], "summary": [...]}`` (the summary from
:func:`swarmpath.planners.summary.summarize`), ``--plot DIR`` writes one PNG per planner x map
(:mod:`swarmpath.plots`) and box plots of length, gap and time per map.

``--maps`` takes preset names (``--list-maps``) and paths: scenario JSON/YAML, ROS map_server /
nav2 YAML (recognised by its ``image`` key) or MovingAI ``.map`` files (one metre per cell).
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

import typer
from rich import box
from rich.console import Console
from rich.measure import Measurement
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from swarmpath.cli import parallel
from swarmpath.cli.core import (
    InputError,
    InputErrors,
    app,
    parse_params_option,
    plot_dir,
    resolve_names,
)
from swarmpath.legend import legend_text

MAX_RUNS = 10_000
MAP_SUFFIXES = (".json", ".yaml", ".yml", ".map")


@dataclass
class PlanSpec:
    planners: list[str]
    maps: list[Any]  # Scenario objects, in order, with distinct names
    runs: int = 10
    seed: int = 1
    params: dict[str, dict[str, Any]] = field(default_factory=dict)
    #: the planner the statistical tests compare against (None: the last of ``planners``)
    reference: str | None = None

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
    """'ICOOT,mfb' -> registered names (case-insensitive, duplicates dropped); 'all' = all."""
    from swarmpath.planners import list_planners

    return resolve_names(spec, list_planners(), "--planners", "planner")


def load_map(item: str) -> Any:
    """A preset by name, or a scenario / nav2 / MovingAI file; raises InputError('--maps')."""
    from swarmpath.world import get_map, list_maps

    presets = list_maps()
    by_lower = {m.lower(): m for m in presets}
    if item in presets or item.lower() in by_lower:
        return get_map(item if item in presets else by_lower[item.lower()])
    path = Path(item)
    if not path.is_file():
        hint = "no such file" if path.suffix.lower() in MAP_SUFFIXES else "unknown map"
        raise InputError(
            "--maps",
            f"{hint} {item!r}; presets: {', '.join(presets)}; or a path to a scenario "
            "JSON/YAML, nav2 map YAML or MovingAI .map file",
        )
    try:
        return _load_file(path)
    except InputError:
        raise
    except (ValueError, KeyError, OSError) as exc:  # ScenarioError, MapImportError, ...
        problems = getattr(exc, "problems", None)
        if problems:  # a scenario file: one line per problem
            raise InputErrors([("--maps", f"{item}: {p}: {m}" if p else f"{item}: {m}")
                               for p, m in problems]) from None
        raise InputError("--maps", f"{item}: {exc}") from None


def _load_file(path: Path) -> Any:
    import yaml

    from swarmpath.world.importers import load_movingai_map, load_ros_map
    from swarmpath.world.scenario_io import load_scenario, scenario_from_dict

    suffix = path.suffix.lower()
    if suffix == ".map":
        return load_movingai_map(path).scenario
    if suffix in (".yaml", ".yml"):
        try:
            doc = yaml.safe_load(path.read_text(encoding="utf-8"))
        except yaml.YAMLError as exc:
            raise InputError("--maps", f"{path}: not valid YAML ({exc})") from None
        if isinstance(doc, dict) and "image" in doc:
            return load_ros_map(path).scenario
        if not isinstance(doc, dict):
            raise InputError("--maps", f"{path}: expected a YAML mapping")
        return scenario_from_dict(doc, str(path))
    return load_scenario(path)


def resolve_maps(spec: str) -> list[Any]:
    maps: list[Any] = []
    names: set[str] = set()
    for item in _names(spec):
        scenario = load_map(item)
        name, k = scenario.name, 2
        while name in names:  # two files with the same scenario name: keep them apart
            name, k = f"{scenario.name}#{k}", k + 1
        if name != scenario.name:
            scenario = dataclasses.replace(scenario, name=name)
        names.add(name)
        maps.append(scenario)
    if not maps:
        raise InputError("--maps", "no map given")
    return maps


def parse_params(text: str | None, planners: Sequence[str]) -> dict[str, dict[str, Any]]:
    """'{"OMPL-RRTstar": {"time": 0.5}}' -> params per planner, each checked by the planner."""
    from swarmpath.planners import get_planner

    return parse_params_option(
        text, planners, "--planners", '{"MFB": {"agents": 10}}',
        lambda name, values: get_planner(name).resolve_params(values),
    )


def make_spec(planners: str, maps: str, runs: int = 10, seed: int = 1,
              params: str | None = None, reference: str | None = None) -> PlanSpec:
    """Validate the command's options; raises :class:`InputError` naming the bad one."""
    from swarmpath.compare import resolve_reference

    names = resolve_planners(planners)
    try:
        ref = resolve_reference(names, reference)
    except ValueError as exc:
        raise InputError("--reference", str(exc)) from None
    scenarios = resolve_maps(maps)
    if not 1 <= runs <= MAX_RUNS:
        raise InputError("--runs", f"{runs} is not in [1, {MAX_RUNS}]")
    if seed < 0:
        raise InputError("--seed", f"{seed} is negative")
    return PlanSpec(names, scenarios, runs, seed, parse_params(params, names), ref)


# -------------------------------------------------------------------------------------- running
def run_episode(spec: PlanSpec, planner: str, scenario: Any, run: int,
                on_step: Callable[[], None] | None = None) -> dict[str, Any]:
    """One run as a JSON-ready dict (``RunOutcome`` fields).

    A planner that raises (a bug: planners report failures as results) gives a failed run whose
    reason names the exception; the error is also noted on stderr.
    """
    from swarmpath.planners import Episode

    ep = None
    try:
        ep = Episode(scenario, planner, spec.seed, run, spec.params.get(planner))
        while not ep.done:
            ep.step()
            if on_step is not None:
                on_step()
        return ep.outcome().to_dict()
    except Exception as exc:  # recorded as a failed run, never hidden
        reason = f"internal error: {type(exc).__name__}: {exc}"
        typer.echo(f"swarmpath plan: warning: {planner} on {scenario.name} run {run}: {reason}",
                   err=True)
        if ep is not None:
            try:
                out = ep.outcome().to_dict()
                out.update(success=False, reason=reason)
                return out
            except Exception:
                pass
        return {
            "planner": planner, "map": scenario.name, "run": run, "seed": spec.seed,
            "success": False, "reason": reason, "collisions": 0, "length": 0.0,
            "error": math.dist(scenario.start, scenario.goal), "smoothness": 0.0,
            "ompl_smoothness": 0.0, "min_clearance": None, "steps": 0, "iterations": 0,
            "seconds": 0.0, "travel_time": 0.0, "optimum": None, "gap": None,
            "planned_length": None, "robot_driven_contacts": 0, "obstacle_driven_contacts": 0,
            "path": [[float(scenario.start[0]), float(scenario.start[1]), 0.0]],
        }


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
    tasks = [(spec, i, run) for i in range(len(spec.cells())) for run in range(spec.runs)]
    finished = 0

    def done(_task: Any) -> None:
        nonlocal finished
        finished += 1
        if on_done is not None:
            on_done(finished)

    outcomes = parallel.run_tasks(_episode, tasks, jobs, on_step, done)
    cells = []
    for i, (planner, scenario) in enumerate(spec.cells()):
        runs = outcomes[i * spec.runs:(i + 1) * spec.runs]
        cells.append(CellResult(planner, scenario, runs, spec.seed))
    return cells


def _episode(task: tuple[PlanSpec, int, int], report: Callable[[int], None]) -> dict[str, Any]:
    """One run of one cell as a JSON-ready dict (in a child process or here)."""
    from swarmpath.planners.summary import json_safe

    spec, index, run = task
    planner, scenario = spec.cells()[index]
    return dict(json_safe(run_episode(spec, planner, scenario, run, lambda: report(1))))


def simulated_world(scenario: Any, seed: int, run: int) -> Any:
    """The moving obstacles and goal of run ``run`` as its simulator saw them (the episode draws
    its world from stream (seed, run, SIMULATION)): for the plots, rebuilt when one is drawn
    rather than sent back from the process that ran the episode."""
    from swarmpath.optimizers.streams import SIMULATION, run_generator

    return scenario.instantiate(run_generator(seed, run, SIMULATION))


def document(cells: Sequence[CellResult], reference: str | None = None) -> dict[str, Any]:
    """The ``--json`` document: exactly {"runs": [...], "summary": [...], "statistics": {...}}
    (statistics: :meth:`swarmpath.compare_maps.MapStatistics.to_json`)."""
    from swarmpath.compare_maps import map_statistics
    from swarmpath.planners.summary import summarize

    runs = [r for c in cells for r in c.runs]
    planners = list(dict.fromkeys(c.planner for c in cells))
    return {"runs": runs, "summary": summarize(runs),
            "statistics": map_statistics(runs, planners, reference).to_json()}


# --------------------------------------------------------------------------------------- tables
def _num(v: Any, digits: int = 4) -> str:
    return "-" if v is None else f"{float(v):.{digits}f}"


def _causes(r: dict[str, Any]) -> str:
    """Collisions by cause, robot-driven / obstacle-driven (see metrics.contact_causes)."""
    return f"{r.get('robot_driven_contacts') or 0}/{r.get('obstacle_driven_contacts') or 0}"


def render_cell(cell: CellResult, row: dict[str, Any]) -> Table:
    """The paper-style run table of one planner x map (``row``: its summary)."""
    optimum = row["optimum"]
    title = f"{cell.planner} on {cell.scenario.name}"
    title += f" (exact optimum {optimum:.4f} m)" if optimum is not None else " (no exact optimum)"
    table = Table(title=title, box=box.SIMPLE_HEAD, pad_edge=False)
    for name in ("Run", "Distance (m)", "Error (m)", "Elapsed time (s)", "Success",
                 "Collisions", "Robot/obstacle-driven", "Gap (%)", "Steps", "Iterations"):
        table.add_column(name, justify="left" if name == "Success" else "right", no_wrap=True)
    planned = any(r.get("planned_length") is not None for r in cell.runs)
    if planned:  # global planners: the length they planned beside the one driven
        table.add_column("Planned (m)", justify="right", no_wrap=True)
    failed = any(not r["success"] for r in cell.runs)
    if failed:
        table.add_column("Reason")
    for r in cell.runs:
        gap = None if r["gap"] is None else 100.0 * r["gap"]
        cols = [str(r["run"] + 1), _num(r["length"]), _num(r["error"]), _num(r["seconds"], 3),
                "yes" if r["success"] else "no", str(r["collisions"]), _causes(r), _num(gap, 2),
                str(r["steps"]), str(r["iterations"])]
        if planned:
            cols.append(_num(r.get("planned_length")))
        if failed:
            cols.append("" if r["success"] else str(r["reason"]))
        table.add_row(*cols)
    gap_mean = None if row["gap_mean"] is None else 100.0 * row["gap_mean"]
    mean = ["Mean", _num(row["length_mean"]), _num(row["error_mean"]), _num(row["seconds_mean"], 3),
            f"{row['successes']}/{row['runs']}", str(row["collisions"]), _causes(row),
            _num(gap_mean, 2),
            f"{row['steps_mean']:.1f}", f"{row['iterations_mean']:.0f}"]
    if planned:
        mean.append("")
    if failed:
        mean.append("")
    table.add_row(*mean, style="bold", end_section=True)
    return table


def print_tables(cells: Sequence[CellResult], spec: PlanSpec, seconds: float) -> None:
    from swarmpath.planners.summary import summarize

    console = Console()
    tables = []
    for cell in cells:
        tables.append(render_cell(cell, summarize(cell.runs)[0]))
    if not console.is_terminal:  # pipes and files: never squeeze the numbers
        widest = max(Measurement.get(console, console.options.update(width=100_000), t).maximum
                     for t in tables)
        console = Console(width=max(80, widest))
    for t in tables:
        console.print(t)
    console.print(
        f"{spec.runs} runs per planner x map, seed {spec.seed}; Distance = executed path length "
        "(Planned: the global planner's plan), Robot/obstacle-driven = colliding steps where the "
        "robot moved into the obstacle / a moving obstacle reached a still or retreating robot, "
        "Error = final distance to the goal, Elapsed time = "
        "planning wall time; the Mean row averages Distance and Gap over successful runs; "
        f"{seconds:.1f} s",
        highlight=False,
    )
    console.print(legend_text(["Collisions", "Gap (%)"]), markup=False, highlight=False)
    if len(spec.planners) > 1:
        from swarmpath.cli import plan_stats
        from swarmpath.compare_maps import map_statistics

        runs = [r for c in cells for r in c.runs]
        tests = map_statistics(runs, spec.planners, spec.reference)
        console.print(plan_stats.render_comparison(tests, summarize(runs), spec.planners))
        console.print(plan_stats.render_counts(tests, spec.planners))
        for line in plan_stats.lines(tests):
            console.print(line, highlight=False)


# ---------------------------------------------------------------------------------------- plots
def write_plots(cells: Sequence[CellResult], directory: Path) -> list[Path]:
    """One PNG per planner x map (every run's path on the map) and one per map (box plots of
    length, gap and planning time): :func:`swarmpath.plots.write_map_plots`."""
    from swarmpath import plots

    scenarios = {c.scenario.name: c.scenario for c in cells}
    seeds = {c.scenario.name: c.seed for c in cells}
    runs = [r for c in cells for r in c.runs]
    return plots.write_map_plots(
        runs, scenarios, lambda sc, run: simulated_world(sc, seeds[sc.name], run), directory)


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
) -> None:
    """Run path planners on maps; print the papers' run tables (Run / Distance / Error / Elapsed
    time) with success, collisions and the gap to the exact optimum."""
    import time

    if list_maps or list_planners:
        if list_maps:
            _list_maps()
        if list_planners:
            _list_planners()
        return
    spec = make_spec(planners, maps, runs, seed, params, reference)
    if not 0 <= jobs <= parallel.MAX_JOBS:
        raise InputError("--jobs", f"{jobs} is not in [0, {parallel.MAX_JOBS}]")
    if plot is not None:
        plot_dir(plot, "--plot")
    stderr = Console(stderr=True)
    started = time.perf_counter()
    total = len(spec.cells()) * spec.runs
    cells = _run_with_progress(spec, stderr, jobs or min(parallel.usable_cpus(), total))
    seconds = time.perf_counter() - started
    if plot is not None:
        for out in write_plots(cells, plot):
            stderr.print(f"wrote {out}", highlight=False)
    if as_json:
        sys.stdout.write(json.dumps(document(cells, spec.reference), allow_nan=False) + "\n")
        return
    print_tables(cells, spec, seconds)
