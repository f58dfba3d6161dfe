"""``swarmpath results JOB``: the job's summary table, its runs as CSV / JSON / Parquet, its curves
in IOHprofiler's format and its figures (a REST client like the other service commands)."""

from __future__ import annotations

import io
import json
import sys
from pathlib import Path
from typing import Annotated, Any

import typer

from swarmpath.cli import service as svc
from swarmpath.cli.core import InputError, app, plot_dir
from swarmpath.evidence.legend import legend_text

SUMMARY_FORMATS = ("table", "json", "csv", "latex")
RUN_FORMATS = ("csv", "json", "parquet")


def _call(fn: Any, *args: Any) -> Any:
    try:
        return fn(*args)
    except Exception as exc:
        svc._fail(exc)
        raise


#: The format an output file's extension names (``-o runs.parquet`` wrote CSV into it, issue 25).
EXTENSIONS = {".csv": "csv", ".json": "json", ".parquet": "parquet", ".pq": "parquet",
              ".tex": "latex"}


def _format(format: str | None, runs: bool, output: Path | None) -> str:
    """``--format`` as given, else the one the output file's extension names, else the default
    (table; csv with --runs); a file whose extension names another format is refused."""
    named = EXTENSIONS.get(output.suffix.lower()) if output is not None else None
    if format is None:
        return named or ("csv" if runs else "table")
    if named is not None and named != format and format not in ("ioh", "ioh-info"):
        raise InputError("--output", f"{str(output)!r} names {named} by its extension, but "
                         f"--format is {format}: change one of them")
    return "csv" if runs and format == "table" else format


def _check(format: str, runs: bool, output: Path | None) -> None:
    if format in ("ioh", "ioh-info"):
        if runs:
            raise InputError("--runs", f"--format {format} writes the curves, not --runs")
        if output is None:
            raise InputError("--output", f"--format {format} needs a directory: -o DIR")
        plot_dir(output, "--output")
        return
    allowed = RUN_FORMATS if runs else SUMMARY_FORMATS
    if format not in allowed:
        what = "with --runs" if runs else "(ioh: IOHprofiler files; --runs: per-run rows)"
        raise InputError("--format", f"{format!r} is not one of {', '.join(allowed)} {what}")
    if output is not None and (output.is_dir() or not output.parent.is_dir()):
        raise InputError("--output", f"{str(output)!r} is not a file in an existing directory")
    if format == "parquet" and output is None:
        raise InputError("--output", "Parquet is binary: give a file, -o FILE.parquet")


@app.command()
def results(
    job: Annotated[str, typer.Argument(metavar="JOB", help="A job id.")],
    format: Annotated[
        str | None,
        typer.Option("--format", help="Summary: table, json, csv or latex (a booktabs table). "
                     "With --runs: csv, json or parquet. ioh: the curves as IOHprofiler files "
                     "(-o DIR; ioh-info: the older .info form). Default: the one -o's "
                     "extension names (.csv, .json, .parquet, .tex), else table (csv with "
                     "--runs).", show_default=False),
    ] = None,
    runs: Annotated[
        bool, typer.Option("--runs", help="One row per run (identity, metrics, curve or path).")
    ] = False,
    output: Annotated[
        Path | None,
        typer.Option("-o", "--output", help="File to write (directory for --format ioh).",
                     show_default="stdout"),
    ] = None,
    plot: Annotated[
        Path | None,
        typer.Option("--plot", metavar="DIR",
                     help="Write PNGs into DIR: curves and box plots per function and "
                     "dimension, or paths per planner x map and box plots per map."),
    ] = None,
    url: svc.UrlOpt = None,
) -> None:
    """The job's summary table (partial while it runs), its runs, IOHprofiler files, figures."""
    format = _format(format, runs, output)
    _check(format, runs, output)
    if plot is not None:
        plot_dir(plot, "--plot")
    with svc._client(url) as client:
        if plot is not None:
            figures = _plots(client, job, plot)
            for out in figures:
                typer.echo(f"wrote {out}", err=True)
            if not figures:
                typer.echo(f"job {job}: no finished run to plot yet", err=True)
        if format in ("ioh", "ioh-info"):
            _ioh(client, job, output, format)  # type: ignore[arg-type]
        elif runs:
            _runs(client, job, format, output)
        elif output is not None:  # rendered first: a job that does not exist leaves no file
            text = io.StringIO()
            _summary(client, job, format, text)
            output.write_text(text.getvalue(), encoding="utf-8")
            typer.echo(f"{output} ({format})", err=True)
        else:
            _summary(client, job, format)


def _summary(client: Any, job: str, format: str, file: Any = None) -> None:
    """The summary in ``format`` on stdout, or into ``file`` (-o: it was ignored before)."""
    out = file or sys.stdout
    if format == "csv":
        out.write(_call(client.summary_csv, job))
        return
    summary = _call(client.summary, job)
    if format == "json":
        out.write(json.dumps(summary, indent=2) + "\n")
        return
    if format == "latex":
        out.write(summary_latex(job, summary))
        return
    title = (f"job {job} ({summary['kind']}): {summary['state']}, "
             f"{summary['runs_done'] + summary['runs_failed']}/{summary['runs_total']} runs"
             + (" (partial)" if summary["partial"] else ""))
    from swarmpath.cli.table_fit import fitted_tables

    if file is None:
        console = svc._console()
    else:
        from rich.console import Console

        console = Console(file=file, width=200)
    tables, empty = fitted_tables(title, summary["columns"], summary["rows"], console.width,
                                  svc._cell, svc._TEXT_COLUMNS)
    for table in tables:
        console.print(table)
    if empty:
        console.print(f"empty in every row, left out: {', '.join(empty)}", highlight=False,
                      markup=False)
    from swarmpath.service.cell_notes import note_lines
    from swarmpath.service.summary_stats import statistics_lines

    for line in statistics_lines(summary) + note_lines(summary):
        console.print(line, highlight=False, markup=False)
    if summary.get("buckets"):  # a job on MovingAI pairs: the table of swarmpath plan --scen
        from swarmpath.cli.plan_tables import render_buckets

        console.print(render_buckets(summary["buckets"]))
    shown = [c for c in summary["columns"] if c not in empty]
    console.print(legend_text(shown), markup=False, highlight=False)


def _runs(client: Any, job: str, format: str, output: Path | None) -> None:
    from swarmpath.evidence import exports

    if format in ("csv", "parquet") and output is not None:
        path = _call(client.download_runs, job, format, output)
        typer.echo(f"{path} ({path.stat().st_size} bytes)", err=True)
        return
    kind = _call(client.job, job)["kind"]
    rows = exports.rows(_call(client.iter_runs, job), job)
    if output is None:  # csv or json on stdout
        if format == "csv":
            for text in exports.csv_chunks(kind, rows):
                sys.stdout.write(text)
        else:
            sys.stdout.write(json.dumps([exports.json_row(r) for r in rows], allow_nan=False)
                             + "\n")
        return
    n = exports.write(kind, rows, format, output)
    typer.echo(f"{output}: {n} runs", err=True)


def _ioh(client: Any, job: str, directory: Path, fmt: str = "ioh") -> None:
    from swarmpath.evidence.ioh import write_ioh

    if _call(client.job, job)["kind"] != "benchmark":
        raise InputError("--format", "ioh holds optimizer curves: JOB must be a benchmark job")
    try:
        written = write_ioh(_call(client.iter_runs, job), directory, job, fmt)
    except ValueError as exc:  # two functions on one IOHprofiler id
        raise InputError("--format", str(exc)) from None
    typer.echo(f"{directory}: {written.runs} runs in {len(written.files)} files"
               + (f" ({written.skipped} runs without a finite curve left out)"
                  if written.skipped else ""), err=True)


def _cd_plots(summary: dict[str, Any], directory: Path) -> list[Path]:
    """A critical-difference diagram per dimension from the summary's Friedman tests."""
    from swarmpath.evidence.cdplot import draw_cd
    from swarmpath.evidence.compare import Friedman

    out = []
    for doc in (summary.get("statistics") or {}).get("friedman", []):
        path = draw_cd(Friedman.from_json(doc), directory / f"cd-D{doc['dim']}.png",
                       f"D = {doc['dim']}")
        if path is not None:
            out.append(path)
    return out


def _plots(client: Any, job: str, directory: Path) -> list[Path]:
    from swarmpath.evidence import plots

    items = [i for i in _call(client.iter_runs, job) if i.get("state") == "done"]
    if not items:
        return []
    if "algorithm" in items[0]:
        return [*plots.write_benchmark_plots(items, directory),
                *_cd_plots(_call(client.summary, job), directory)]
    from swarmpath.service.recorder import scenario_for, world_for

    scenarios: dict[str, Any] = {}
    for item in items:
        if item["map"] not in scenarios:
            scenarios[item["map"]] = scenario_for(item.get("spec") or {"map": item["map"]})
    known = [i for i in items if scenarios[i["map"]] is not None]
    seed = int(items[0]["seed"])
    return plots.write_map_plots(known, scenarios, lambda sc, run: world_for(sc, seed, run),
                                 directory)


def summary_latex(job: str, summary: dict[str, Any]) -> str:
    """A job's summary as a booktabs table: the benchmark table (location, spread, markers,
    effect sizes, posterior; bold = best and similar) or the map comparison."""
    from swarmpath.evidence import latex, tables

    rows = summary["rows"]
    st = summary.get("statistics") or {}
    runs = max((int(r.get("runs") or 0) for r in rows), default=0)
    state = "" if not summary.get("partial") else " (partial)"
    if summary["kind"] == "benchmark":
        algorithms = list(dict.fromkeys(r["algorithm"] for r in rows))
        reference = (st.get("comparison") or {}).get("reference")
        grid = tables.benchmark_grid(rows, algorithms, compared=reference is not None,
                                     reference=reference)
        functions = ", ".join(dict.fromkeys(r["function"] for r in rows))
        dims = ", ".join(str(d) for d in dict.fromkeys(r["dim"] for r in rows))
        what = f"{functions} in {dims} dimensions"
    else:
        planners = list(dict.fromkeys(r["planner"] for r in rows))
        reference = next(iter((st.get("comparisons") or {}).values()), {}).get("reference")
        grid = tables.map_grid(rows, planners, reference)
        what = ", ".join(dict.fromkeys(r["map"] for r in rows))
    tests = (f" Against {reference}: superscript +/=/- significantly better / no difference / "
             "worse (two-sided Wilcoxon rank-sum test; success rates: Fisher's exact test; "
             "Holm-adjusted, alpha 0.05); A12: Vargha-Delaney effect size; shift and its 95 % "
             "interval: Hodges-Lehmann; P(b/e/w): posterior probabilities of better / "
             "practically equivalent / worse (Bayesian bootstrap of the mean, rope 1 % of the "
             "larger distance to the optimum). Bold: the best mean and those not significantly "
             "worse." if reference else "")
    if st.get("race") and reference:
        from swarmpath.evidence.race_report import race_legend

        tests = (f" Superscript {race_legend(st['race'], reference)}. A12: Vargha-Delaney effect "
                 "size; P(b/e/w): posterior probabilities of better / practically equivalent / "
                 "worse (Bayesian bootstrap of the mean, rope 1 % of the larger distance to the "
                 "optimum). Bold: the best mean.")
    caption = (f"swarmpath job {job} ({summary['kind']}{state}): {what}; up to {runs} runs per "
               f"cell.{tests}")
    return latex.grid_to_latex(grid, caption, f"tab:swarmpath-{job}")
