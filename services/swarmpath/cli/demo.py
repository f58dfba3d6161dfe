"""``swarmpath demo`` (what ``scripts/demo`` runs): the main job through the service.

Starts ``swarmpath up --workers 2`` on free loopback ports, submits a benchmark job (the ICOOT
paper's algorithms on four functions) and a map study (the four papers' planners on mfb-static
and mfb-dynamic), waits with progress, prints both summary tables, downloads both MCAP files
with their Foxglove layouts into ``--out`` and says where every output is. Without ``--keep``
it then stops the service and deletes its data directory; with ``--keep`` the coordinator, its
dashboard and its data directory (``OUT/demo-data``) stay until Ctrl-C, so the dashboard it
advertises can be visited. ``--quick`` runs two tiny jobs instead (seconds: a smoke test).
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Annotated, Any

import typer

from swarmpath.cli.core import InputError, app

BENCHMARK = {"kind": "benchmark", "algorithms": ["PSO", "SSA", "FDO", "mCOOT", "COOT", "ICOOT"],
             "functions": ["F1", "F5", "F9", "F10"], "dims": [30], "runs": 10, "agents": 30,
             "iterations": 500, "seed": 1}
MAP = {"kind": "map", "planners": ["ICOOT", "IHPO", "RFO-GWO-EA", "MFB", "HPSO-MFB"],
       "maps": ["mfb-static", "mfb-dynamic"], "runs": 3, "seed": 1}
QUICK = [{"kind": "benchmark", "algorithms": ["PSO", "ICOOT"], "functions": ["F1", "F9"],
          "dims": [2], "runs": 2, "agents": 10, "iterations": 20, "seed": 1},
         {"kind": "map", "planners": ["OMPL-RRTstar"], "maps": ["mfb-static"], "runs": 1,
          "seed": 1, "params": {"OMPL-RRTstar": {"iterations": 2000}}}]
START_SECONDS = 120.0  # the coordinator answers within this (a loaded machine), or the demo fails


def _free_ports(n: int) -> list[int]:
    socks = [socket.socket() for _ in range(n)]
    try:
        for s in socks:
            s.bind(("127.0.0.1", 0))
        return [int(s.getsockname()[1]) for s in socks]
    finally:
        for s in socks:
            s.close()


def _say(text: str) -> None:
    typer.echo(f"demo: {text}", err=True)


def _end_with_parent() -> None:
    """In the child before exec: SIGTERM it when the demo dies, even by SIGKILL (Linux
    PR_SET_PDEATHSIG; elsewhere the demo's own Ctrl-C / SIGTERM handling is what stops it)."""
    if sys.platform.startswith("linux"):
        import ctypes

        ctypes.CDLL(None).prctl(1, signal.SIGTERM, 0, 0, 0)  # 1: PR_SET_PDEATHSIG


class _Service:
    """``swarmpath up`` as a child process (its own session: stopped with its workers)."""

    def __init__(self, data: Path, log: Path):
        self.http, self.zenoh = _free_ports(2)
        self.url = f"http://127.0.0.1:{self.http}"
        self.log = log
        self._log = open(log, "ab")  # closed by stop()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "swarmpath.cli", "up", "--workers", "2", "--http",
             f"127.0.0.1:{self.http}", "--zenoh", f"tcp/127.0.0.1:{self.zenoh}", "--data",
             str(data), "--log-level", "warning"],
            stdout=self._log, stderr=self._log, start_new_session=True,
            preexec_fn=_end_with_parent)

    def wait_ready(self) -> None:
        import httpx

        deadline = time.monotonic() + START_SECONDS
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError(f"swarmpath up exited ({self.proc.returncode}); see {self.log}")
            try:
                if httpx.get(f"{self.url}/healthz", timeout=2.0).status_code == 200:
                    return
            except httpx.HTTPError:
                pass
            time.sleep(0.3)
        raise RuntimeError(f"no answer from {self.url} in {START_SECONDS:.0f} s; see {self.log}")

    def stop(self) -> None:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGTERM)
            try:
                self.proc.wait(30)
            except subprocess.TimeoutExpired:
                _say("swarmpath up did not exit in 30 s; killing it")
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait(10)
        self._log.close()


def _run_jobs(url: str, specs: list[dict[str, Any]], out: Path) -> list[tuple[str, Path, Path]]:
    """Submit, wait, print each summary; download each MCAP and its layout into ``out``."""
    from swarmpath.cli.results import _summary
    from swarmpath.cli.service import _wait_with_progress
    from swarmpath.service import foxglove
    from swarmpath.service.client import ServiceClient

    done = []
    with ServiceClient(url) as client:
        jobs = [client.submit(spec) for spec in specs]
        for job in jobs:
            status = _wait_with_progress(client, job["id"], job["runs_total"])
            if status["state"] != "done":
                raise RuntimeError(f"job {job['id']} ended {status['state']}")
        for job in jobs:
            typer.echo("")
            _summary(client, job["id"], "table")
        for job in jobs:
            path = client.download(job["id"], out / f"demo-{job['id']}.mcap")
            layout = path.with_name(f"demo-{job['id']}.layout.json")
            layout.write_text(json.dumps(foxglove.layout(foxglove.mcap_topics(path)), indent=1),
                              encoding="utf-8")
            done.append((job["id"], path, layout))
    return done


@app.command()
def demo(
    keep: Annotated[bool, typer.Option(
        "--keep", help="Keep the coordinator, its dashboard and its data directory up after the "
        "jobs (until Ctrl-C).")] = False,
    out: Annotated[Path, typer.Option(
        "--out", envvar="DEMO_OUT", help="Where the MCAP files, layouts (and with --keep the "
        "data directory) go.")] = Path("out"),
    quick: Annotated[bool, typer.Option(
        "--quick", help="Two tiny jobs instead of the main job (seconds; a smoke test).")] = False,
) -> None:
    """The main job through the service: a benchmark job and a map study on a local
    coordinator with two workers; prints the tables and where every output is."""
    if out.exists() and not out.is_dir():
        raise InputError("--out", f"{str(out)!r} is not a directory")
    out.mkdir(parents=True, exist_ok=True)
    scratch = Path(tempfile.mkdtemp(prefix="swarmpath-demo-"))
    data = out / "demo-data" if keep else scratch / "data"
    if keep and data.exists():
        shutil.rmtree(data)  # a fresh queue each time (the outputs of earlier runs stay in out)
    log = (out if keep else scratch) / "demo-up.log"
    service = _Service(data, log)

    def stop(_signum: int, _frame: Any) -> None:  # SIGTERM as Ctrl-C: stop the service cleanly
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, stop)
    # Ctrl-C explicitly too: a process started with SIGINT ignored (by a parent that ignores it,
    # `nohup`, a test runner) inherits SIG_IGN, and Python then installs no KeyboardInterrupt:
    # the demo that says "Ctrl-C stops it" would not stop
    signal.signal(signal.SIGINT, stop)
    failed = True
    try:
        service.wait_ready()
        _say(f"coordinator at {service.url}, zenoh tcp/127.0.0.1:{service.zenoh}")
        done = _run_jobs(service.url, QUICK if quick else [BENCHMARK, MAP], out)
        typer.echo("")
        _say("outputs:")
        _say("  the summary tables: above" + (
            f" (again: swarmpath results JOB --url {service.url})" if keep else
            " (with --keep the coordinator stays up to ask again: swarmpath results JOB)"))
        for job, path, layout in done:
            _say(f"  job {job}: {path} (open in Foxglove), layout {layout} (Layouts > Import)")
        failed = False
        if keep:
            _say(f"  the service's log: {log}")
            _say(f"  the data directory (SQLite queue, MCAP files): {data}")
            _say(f"the coordinator stays up: dashboard {service.url}/ (jobs: "
                 + ", ".join(f"{service.url}/ui/jobs/{job}" for job, _p, _l in done)
                 + "); Ctrl-C stops it")
            while service.proc.poll() is None:
                time.sleep(0.5)
            failed = True  # it went away by itself
            _say(f"swarmpath up exited ({service.proc.returncode}); see {log}")
    except KeyboardInterrupt:
        if not keep or failed:
            _say("interrupted")
    except Exception as exc:
        _say(f"failed: {' '.join(str(exc).split())[:400]}")
        if log.exists():
            tail = log.read_text(errors="replace").splitlines()[-30:]
            typer.echo("\n".join(tail), err=True)
    finally:
        service.stop()
        shutil.rmtree(scratch, ignore_errors=True)
    if failed:
        raise typer.Exit(1)
