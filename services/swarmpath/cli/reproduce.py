"""``swarmpath reproduce``: run a seed paper's table at the paper's setting and set it beside
the published one (:mod:`swarmpath.evidence.reference` holds the tables,
:mod:`swarmpath.evidence.reproduction`
the verdicts).

Benchmark tables run through ``swarmpath bench``'s own functions (same spec, same seed, same
numbers); map tables through ``swarmpath plan``'s. With ``--url`` the study is submitted as one
job to a running coordinator and its runs are read back.
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
from rich.console import Console

from swarmpath import __version__
from swarmpath.cli import parallel
from swarmpath.cli.core import InputError, app
from swarmpath.cli.study_options import BackendOpt
from swarmpath.evidence import reference, report, reproduction
from swarmpath.provenance import numeric_platform

FORMATS = ("table", "markdown", "csv")


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


def study_setting(table: reference.Table, runs: int | None, seed: int,
                  backend: str = "numpy") -> dict[str, Any]:
    """The study run for ``table``: the paper's setting, runs lowered by ``--runs``; a backend
    other than the reference (numpy) is part of the setting."""
    paper_runs = int(table.setting["runs"])
    if runs is not None and not 1 <= runs <= paper_runs:
        raise InputError("--runs", f"{runs} is not in [1, {paper_runs}] (the paper's count)")
    if seed < 0:
        raise InputError("--seed", f"{seed} is negative")
    n = paper_runs if runs is None else runs
    if isinstance(table, reference.BenchmarkTable):
        setting = {
            "kind": "benchmark", "algorithms": list(table.algorithms),
            "functions": list(table.functions), "dims": [table.dim], "runs": n,
            "agents": int(table.setting["agents"]),
            "iterations": int(table.setting["iterations"]), "seed": seed,
        }
        if backend != "numpy":
            from swarmpath.optimizers import ParameterError
            from swarmpath.optimizers.api import check_backend

            try:
                check_backend(backend, setting["algorithms"])
            except ParameterError as exc:
                raise InputError("--backend", f"{table.name}: {exc}") from None
            setting["backend"] = backend
        return setting
    if backend != "numpy":
        raise InputError("--backend", f"{table.name} is a map table: planners run on numpy only")
    return {"kind": "map", "planners": list(table.planners), "maps": list(table.maps),
            "runs": n, "seed": seed}


# ------------------------------------------------------------------------------------ running
def run_benchmark_local(setting: dict[str, Any], jobs: int) -> list[report.Cell]:
    from swarmpath.cli import bench
    from swarmpath.cli.bench_spec import make_spec

    spec = make_spec(
        ",".join(setting["algorithms"]), ",".join(setting["functions"]),
        ",".join(str(d) for d in setting["dims"]), runs=setting["runs"],
        agents=setting["agents"], iterations=setting["iterations"], seed=setting["seed"],
        backend=setting.get("backend", "numpy"),
    )
    stderr = Console(stderr=True)
    return bench._run_with_progress(spec, stderr, jobs or bench.auto_jobs(spec))


def run_map_local(setting: dict[str, Any], jobs: int) -> list[dict[str, Any]]:
    from swarmpath.cli import plan

    spec = plan.make_spec(",".join(setting["planners"]), ",".join(setting["maps"]),
                          runs=setting["runs"], seed=setting["seed"])
    stderr = Console(stderr=True)
    cells = plan._run_with_progress(spec, stderr, jobs or parallel.usable_cpus())
    return [r for c in cells for r in c.runs]


def run_remote(setting: dict[str, Any], url: str) -> list[dict[str, Any]]:
    """Submit the study as one job, wait for it, return its runs (ServiceError/exit on failure)."""
    from swarmpath.cli import service as svc

    with svc._client(url) as client:
        try:
            job = client.submit(setting)
            status = svc._wait_with_progress(client, job["id"], job["runs_total"])
            if status["state"] != "done":
                typer.echo(f"swarmpath reproduce: error: job {job['id']} ended "
                           f"{status['state']}", err=True)
                raise typer.Exit(1)
            return client.all_runs(job["id"])
        except typer.Exit:
            raise
        except Exception as exc:
            svc._fail(exc)
            raise


def cells_from_runs(runs: Sequence[dict[str, Any]]) -> list[report.Cell]:
    """Benchmark runs read back from the service -> bench's cells (runs in order)."""
    groups: dict[tuple[str, str, int], list[dict[str, Any]]] = {}
    for r in runs:
        groups.setdefault((r["algorithm"], r["function"], int(r["dim"])), []).append(r)
    out = []
    for (algorithm, function, dim), items in groups.items():
        items.sort(key=lambda r: int(r["run"]))
        out.append(report.Cell(
            algorithm=algorithm, function=function, dim=dim,
            run_ids=[int(r["run"]) for r in items],
            best_fitness=[float(r["best_fitness"]) for r in items],
            evaluations=[int(r.get("evaluations") or 0) for r in items],
            seconds=sum(float(r.get("seconds") or 0.0) for r in items),
        ))
    return out


# ------------------------------------------------------------------------------- reproduction
Result = tuple[reference.Table, dict[str, Any], list[reproduction.Row], dict[str, Any] | None,
               dict[str, str | None]]


def reproduce_table(name: str, runs: int | None, seed: int, jobs: int, url: str | None,
                    backend: str = "numpy") -> Result:
    """Run one table's study; returns (table, setting, rows, statistics json, markers)."""
    table = reference.load(name)
    setting = study_setting(table, runs, seed, backend)
    started = time.perf_counter()
    measured: list[Any]
    if isinstance(table, reference.BenchmarkTable):
        measured = (cells_from_runs(run_remote(setting, url)) if url
                    else run_benchmark_local(setting, jobs))
    else:
        measured = run_remote(setting, url) if url else run_map_local(setting, jobs)
    setting["seconds"] = round(time.perf_counter() - started, 1)
    return judge(table, setting, measured)


def judge(table: reference.Table, setting: dict[str, Any], measured: Sequence[Any]) -> Result:
    """Verdicts, statistics and markers for measured benchmark cells (``report.Cell``) or map
    run outcomes (dicts with planner, map, success, length, ...), with the current reasons."""
    reasons = reference.load_reasons()
    markers: dict[str, str | None] = {}
    statistics: dict[str, Any] | None = None
    if isinstance(table, reference.BenchmarkTable):
        cells: list[report.Cell] = list(measured)
        by_cell = {(c.function, c.algorithm): c.best_fitness for c in cells}
        rows = reproduction.benchmark_rows(table, by_cell, reasons)
        stats = report.statistics(cells, list(table.algorithms))
        statistics = report.tests_to_json(stats)
        for c in cells:
            markers[reference.cell_key(table.name, c.algorithm, c.function, c.dim)] = (
                stats.marker(c))
    else:
        from swarmpath.world import get_map

        grouped: dict[tuple[str, str], list[dict[str, Any]]] = {}
        for r in measured:
            grouped.setdefault((r["planner"], r["map"]), []).append(r)
        scenarios = {m: get_map(m) for m in table.maps}
        rows = reproduction.map_rows(table, grouped, reasons, scenarios)
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
    for c in doc["cells"]:
        if table.kind == "benchmark":
            values = [float(v) for v in c["runs"]]
            measured.append(report.Cell(
                algorithm=c["algorithm"], function=c["function"], dim=int(c["dim"]),
                run_ids=list(range(len(values))), best_fitness=values,
                evaluations=[0] * len(values), seconds=0.0))
        else:
            measured += [{**o, "planner": c["planner"], "map": c["map"]}
                         for o in c["outcomes"]]
    return judge(table, dict(doc["setting"]), measured)


def command_line(name: str, runs: int | None, seed: int, fmt: str, backend: str = "numpy") -> str:
    parts = ["swarmpath", "reproduce", name]
    if runs is not None:
        parts += ["--runs", str(runs)]
    if seed != 1:
        parts += ["--seed", str(seed)]
    if backend != "numpy":
        parts += ["--backend", backend]
    if fmt != "table":
        parts += ["--format", fmt]
    return shlex.join(parts)


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
    fmt: Annotated[str, typer.Option("--format", help="table, markdown or csv.")] = "table",
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON document.")] = False,
    out: Annotated[
        Path | None, typer.Option(help="Also write DIR/<table>.md and DIR/<table>.png.")
    ] = None,
    from_: Annotated[
        Path | None,
        typer.Option("--from", help="Judge the runs of an earlier --json output again "
                                    "(no study is run; reasons as they are now)."),
    ] = None,
    backend: BackendOpt = "numpy",
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
                              or backend != "numpy"):
        raise InputError("--from", "judges saved runs: give no TABLE, --runs, --url or "
                                   "--backend with it")
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
            study_setting(reference.load(name), runs, seed, backend)
    if fmt == "markdown" and not as_json:
        whole = table if table is not None else (
            "all" if names == list(reference.TABLES) else ",".join(names))
        first_runs = runs
        if from_ is not None:
            first_runs = int(results[0][1]["runs"])
            seed = int(results[0][1]["seed"])
        sys.stdout.write(output.markdown_header(
            command_line(whole, first_runs, seed, fmt, backend), __version__,
            None if from_ is None else from_.name))
    docs = []
    for i, name in enumerate(names):
        tab, setting, rows, statistics, markers = (
            results[i] if results else reproduce_table(name, runs, seed, jobs, url, backend))
        if results:
            runs, seed = int(setting["runs"]), int(setting["seed"])
            backend = str(setting.get("backend", "numpy"))
        doc = reproduction.document(tab, setting, rows, statistics)
        doc["version"] = __version__
        doc["platform"] = numeric_platform()
        docs.append(doc)
        if out is not None:
            output.write_outputs(out, tab, setting, rows, markers,
                                 command_line(name, runs, seed, "markdown", backend))
        if as_json:
            continue
        if fmt == "markdown":
            sys.stdout.write(output.markdown(tab, setting, rows, markers,
                                             command_line(name, runs, seed, fmt, backend)))
        elif fmt == "csv":
            sys.stdout.write(output.csv_text(tab, rows, markers))
        else:
            output.print_rich(tab, setting, rows, markers)
    if as_json:
        sys.stdout.write(json.dumps(docs[0] if len(docs) == 1 else docs, allow_nan=False)
                         + "\n")
