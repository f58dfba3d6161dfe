"""Running a reproduction study for ``swarmpath reproduce``: locally through ``bench``'s and
``plan``'s own functions (same spec, same seed, same numbers), or as one job on a coordinator
(``--url``), whose runs are read back as bench's cells."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import typer
from rich.console import Console

from swarmpath.cli import parallel
from swarmpath.evidence import report


def run_benchmark_local(setting: dict[str, Any], jobs: int) -> list[report.Cell]:
    from swarmpath.cli import bench
    from swarmpath.cli.bench_spec import make_spec

    spec = make_spec(
        ",".join(setting["algorithms"]), ",".join(setting["functions"]),
        ",".join(str(d) for d in setting["dims"]), runs=setting["runs"],
        agents=setting["agents"], iterations=setting["iterations"], seed=setting["seed"],
        backend=setting.get("backend", "auto"), transform=setting.get("transform"),
        instances=(",".join(str(i) for i in setting["instances"]) if setting.get("instances")
                   else None),
        budget_evals=setting.get("budget_evals"),
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
            cpu_seconds=report.cpu_total(r.get("cpu_seconds") for r in items),
        ))
    return out
