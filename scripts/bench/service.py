#!/usr/bin/env python3
"""The service's speed: per-run dispatch overhead, one versus two workers, Table 2 at scale.

    .venv/bin/python scripts/bench/service.py [--dispatch-runs 2000] [--table2-runs 30]
                                              [--big-table2 RUNS | --full-table2] [--skip ...]
                                              [--stacking RUNS]

Each measurement starts its own ``swarmpath up --workers N`` (coordinator + N local workers, one
slot each) on free loopback ports with a fresh data directory, submits one job through the REST
API and reads the job's ``started``/``finished`` times from ``GET /jobs/{id}`` (the coordinator's
clock: first lease to last result, no client polling in it); the processes are stopped (SIGTERM,
then SIGKILL) afterwards. Every row also has the CPU seconds spent during the job by the
coordinator, the worker processes and their slot processes (from /proc), and the 1-minute load
average before and after it: the machine is shared, so read timings next to the load.

Part (a) dispatch: GWO on F1, 2 dims, 5 agents, 1 iteration, ``--dispatch-runs`` runs (2000):
each run computes almost nothing, so (finished - started) / runs_total is the per-run cost of
leasing, executing and recording through the service. Target < 2 ms per run. Leases are sized
by expected work and a worker computes a lease's runs as one vectorized batch, so this cost is
amortized over many runs per lease; the second measurement (GWO and PSO x F1-F13 x dims 2-11, one
run per cell: 260 leases of one run) shows the cost per lease, which bundles of leases (several
per reply, their results in one batch and one transaction) and prefetching amortize.

Part (b) the ICOOT paper's Table 2 setting: PSO, SSA, FDO, mCOOT, COOT, ICOOT x F1-F13 x 30 dims x
30 agents x 500 iterations x ``--table2-runs`` runs per cell (30, as in issue 2's Table 2 study;
the paper itself reports 1000, part c), with one worker and then with two. Target speed-up
>= 1.8x.

Part (c), only when asked: ``--big-table2 RUNS`` runs Table 2 at RUNS runs per cell with two
workers and extrapolates linearly to 1000 runs per cell; ``--full-table2`` runs the paper's own
scale (78 cells x 1000 runs; target < 15 min).

Part (d), only when asked: ``--stacking RUNS`` runs Table 2 at RUNS runs per cell with two
workers twice, with their default stacking (a bundle's leases that differ only in the function
run as one batch) and with ``--no-stacking`` (every lease alone), and prints the slots' CPU
milliseconds per run side by side.

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
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import httpx
from polling import wait_until  # scripts/bench/polling.py

ROOT = Path(__file__).resolve().parents[2]
ENV = {**os.environ, "PYTHONPATH": str(ROOT / "services"), "PYTHONUNBUFFERED": "1"}
ENV.pop("SWARMPATH_TOKEN", None)

TABLE2_ALGORITHMS = ["PSO", "SSA", "FDO", "mCOOT", "COOT", "ICOOT"]
TABLE2_FUNCTIONS = [f"F{i}" for i in range(1, 14)]


CLK_TCK = os.sysconf("SC_CLK_TCK")
LOG_LEVEL = "warning"


def process_cpu(root: int) -> dict[str, float]:
    """CPU seconds (user + system) of ``root`` and its live descendants, by role: the
    coordinator (``root``, the ``swarmpath up`` process), its MCAP recorder process (the child
    started by multiprocessing), its workers (the other children) and their slots
    (grandchildren). Linux /proc only; empty elsewhere."""
    stats: dict[int, tuple[int, float]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            text = (entry / "stat").read_text()
        except OSError:
            continue
        fields = text[text.rindex(")") + 2:].split()  # after "pid (comm) "
        stats[int(entry.name)] = (int(fields[1]), (int(fields[11]) + int(fields[12])) / CLK_TCK)
    depth = {root: 0}
    changed = True
    while changed:
        changed = False
        for pid, (ppid, _cpu) in stats.items():
            if pid not in depth and ppid in depth:
                depth[pid] = depth[ppid] + 1
                changed = True
    out = {"coordinator": 0.0, "recorder": 0.0, "workers": 0.0, "slots": 0.0}
    for pid, d in depth.items():
        if pid in stats:
            role = ("coordinator", "workers", "slots")[min(d, 2)]
            if d == 1 and _multiprocessing_child(pid):
                role = "recorder"
            out[role] += stats[pid][1]
    return out


def _multiprocessing_child(pid: int) -> bool:
    """A process started by multiprocessing (the coordinator's recorder, its resource tracker)."""
    try:
        return b"multiprocessing" in (Path("/proc") / str(pid) / "cmdline").read_bytes()
    except OSError:
        return False


def note(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Up:
    """``swarmpath up --workers N`` on free loopback ports, stopped on exit."""

    def __init__(self, workers: int, tmp: Path, extra: Sequence[str] = ()):
        self.workers = workers
        http, zport = free_port(), free_port()
        self.url = f"http://127.0.0.1:{http}"
        data = tmp / f"data-{workers}w-{http}"
        self.log = open(tmp / f"up-{workers}w-{http}.log", "ab")  # closed in stop()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "swarmpath.cli", "up", "--workers", str(workers), "--slots", "1",
             "--http", f"127.0.0.1:{http}", "--zenoh", f"tcp/127.0.0.1:{zport}",
             "--data", str(data), "--log-level", LOG_LEVEL, *extra],
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
        def exited() -> str | None:
            if self.proc.poll() is not None:
                return f"swarmpath up exited ({self.proc.returncode})"
            return None

        wait_until(cond, timeout, what, exited, f"log in {self.log.name}", poll)

    def run_job(self, spec: dict[str, Any], timeout: float) -> dict[str, Any]:
        """Submit, wait for the end; the status gets ``cpu`` (CPU seconds spent by role during
        the job) and ``load`` (load averages before and after)."""
        load0 = os.getloadavg()
        cpu0 = process_cpu(self.proc.pid)
        r = self.http.post("/jobs", json=spec)
        r.raise_for_status()
        job = r.json()["id"]
        final: dict[str, Any] = {}

        def ended() -> bool:
            final.update(self.http.get(f"/jobs/{job}").json())
            return final["state"] in ("done", "failed", "cancelled")

        self.wait(ended, timeout, f"job {job}", poll=0.5)
        cpu1 = process_cpu(self.proc.pid)
        if final["state"] != "done" or final["runs_done"] != final["runs_total"]:
            raise RuntimeError(f"job {job} ended {final}")
        final["cpu"] = {k: cpu1[k] - cpu0.get(k, 0.0) for k in cpu1}
        final["load"] = (load0[0], os.getloadavg()[0])
        final["tail"] = self.tail(job, final)
        return final

    def tail(self, job: str, status: dict[str, Any]) -> float:
        """Seconds between the first worker's last result and the job's end: how long the job
        ran on fewer than all workers at its end (0 with one worker)."""
        last: dict[str, float] = {}
        offset = 0
        while offset < status["runs_total"]:
            page = self.http.get(f"/jobs/{job}/runs",
                                 params={"limit": 1000, "offset": offset}).json()
            for item in page["items"]:
                if item.get("completed") is not None:
                    last[item["worker"]] = max(last.get(item["worker"], 0.0), item["completed"])
            offset += 1000
        if len(last) < 2:
            return 0.0
        return float(status["finished"]) - min(last.values())

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


def run(tmp: Path, workers: int, spec: dict[str, Any], what: str,
        extra: Sequence[str] = ()) -> dict[str, Any]:
    with Up(workers, tmp, extra) as up:
        note(f"{what}: {workers} worker(s) ...")
        status = up.run_job(spec, timeout=86400)
    note(f"  {elapsed(status):.2f} s, load {status['load'][0]:.2f} -> {status['load'][1]:.2f}")
    return status


def dispatch_spec(runs: int) -> dict[str, Any]:
    return {"kind": "benchmark", "algorithms": ["GWO"], "functions": ["F1"], "dims": [2],
            "agents": 5, "iterations": 1, "runs": runs, "seed": 1}


def one_run_cells_spec() -> dict[str, Any]:
    """One run per cell: every lease holds a single run (nothing to vectorize)."""
    return {"kind": "benchmark", "algorithms": ["GWO", "PSO"], "functions": TABLE2_FUNCTIONS,
            "dims": list(range(2, 12)), "agents": 5, "iterations": 1, "runs": 1, "seed": 1}


def table2_spec(runs: int) -> dict[str, Any]:
    return {"kind": "benchmark", "algorithms": TABLE2_ALGORITHMS, "functions": TABLE2_FUNCTIONS,
            "dims": [30], "agents": 30, "iterations": 500, "runs": runs, "seed": 1}


def row(what: str, workers: int, status: dict[str, Any], digits: int = 2) -> str:
    secs, total = elapsed(status), status["runs_total"]
    cpu = status["cpu"]
    return (f"| {what} | {workers} | {total} | {secs:.{digits}f} | {1000 * secs / total:.2f} ms "
            f"| {cpu['coordinator']:.1f} / {cpu['workers']:.1f} / {cpu['slots']:.1f} "
            f"| {status['tail']:.2f} | {status['load'][0]:.2f} -> {status['load'][1]:.2f} |")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dispatch-runs", type=int, default=2000)
    ap.add_argument("--table2-runs", type=int, default=30, help="runs per cell of part (b)")
    ap.add_argument("--big-table2", type=int, default=0, metavar="RUNS",
                    help="also Table 2 at RUNS runs per cell with two workers, extrapolated to "
                         "the paper's 1000 (long)")
    ap.add_argument("--full-table2", action="store_true",
                    help="also the paper's scale: 1000 runs per cell with two workers (long)")
    ap.add_argument("--skip", default="", help="comma list of parts to leave out: "
                    "dispatch, leases, table2")
    ap.add_argument("--stacking", type=int, default=0, metavar="RUNS",
                    help="also Table 2 at RUNS runs per cell with two workers, stacked and "
                         "--no-stacking: the slots' CPU per run side by side")
    ap.add_argument("--log-level", default="warning", help="of the swarmpath up processes")
    args = ap.parse_args(argv)
    skip = set(filter(None, args.skip.split(",")))
    global LOG_LEVEL
    LOG_LEVEL = args.log_level

    load0 = os.getloadavg()
    t0 = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    rows: list[str] = []
    notes: list[str] = []
    with tempfile.TemporaryDirectory(prefix="swarmpath-bench-") as d:
        tmp = Path(d)
        if "dispatch" not in skip:
            for workers in (1, 2):
                st = run(tmp, workers, dispatch_spec(args.dispatch_runs), "dispatch")
                rows.append(row("dispatch: GWO F1 dim 2, 5 agents, 1 iteration", workers, st))
        if "leases" not in skip:
            for workers in (1, 2):
                st = run(tmp, workers, one_run_cells_spec(), "one-run cells")
                rows.append(row("dispatch, one run per cell: GWO+PSO x F1-F13 x dims 2-11, "
                                "5 agents, 1 iteration", workers, st))
        t2: dict[int, dict[str, Any]] = {}
        if "table2" not in skip:
            for workers in (1, 2):
                t2[workers] = st = run(tmp, workers, table2_spec(args.table2_runs), "table2")
                rows.append(row(f"Table 2: 6 algorithms x F1-F13, dim 30, 30 agents, "
                                f"500 it., {args.table2_runs} runs/cell", workers, st))
            speedup = elapsed(t2[1]) / elapsed(t2[2])
            slots = {w: t2[w]["cpu"]["slots"] for w in t2}
            cores = {w: slots[w] / elapsed(t2[w]) for w in t2}
            notes.append(
                f"Speed-up two workers / one on Table 2 ({args.table2_runs} runs per cell): "
                f"**{speedup:.3f}x** (target "
                f">= 1.8x). CPU seconds in the slots (the computing processes): "
                f"{slots[1]:.1f} with one worker, {slots[2]:.1f} with two "
                f"({slots[2] / max(slots[1], 1e-9):.2f}x the CPU for the same runs); the slots "
                f"got {cores[1]:.2f} cores with one worker and {cores[2]:.2f} with two "
                f"({cores[2] / max(cores[1], 1e-9):.2f}x). On an otherwise idle machine (each "
                f"slot on a full core) the same CPU would give "
                f"{slots[1] / (slots[2] / 2):.2f}x.")
        if args.stacking:
            cpu: dict[str, float] = {}
            for label, extra in (("stacked", ()), ("unstacked", ("--no-stacking",))):
                st = run(tmp, 2, table2_spec(args.stacking),
                         f"table2 at {args.stacking} runs/cell, {label}", extra)
                rows.append(row(f"Table 2 at {args.stacking} runs/cell, {label} "
                                f"(`up {' '.join(extra) or '--stacking'}`)", 2, st))
                cpu[label] = 1000 * st["cpu"]["slots"] / st["runs_total"]
            notes.append(
                f"Slot CPU per run at {args.stacking} runs per cell, two workers: stacked "
                f"**{cpu['stacked']:.1f} ms**, unstacked **{cpu['unstacked']:.1f} ms** "
                f"({cpu['unstacked'] / max(cpu['stacked'], 1e-9):.2f}x).")
        big = 1000 if args.full_table2 else args.big_table2
        if big:
            st = run(tmp, 2, table2_spec(big), f"table2 at {big} runs/cell")
            rows.append(row(f"Table 2 at {big} runs/cell", 2, st, digits=1))
            secs = elapsed(st)
            if big != 1000:
                notes.append(
                    f"Table 2 at {big} runs per cell with two workers: {secs:.1f} s; "
                    f"**extrapolated** to 1000 runs per cell (x {1000 / big:g}, linear in the "
                    f"runs): {secs * 1000 / big / 60:.1f} min (target < 15 min).")
            else:
                notes.append(f"Table 2 at 1000 runs per cell with two workers: {secs / 60:.1f} min "
                             f"(target < 15 min).")
            notes.append(
                f"Coordinator CPU: {1000 * st['cpu']['coordinator'] / st['runs_total']:.2f} ms "
                f"per run ({st['cpu']['coordinator']:.1f} s for {st['runs_total']} runs).")
    load1 = os.getloadavg()

    print(f"Started {t0}; machine {platform.machine()}, {os.cpu_count()} CPUs, Python "
          f"{platform.python_version()}; load average (1/5/15 min) at start "
          f"{' / '.join(f'{x:.2f}' for x in load0)}, at the end "
          f"{' / '.join(f'{x:.2f}' for x in load1)}.\n")
    print("| measurement | workers | runs | s (finished - started) | per run "
          "| CPU s: coordinator / workers / slots | tail s | load (1 min) before -> after |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    print("\n".join(rows))
    if notes:
        print("\n" + "\n\n".join(notes))
    return 0


if __name__ == "__main__":
    sys.exit(main())
