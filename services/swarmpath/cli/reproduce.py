"""``swarmpath reproduce``: run a seed paper's table at the paper's setting and set it beside
the published one (:mod:`swarmpath.evidence.reference` holds the tables,
:mod:`swarmpath.evidence.reproduction` and :mod:`swarmpath.evidence.verdicts` the verdicts).

Benchmark tables run through ``swarmpath bench``'s own functions (same spec, same seed, same
numbers), and again shifted (``--transform shift``, the same runs and seeds) to mark the cells
whose result owes more than 3 decades to where the optimum was; map tables run through
``swarmpath plan``'s (:mod:`swarmpath.cli.reproduce_run`). With ``--url`` the study is submitted
as one job to a running coordinator and its runs are read back.
"""

from __future__ import annotations

import json
import shlex
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Annotated, Any

import typer

from swarmpath import __version__
from swarmpath.cli import parallel
from swarmpath.cli.core import InputError, app
from swarmpath.cli.reproduce_added import (
    added_statistics,
    markdown_added,
    parse_added,
    print_added,
)
from swarmpath.cli.reproduce_run import (
    cells_from_runs,
    run_benchmark_local,
    run_map_local,
    run_remote,
)
from swarmpath.cli.study_options import BackendOpt
from swarmpath.evidence import reference, report, reproduction, reproduction_maps
from swarmpath.provenance import numeric_platform

FORMATS = ("table", "markdown", "csv", "latex")


def resolve_tables(name: str | None) -> list[str]:
    if name is None:
        raise InputError("TABLE", f"name a table ({', '.join(reference.TABLES)}) or use --list")
    if name.strip().lower() == "all":
        return list(reference.TABLES)
    names = [n.strip() for n in name.split(",") if n.strip()]
    for n in names:
        if n not in reference.TABLES:
            raise InputError("TABLE", f"unknown table {n!r}; reproducible: "
                                      f"{', '.join(reference.TABLES)}")
    if not names:
        raise InputError("TABLE", "no table given")
    return list(dict.fromkeys(names))


def _subset(option: str, given: str | None, names: Sequence[str]) -> list[str]:
    """``given`` (comma-separated) as a subset of ``names`` in table order (all when None)."""
    if given is None:
        return list(names)
    wanted = [n.strip() for n in given.split(",") if n.strip()]
    unknown = [n for n in wanted if n not in names]
    if unknown or not wanted:
        raise InputError(option, f"{', '.join(unknown) or 'nothing'} is not a column of the "
                                 f"table ({', '.join(names)})")
    return [n for n in names if n in wanted]


def study_setting(table: reference.Table, runs: int | None, seed: int,
                  backend: str = "auto", algorithms: str | None = None,
                  functions: str | None = None, add: str | None = None) -> dict[str, Any]:
    """The study run for ``table``: the paper's setting, runs lowered by ``--runs``, cells
    narrowed by ``--algorithms``/``--functions``; a backend other than ``auto`` (the default:
    the reference's numbers, compiled where it can) is part of the setting."""
    from swarmpath.optimizers.api import BACKENDS

    if backend not in BACKENDS:
        raise InputError("--backend", f"{backend!r} is not one of {', '.join(BACKENDS)}")
    paper_runs = int(table.setting["runs"])
    if runs is not None and not 1 <= runs <= paper_runs:
        raise InputError("--runs", f"{runs} is not in [1, {paper_runs}] (the paper's count)")
    if seed < 0:
        raise InputError("--seed", f"{seed} is negative")
    n = paper_runs if runs is None else runs
    if isinstance(table, reference.BenchmarkTable):
        columns = _subset("--algorithms", algorithms, table.algorithms)
        added = parse_added(add, table)  # reproduce_added: measured beside the table
        setting: dict[str, Any] = {
            "kind": "benchmark", "algorithms": [*columns, *added],
            "functions": _subset("--functions", functions, table.functions),
            "dims": [table.dim], "runs": n,
            "agents": int(table.setting["agents"]),
            "iterations": int(table.setting["iterations"]), "seed": seed,
        }
        for key in ("budget_evals", "instances"):  # the suites' settings (docs/functions.md)
            if table.setting.get(key) is not None:
                setting[key] = table.setting[key]
        if backend == "numba":
            from swarmpath.optimizers import ParameterError
            from swarmpath.optimizers.api import check_backend

            try:
                check_backend(backend, setting["algorithms"])
                check_backend(backend, setting["algorithms"], "shift")
            except ParameterError as exc:
                raise InputError("--backend", f"{table.name}: {exc}") from None
        if backend != "auto":
            setting["backend"] = backend
        if added:
            setting["added"] = added
        return setting
    if backend == "numba":
        raise InputError("--backend", f"{table.name} is a map table: planners run on numpy only")
    if add is not None:
        raise InputError("--add", f"{table.name} is a map table: --add adds optimizers to "
                                  "benchmark tables")
    for option, given in (("--algorithms", algorithms), ("--functions", functions)):
        if given is not None:
            raise InputError(option, f"{table.name} is a map table: it has no {option[2:]}")
    return {"kind": "map", "planners": list(table.planners), "maps": list(table.maps),
            "runs": n, "seed": seed}


def _suites(setting: dict[str, Any]) -> bool:
    """Whether the study runs suite functions (their instance already moves the optimum: no
    origin check)."""
    from swarmpath.functions import expand_function_names, get_function

    return any(getattr(get_function(f), "suite", "") for f in
               expand_function_names(",".join(setting["functions"])))


# ------------------------------------------------------------------------------- reproduction
Result = tuple[reference.Table, dict[str, Any], list[reproduction.Row], dict[str, Any] | None,
               dict[str, str | None]]


def reproduce_table(name: str, runs: int | None, seed: int, jobs: int, url: str | None,
                    backend: str = "auto", origin_check: bool = True,
                    algorithms: str | None = None, functions: str | None = None,
                    add: str | None = None) -> Result:
    """Run one table's study (benchmark tables: also shifted when ``origin_check``); returns
    (table, setting, rows, statistics json, markers)."""
    table = reference.load(name)
    setting = study_setting(table, runs, seed, backend, algorithms, functions, add)
    started = time.perf_counter()
    measured: list[Any]
    shifted: list[report.Cell] | None = None
    if isinstance(table, reference.BenchmarkTable):
        job = {k: v for k, v in setting.items() if k != "added"}  # a job spec's fields
        measured = (cells_from_runs(run_remote(job, url)) if url
                    else run_benchmark_local(setting, jobs))
        if setting.get("instances"):  # a table's function is its instances pooled (COCO)
            from swarmpath.evidence.instances import pool_instances

            measured = pool_instances(measured)
        if origin_check and not _suites(setting):  # the same runs, the optimum moved
            moved = {**job, "transform": "shift", "algorithms": [  # the table's columns
                a for a in job["algorithms"] if a not in setting.get("added", ())]}
            shifted = (cells_from_runs(run_remote(moved, url)) if url
                       else run_benchmark_local(moved, jobs))
            setting["origin_check"] = "shift"
    else:
        measured = run_remote(setting, url) if url else run_map_local(setting, jobs)
    setting["seconds"] = round(time.perf_counter() - started, 1)
    return judge(table, setting, measured, shifted)


def judge(table: reference.Table, setting: dict[str, Any], measured: Sequence[Any],
          shifted: Sequence[report.Cell] | None = None) -> Result:
    """Verdicts, statistics and markers for measured benchmark cells (``report.Cell``; and the
    same cells shifted, for the origin check) or map run outcomes (dicts with planner, map,
    success, length, ...), with the current reasons."""
    reasons = reference.load_reasons()
    markers: dict[str, str | None] = {}
    statistics: dict[str, Any] | None = None
    if isinstance(table, reference.BenchmarkTable):
        added = list(setting.get("added") or [])
        cells: list[report.Cell] = [c for c in measured if c.algorithm not in added]
        by_cell = {(c.function, c.algorithm): c.best_fitness for c in cells}
        moved = (None if shifted is None else
                 {(c.function, c.algorithm): c.best_fitness for c in shifted})
        rows = reproduction.benchmark_rows(table, by_cell, reasons, moved)
        stats = report.statistics(cells, list(table.algorithms))
        statistics = report.tests_to_json(stats)
        if any(c.curves for c in cells):  # run here (not --from, --url): the anytime view
            from swarmpath.evidence import anytime

            statistics["anytime"] = anytime.groups_to_json(anytime.study_groups(
                cells, int(setting["agents"]), int(setting["iterations"])))
        for c in cells:
            markers[reference.cell_key(table.name, c.algorithm, c.function, c.dim)] = (
                stats.marker(c))
        if added:  # beside the table, against its proposed (last measured) column
            own = [a for a in setting["algorithms"] if a not in added]
            statistics["added"] = added_statistics(list(measured), added, own[-1])
    else:
        from swarmpath.world import get_map

        grouped: dict[tuple[str, str], list[dict[str, Any]]] = {}
        for r in measured:
            grouped.setdefault((r["planner"], r["map"]), []).append(r)
        scenarios = {m: get_map(m) for m in table.maps}
        rows = reproduction_maps.map_rows(table, grouped, reasons, scenarios)
        if len(table.planners) > 1:
            from swarmpath.evidence import compare

            samples: dict[str, dict[str, list[float]]] = {r.where: {} for r in rows}
            for r in rows:
                samples[r.where][r.who] = r.runs
            comparison = compare.compare_samples(samples, list(table.planners))
            statistics = {"comparison": comparison.to_json(("map",))}
            for r in rows:
                markers[r.key] = comparison.marker(r.where, r.who)
    return table, setting, rows, statistics, markers


def from_document(doc: dict[str, Any]) -> Result:
    """Judge again the runs of an earlier ``--json`` document (same numbers; current reasons)."""
    name = doc.get("table")
    if name not in reference.TABLES:
        raise InputError("--from", f"not a reproduce document of a known table: {name!r}")
    table = reference.load(name)
    measured: list[Any] = []
    shifted: list[report.Cell] = []
    for c in doc["cells"]:
        if table.kind == "benchmark":
            measured.append(_saved_cell(c, c["runs"]))
            if "shifted_runs" in c:
                shifted.append(_saved_cell(c, c["shifted_runs"]))
        else:
            measured += [{**o, "planner": c["planner"], "map": c["map"]}
                         for o in c["outcomes"]]
    for c in ((doc.get("statistics") or {}).get("added") or {}).get("cells", []):
        measured.append(_saved_cell(c, c["runs"]))  # --add's cells, beside the table
    return judge(table, dict(doc["setting"]), measured, shifted or None)


def _saved_cell(c: dict[str, Any], runs: Sequence[Any]) -> report.Cell:
    values = [float(v) for v in runs]
    return report.Cell(algorithm=c["algorithm"], function=c["function"], dim=int(c["dim"]),
                       run_ids=list(range(len(values))), best_fitness=values,
                       evaluations=[0] * len(values), seconds=0.0)


def command_line(name: str, runs: int | None, seed: int, fmt: str, backend: str = "auto",
                 options: Sequence[str] = ()) -> str:
    parts = ["swarmpath", "reproduce", name]
    if runs is not None:
        parts += ["--runs", str(runs)]
    if seed != 1:
        parts += ["--seed", str(seed)]
    if backend != "auto":
        parts += ["--backend", backend]
    parts += list(options)
    if fmt != "table":
        parts += ["--format", fmt]
    return shlex.join(parts)


def narrowing(table: reference.Table, setting: dict[str, Any]) -> list[str]:
    """The options that narrowed a benchmark study (cells, origin check), as typed."""
    if not isinstance(table, reference.BenchmarkTable):
        return []
    out = []
    added = list(setting.get("added") or [])
    for option, key, names in (("--algorithms", "algorithms", table.algorithms),
                               ("--functions", "functions", table.functions)):
        given = [n for n in setting.get(key, names) if n not in added]
        if given != list(names):
            out += [option, ",".join(given)]
    if added:
        out += ["--add", ",".join(added)]
    if "origin_check" not in setting and not _suites(setting):
        out.append("--no-origin-check")
    return out


@app.command()
def reproduce(
    table: Annotated[
        str | None,
        typer.Argument(metavar="TABLE", help="A table of --list, several joined by commas, "
                                            "or 'all'."),
    ] = None,
    list_: Annotated[
        bool, typer.Option("--list", help="Name the reproducible tables and exit.")
    ] = False,
    runs: Annotated[
        int | None, typer.Option(help="Runs per cell (default: the paper's count).")
    ] = None,
    seed: Annotated[int, typer.Option(help="Study seed, as for bench and plan.")] = 1,
    jobs: Annotated[
        int, typer.Option("--jobs", "-j", help="Local processes (0: one per CPU).")
    ] = 0,
    url: Annotated[
        str | None, typer.Option(help="Run as a job on this coordinator (http://host:port).")
    ] = None,
    fmt: Annotated[str, typer.Option("--format", help="table, markdown, csv or latex.")] = "table",
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON document.")] = False,
    out: Annotated[
        Path | None, typer.Option(help="Also write DIR/<table>.md, DIR/<table>.png and, for a "
                                   "benchmark table run here, DIR/<table>-anytime/*.png.")
    ] = None,
    from_: Annotated[
        Path | None,
        typer.Option("--from", help="Judge the runs of an earlier --json output again "
                                    "(no study is run; reasons as they are now)."),
    ] = None,
    backend: BackendOpt = "auto",
    algorithms: Annotated[
        str | None, typer.Option("--algorithms", "-a", help="Only these columns of a "
                                 "benchmark table (comma-separated; default: all).")
    ] = None,
    functions: Annotated[
        str | None, typer.Option("--functions", "-f", help="Only these rows of a benchmark "
                                 "table (comma-separated; default: all).")
    ] = None,
    origin_check: Annotated[
        bool, typer.Option("--origin-check/--no-origin-check", help="Also run benchmark "
                           "tables shifted (same runs and seeds) and mark the cells that lose "
                           "more than 3 decades (origin-suspect).")
    ] = True,
    add: Annotated[
        str | None, typer.Option("--add", metavar="NAMES", help="Also run these optimizers "
                                 "(built-in or plugin, comma-separated) at a benchmark "
                                 "table's setting: measured beside it, no verdict, markers "
                                 "against the table's proposed algorithm (table, markdown, "
                                 "--json).")
    ] = None,
) -> None:
    """Run a seed paper's table at its setting; print published beside measured, with verdicts."""
    from swarmpath.cli import reproduce_output as output

    if list_:
        for name in reference.TABLES:
            typer.echo(name)
        return
    if fmt not in FORMATS:
        raise InputError("--format", f"{fmt!r} is not one of {', '.join(FORMATS)}")
    if not 0 <= jobs <= parallel.MAX_JOBS:
        raise InputError("--jobs", f"{jobs} is not in [0, {parallel.MAX_JOBS}]")
    results: list[Result] = []
    if from_ is not None and (table is not None or runs is not None or url is not None
                              or backend != "auto" or algorithms is not None
                              or functions is not None or not origin_check
                              or add is not None):
        raise InputError("--from", "judges saved runs: give no TABLE, --runs, --url, "
                                   "--backend, --algorithms, --functions, --add or "
                                   "--no-origin-check with it")
    if add is not None and fmt in ("csv", "latex") and not as_json:
        raise InputError("--add", f"the added columns print in table and markdown formats "
                                  f"and --json, not --format {fmt}")
    if from_ is not None:
        try:
            loaded = json.loads(from_.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise InputError("--from", f"{from_}: {exc}") from None
        previous = loaded if isinstance(loaded, list) else [loaded]
        try:
            results = [from_document(d) for d in previous]
        except (KeyError, TypeError, ValueError) as exc:
            if isinstance(exc, InputError):
                raise
            raise InputError("--from", f"{from_}: not a reproduce document ({exc})") from None
        names = [r[0].name for r in results]
    else:
        names = resolve_tables(table)
        for name in names:  # validate every table's options before running anything
            study_setting(reference.load(name), runs, seed, backend, algorithms, functions, add)
    options = [*(["--algorithms", algorithms] if algorithms else []),
               *(["--functions", functions] if functions else []),
               *(["--add", add] if add else []),
               *([] if origin_check else ["--no-origin-check"])]
    if fmt == "markdown" and not as_json:
        whole = table if table is not None else (
            "all" if names == list(reference.TABLES) else ",".join(names))
        sys.stdout.write(output.markdown_header(  # --from: each section names its command
            command_line(whole, runs, seed, fmt, backend, options), __version__,
            None if from_ is None else from_.name))
    docs = []
    for i, name in enumerate(names):
        tab, setting, rows, statistics, markers = (
            results[i] if results else reproduce_table(name, runs, seed, jobs, url, backend,
                                                       origin_check, algorithms, functions,
                                                       add))
        if results:
            runs, seed = int(setting["runs"]), int(setting["seed"])
            backend = str(setting.get("backend", "auto"))
            options = narrowing(tab, setting)
        doc = reproduction.document(tab, setting, rows, statistics)
        doc["version"] = __version__
        doc["platform"] = numeric_platform()
        docs.append(doc)
        if out is not None:
            output.write_outputs(out, tab, setting, rows, markers,
                                 command_line(name, runs, seed, "markdown", backend, options),
                                 statistics)
        if as_json:
            continue
        if fmt == "markdown":
            sys.stdout.write(output.markdown(tab, setting, rows, markers,
                                             command_line(name, runs, seed, fmt, backend,
                                                          options))
                             + markdown_added(statistics))
        elif fmt == "csv":
            sys.stdout.write(output.csv_text(tab, rows, markers))
        elif fmt == "latex":
            sys.stdout.write(output.latex_table(tab, setting, rows, markers))
        else:
            output.print_rich(tab, setting, rows, markers)
            print_added(statistics)
    if as_json:
        sys.stdout.write(json.dumps(docs[0] if len(docs) == 1 else docs, allow_nan=False)
                         + "\n")
