"""The service's REST client commands: ``submit``, ``status``, ``cancel``, ``download``
(``--url`` or ``$SWARMPATH_URL``, token from ``$SWARMPATH_TOKEN``; ``results`` is in
:mod:`swarmpath.cli.results`, the processes ``up``, ``coordinator``, ``worker`` in
:mod:`swarmpath.cli.processes`).

Heavy imports (the HTTP client, rich) stay inside the command functions.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Annotated, Any

import typer

from swarmpath.cli.core import CommandFailed, InputError, InputErrors, app
from swarmpath.evidence.legend import legend_text

UrlOpt = Annotated[
    str | None,
    typer.Option("--url", envvar="SWARMPATH_URL", help="Coordinator URL.",
                 show_default="http://127.0.0.1:8000"),
]



# ---------------------------------------------------------------------------------- clients
def _client(url: str | None) -> Any:
    from swarmpath.service.client import ServiceClient

    return ServiceClient(url)


def _fail(exc: Exception, job_option: str = "JOB") -> None:
    """ServiceError -> InputError (bad input, exit 2) or CommandFailed (one line, exit 1)."""
    from swarmpath.service.client import ServiceError, Unreachable, describe_detail, error_field

    if isinstance(exc, Unreachable):
        raise CommandFailed(str(exc)) from None
    if isinstance(exc, ServiceError):
        if exc.status == 422:
            if isinstance(exc.detail, list) and exc.detail:
                raise InputErrors([
                    (error_field(d.get("loc", [])), str(d.get("msg", "")))
                    if isinstance(d, dict) else ("spec", str(d)) for d in exc.detail
                ]) from None
            raise InputError("spec", describe_detail(exc.detail)) from None
        if exc.status == 404:
            raise InputError(job_option, describe_detail(exc.detail)) from None
        if exc.status == 401:
            raise CommandFailed("unauthorized: set SWARMPATH_TOKEN") from None
        raise CommandFailed(f"{exc.status}: {describe_detail(exc.detail)}") from None
    raise exc


def _table(title: str, columns: list[str], rows: list[dict[str, Any]]) -> Any:
    from rich.table import Table

    table = Table(title=title, title_justify="left")
    for c in columns:
        table.add_column(c, justify="left" if c in _TEXT_COLUMNS else "right")
    for row in rows:
        table.add_row(*(_cell(row.get(c)) for c in columns))
    return table


_TEXT_COLUMNS = {"algorithm", "function", "planner", "map", "id", "kind", "state", "host",
                 "worker", "current_runs", "contents", "extension", "origin", "digest"}


def _cell(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.4g}"
    if isinstance(v, list):
        return ", ".join(str(x) for x in v[:4]) + (f" (+{len(v) - 4})" if len(v) > 4 else "")
    return str(v)


def _when(t: float | None) -> str:
    return time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(t)) if t else ""


def _console() -> Any:
    from rich.console import Console

    console = Console()
    if not console.is_terminal:
        console = Console(width=200)
    return console


@app.command()
def submit(
    spec_file: Annotated[Path, typer.Argument(metavar="SPEC.json", help="Job spec ('-': stdin).")],
    wait: Annotated[bool, typer.Option("--wait", help="Wait for the job, with progress.")] = False,
    url: UrlOpt = None,
) -> None:
    """Submit a job spec; prints the job id (and waits with a progress bar with --wait)."""
    try:
        text = sys.stdin.read() if str(spec_file) == "-" else spec_file.read_text("utf-8")
    except OSError as exc:
        raise InputError("SPEC.json", f"cannot read {spec_file}: {exc.strerror}") from None
    try:
        spec = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError("SPEC.json", f"not valid JSON: {exc.msg} (line {exc.lineno})") from None
    if not isinstance(spec, dict):
        raise InputError("SPEC.json", "a job spec is a JSON object")
    for line in trajectory_notes(spec):
        typer.echo(f"swarmpath submit: warning: {line}", err=True)
    with _client(url) as client:
        try:
            job = client.submit(spec)
        except Exception as exc:
            _fail(exc)
            raise
        typer.echo(job["id"])
        typer.echo(f"job {job['id']}: {job['runs_total']} runs, {job['state']}", err=True)
        if wait:
            _wait_and_report(client, job)


def _wait_and_report(client: Any, job: dict[str, Any]) -> None:
    """--wait of submit and extend: a progress bar until the job ends, its counts, exit 1
    unless it is done."""
    status = _wait_with_progress(client, job["id"], job["runs_total"])
    typer.echo(f"job {status['id']}: {status['state']} ({status['runs_done']} done, "
               f"{status['runs_failed']} failed)", err=True)
    if status["state"] != "done":
        raise typer.Exit(1)


@app.command()
def extend(
    job: Annotated[str, typer.Argument(metavar="JOB", help="An ended job's id.")],
    runs: Annotated[int, typer.Option("--runs", help="Runs per cell of the new job (a raced "
                                      "job: its max_runs); at least the job's runs.")],
    wait: Annotated[bool, typer.Option("--wait", help="Wait for the job, with progress.")] = False,
    url: UrlOpt = None,
) -> None:
    """A new job with an ended job's spec and more runs per cell, reusing every run the job has
    (run r is the same run in both; a raced job's race goes on from its runs); prints its id."""
    from swarmpath.service.model import MAX_RUNS_PER_CELL

    if not 1 <= runs <= MAX_RUNS_PER_CELL:
        raise InputError("--runs", f"must be in 1..{MAX_RUNS_PER_CELL}, got {runs}")
    with _client(url) as client:
        try:
            new = client.extend(job, runs)
        except Exception as exc:
            _fail(exc)
            raise
        typer.echo(new["id"])
        typer.echo(f"job {new['id']}: extends {job} to {runs} runs per cell, "
                   f"{new['reused']} runs reused, {new['runs_total']} runs, {new['state']}",
                   err=True)
        if wait:
            _wait_and_report(client, new)


def trajectory_notes(spec: dict[str, Any]) -> list[str]:
    """``maps[i].FIELD: message`` for each inline scenario of a map job whose moving goal or
    moving obstacle has a stated path into a static obstacle
    (:func:`swarmpath.world.trajectories.trajectory_warnings`, as ``swarmpath plan`` warns).
    Checked here, on the submitter's machine, not by the coordinator (the check samples the
    whole episode: work the shared HTTP port should not do for anyone). Entries the coordinator
    will refuse are left to its 422; presets and uploaded maps state no such paths."""
    maps = spec.get("maps") if spec.get("kind") == "map" else None
    if not isinstance(maps, list):
        return []
    from swarmpath.world.scenario_io import scenario_from_dict
    from swarmpath.world.trajectories import trajectory_warnings

    out: list[str] = []
    for i, entry in enumerate(maps):
        if not isinstance(entry, dict) or "map" in entry:
            continue
        try:
            scenario = scenario_from_dict(dict(entry))
        except ValueError:  # ScenarioError: the coordinator's 422 names it
            continue
        out += [f"maps[{i}].{field} ({scenario.name}): {message}"
                for field, message in trajectory_warnings(scenario)]
    return out


def _wait_with_progress(client: Any, job_id: str, total: int) -> dict[str, Any]:
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    stderr = Console(stderr=True)
    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
               TimeElapsedColumn(), TimeRemainingColumn())
    with Progress(*columns, console=stderr, transient=False) as progress:
        task = progress.add_task(f"job {job_id}", total=total)

        def show(status: dict[str, Any]) -> None:  # a race adds runs as it goes: its total too
            progress.update(task, completed=status["runs_done"] + status["runs_failed"],
                            total=status["runs_total"],
                            description=f"job {job_id} {status['state']}")

        try:
            return client.wait(job_id, poll=0.5, on_status=show)
        except Exception as exc:
            _fail(exc)
            raise


@app.command()
def status(
    job: Annotated[str | None, typer.Argument(metavar="[JOB]", help="A job id.")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON.")] = False,
    url: UrlOpt = None,
) -> None:
    """Jobs (newest first) and workers, or one job."""
    with _client(url) as client:
        try:
            if job is not None:
                data: Any = client.job(job)
            else:
                data = {"jobs": client.jobs(), "workers": client.workers()}
        except Exception as exc:
            _fail(exc)
            raise
    if as_json:
        typer.echo(json.dumps(data, indent=2))
        return
    console = _console()
    jobs = [data] if job is not None else data["jobs"]
    rows = [{**j, "runs": f"{j['runs_done'] + j['runs_failed']}/{j['runs_total']}",
             "failed": j["runs_failed"], "created": _when(j["created"]),
             "finished": _when(j["finished"])} for j in jobs]
    console.print(_table("jobs", ["id", "kind", "contents", "state", "runs", "failed", "created",
                                  "finished"], rows))
    console.print(legend_text(["failed"]), markup=False, highlight=False)
    for j in jobs:  # a job no live worker can run says why
        if j.get("waiting"):
            console.print(f"job {j['id']} waiting: {j['waiting']}", markup=False,
                          highlight=False)
    if job is not None and data.get("pins"):
        console.print(_table("pinned extensions", ["extension", "origin", "digest"], [
            {"extension": k, "origin": p.get("origin", ""), "digest": p.get("digest", "")[:12]}
            for k, p in sorted(data["pins"].items())]))
    if job is None:
        workers = [{**w, "alive": "yes" if w["alive"] else "no",
                    "current_runs": len(w["current_runs"]),
                    "last_seen": _when(w["last_seen"])} for w in data["workers"]]
        console.print(_table("workers", ["id", "host", "pid", "slots", "alive", "current_runs",
                                         "runs_done", "last_seen"], workers))


@app.command()
def cancel(
    job: Annotated[str, typer.Argument(metavar="JOB", help="A job id.")],
    url: UrlOpt = None,
) -> None:
    """Cancel a queued or running job (a finished job stays as it is); prints its state."""
    with _client(url) as client:
        try:
            status = client.cancel(job)
        except Exception as exc:
            _fail(exc)
            raise
    done = status["runs_done"] + status["runs_failed"]
    typer.echo(f"job {status['id']}: {status['state']} ({done}/{status['runs_total']} runs "
               f"finished, {status['runs_failed']} failed)")


@app.command()
def download(
    job: Annotated[str, typer.Argument(metavar="JOB", help="A job id.")],
    output: Annotated[
        Path | None,
        typer.Option("-o", "--output", help="Where to write the MCAP (a file or a directory).",
                     show_default="JOB.mcap"),
    ] = None,
    layout: Annotated[
        bool,
        typer.Option("--layout", help="Also write a Foxglove layout next to it as "
                     "JOB.layout.json: a 3D scene with this file's topics (map jobs), a Plot "
                     "of /curves (benchmark jobs), the /results message."),
    ] = False,
    url: UrlOpt = None,
) -> None:
    """Download the job's MCAP file (after the job has ended)."""
    if output is None:
        output = Path(f"{job}.mcap")
    elif output.is_dir():
        output = output / f"{job}.mcap"
    if not output.parent.exists():
        raise InputError("--output", f"directory {str(output.parent)!r} does not exist")
    with _client(url) as client:
        try:
            path = client.download(job, output)
        except Exception as exc:
            _fail(exc)
            raise
    typer.echo(f"{path} ({path.stat().st_size} bytes)", err=True)
    if layout:
        from swarmpath.service import foxglove

        out = path.with_name(f"{job}.layout.json")
        doc = foxglove.layout(foxglove.mcap_topics(path))
        out.write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
        typer.echo(f"{out} (Foxglove: Layouts > Import from file)", err=True)
