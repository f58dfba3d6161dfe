#!/usr/bin/env python3
"""The service's speed: per-run dispatch overhead, and one versus two workers.

    .venv/bin/python scripts/bench/service.py [--dispatch-runs 2000] [--table2-runs 3]
                                              [--full-table2]

Each measurement starts its own ``swarmpath up --workers N`` (coordinator + N local workers, one
slot each) on free loopback ports with a fresh data directory, submits one job through the REST
API and reads the job's ``started``/``finished`` times from ``GET /jobs/{id}`` (the coordinator's
clock: first lease to last result, no client polling in it); the processes are stopped (SIGTERM,
then SIGKILL) afterwards.

Part (a) dispatch: GWO on F1, 2 dims, 5 agents, 1 iteration, ``--dispatch-runs`` runs (2000):
each run computes almost nothing, so (finished - started) / runs_total is the per-run cost of
leasing, executing and recording through the service. Target < 2 ms per run. The coordinator
sizes leases (about 3 s of work, at least 8 runs of a cell, at most 1000) and a worker computes a
lease's runs as one vectorized batch, so this cost is amortized over up to 1000 runs per lease;
the second measurement (GWO and PSO x F1-F13 x dims 2-11, one run per cell: 260 leases of one
run) shows the cost of a lease round trip that nothing amortizes.

Part (b) ICOOT Table 2 setting, REDUCED: PSO, SSA, FDO, mCOOT, COOT, ICOOT x F1-F13 x 30 dims x
30 agents x 500 iterations, but ``--table2-runs`` runs per cell (3, not the paper's 1000), with
one worker and then with two. Target speed-up >= 1.8x. ``--full-table2`` runs the paper's own
scale (1000 runs per cell, two workers only; long: not run by default).

Markdown goes to stdout, progress to stderr.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import platform
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx

ROOT = Path(__file__).resolve().parents[2]
ENV = {**os.environ, "PYTHONPATH": str(ROOT / "services"), "PYTHONUNBUFFERED": "1"}
ENV.pop("SWARMPATH_TOKEN", None)

TABLE2_ALGORITHMS = ["PSO", "SSA", "FDO", "mCOOT", "COOT", "ICOOT"]
TABLE2_FUNCTIONS = [f"F{i}" for i in range(1, 14)]


def note(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Up:
    """``swarmpath up --workers N`` on free loopback ports, stopped on exit."""

    def __init__(self, workers: int, tmp: Path):
        self.workers = workers
        http, zport = free_port(), free_port()
        self.url = f"http://127.0.0.1:{http}"
        data = tmp / f"data-{workers}w-{http}"
        self.log = open(tmp / f"up-{workers}w-{http}.log", "ab")  # closed in stop()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "swarmpath.cli", "up", "--workers", str(workers), "--slots", "1",
             "--http", f"127.0.0.1:{http}", "--zenoh", f"tcp/127.0.0.1:{zport}",
             "--data", str(data), "--log-level", "warning"],
            stdout=self.log, stderr=self.log, env=ENV, start_new_session=True)
        self.http = httpx.Client(base_url=self.url, timeout=30.0)

    def __enter__(self) -> Up:
        try:
            self.wait(lambda: len([w for w in self.http.get("/workers").json() if w["alive"]])
                      >= self.workers, 90, f"{self.workers} workers alive")
        except BaseException:
            self.stop()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def wait(self, cond: Any, timeout: float, what: str, poll: float = 0.2) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError(f"swarmpath up exited ({self.proc.returncode}) waiting for "
                                   f"{what}; log in {self.log.name}")
            with contextlib.suppress(httpx.HTTPError, ValueError, KeyError):
                if cond():
                    return
            time.sleep(poll)
        raise TimeoutError(f"timed out waiting for {what}; log in {self.log.name}")

    def run_job(self, spec: dict[str, Any], timeout: float) -> dict[str, Any]:
        r = self.http.post("/jobs", json=spec)
        r.raise_for_status()
        job = r.json()["id"]
        final: dict[str, Any] = {}

        def ended() -> bool:
            final.update(self.http.get(f"/jobs/{job}").json())
            return final["state"] in ("done", "failed", "cancelled")

        self.wait(ended, timeout, f"job {job}", poll=0.5)
        if final["state"] != "done" or final["runs_done"] != final["runs_total"]:
            raise RuntimeError(f"job {job} ended {final}")
        return final

    def stop(self) -> None:
        self.http.close()
        if self.proc.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(self.proc.pid, signal.SIGTERM)
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                with contextlib.suppress(ProcessLookupError):
                    os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait(10)
        with contextlib.suppress(ProcessLookupError):  # stray workers of the group
            os.killpg(self.proc.pid, signal.SIGKILL)
        self.log.close()


def elapsed(status: dict[str, Any]) -> float:
    return float(status["finished"]) - float(status["started"])


def dispatch(tmp: Path, runs: int, workers: int) -> tuple[int, float]:
    spec = {"kind": "benchmark", "algorithms": ["GWO"], "functions": ["F1"], "dims": [2],
            "agents": 5, "iterations": 1, "runs": runs, "seed": 1}
    with Up(workers, tmp) as up:
        note(f"dispatch: {runs} tiny runs, {workers} worker(s) ...")
        status = up.run_job(spec, timeout=600)
    return status["runs_total"], elapsed(status)


def dispatch_leases(tmp: Path, workers: int) -> tuple[int, float]:
    """One run per cell: every lease holds a single run (no batching to amortize over)."""
    spec = {"kind": "benchmark", "algorithms": ["GWO", "PSO"], "functions": TABLE2_FUNCTIONS,
            "dims": list(range(2, 12)), "agents": 5, "iterations": 1, "runs": 1, "seed": 1}
    with Up(workers, tmp) as up:
        note(f"dispatch: 260 one-run leases, {workers} worker(s) ...")
        status = up.run_job(spec, timeout=600)
    return status["runs_total"], elapsed(status)


def table2(tmp: Path, runs: int, workers: int) -> tuple[int, float]:
    spec = {"kind": "benchmark", "algorithms": TABLE2_ALGORITHMS, "functions": TABLE2_FUNCTIONS,
            "dims": [30], "agents": 30, "iterations": 500, "runs": runs, "seed": 1}
    with Up(workers, tmp) as up:
        note(f"table2: 78 cells x {runs} runs, {workers} worker(s) ...")
        status = up.run_job(spec, timeout=86400)
    return status["runs_total"], elapsed(status)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dispatch-runs", type=int, default=2000)
    ap.add_argument("--table2-runs", type=int, default=3, help="runs per cell (reduced setting)")
    ap.add_argument("--full-table2", action="store_true",
                    help="also the paper's scale: 1000 runs per cell with two workers (long)")
    args = ap.parse_args(argv)

    load0 = os.getloadavg()
    t0 = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    rows: list[str] = []
    with tempfile.TemporaryDirectory(prefix="swarmpath-bench-") as d:
        tmp = Path(d)
        for workers in (1, 2):
            total, secs = dispatch(tmp, args.dispatch_runs, workers)
            rows.append(f"| dispatch: GWO F1 dim 2, 5 agents, 1 iteration | {workers} | {total} "
                        f"| {secs:.2f} | {1000 * secs / total:.2f} ms/run |")
        for workers in (1, 2):
            total, secs = dispatch_leases(tmp, workers)
            rows.append(f"| dispatch, one run per lease: GWO+PSO x F1-F13 x dims 2-11, 5 agents, "
                        f"1 iteration, 1 run/cell | {workers} | {total} | {secs:.2f} | "
                        f"{1000 * secs / total:.2f} ms/run |")
        t2: dict[int, float] = {}
        for workers in (1, 2):
            total, t2[workers] = table2(tmp, args.table2_runs, workers)
            rows.append(f"| Table 2 reduced: 6 algorithms x F1-F13, dim 30, 30 agents, 500 it., "
                        f"{args.table2_runs} runs/cell | {workers} | {total} | {t2[workers]:.2f} | "
                        f"{1000 * t2[workers] / total:.1f} ms/run |")
        if args.full_table2:
            total, secs = table2(tmp, 1000, 2)
            rows.append(f"| Table 2 full: 1000 runs/cell | 2 | {total} | {secs:.1f} | "
                        f"{1000 * secs / total:.1f} ms/run |")
    load1 = os.getloadavg()

    print(f"Started {t0}; machine {platform.machine()}, {os.cpu_count()} CPUs, Python "
          f"{platform.python_version()}; load average (1/5/15 min) at start "
          f"{' / '.join(f'{x:.2f}' for x in load0)}, at the end "
          f"{' / '.join(f'{x:.2f}' for x in load1)}.\n")
    print("| measurement | workers | runs | s (finished - started) | per run |")
    print("| --- | ---: | ---: | ---: | ---: |")
    print("\n".join(rows))
    print(f"\nSpeed-up two workers / one on the reduced Table 2: {t2[1] / t2[2]:.2f}x "
          f"(target >= 1.8x).")
    return 0


if __name__ == "__main__":
    sys.exit(main())
