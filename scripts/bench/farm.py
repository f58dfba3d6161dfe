#!/usr/bin/env python3
"""The farm simulator: one real coordinator, K simulated workers, one job; how fast it is taken.

    .venv/bin/python scripts/bench/farm.py [--workers K] [--slots S] [--procs P] [--runs N]
        [--cells C] [--iterations I] [--agents A] [--dim D] [--algorithm GWO] [--function F1]
        [--map mfb-static --planner MFB] [--run-ms MS] [--runs-per-lease R] [--max-leases L]
        [--seconds T] [--jobs N] [--zenoh-config FILE] [--json FILE] [--data DIR]
        [--profile OUT.raw [--rate HZ]]

What runs: ``swarmpath coordinator`` as a subprocess on free loopback ports (HTTP, Zenoh router
with usrpwd authentication, a fresh data directory: its real SQLite store and MCAP recorder), and
P subprocesses of scripts/bench/farm_workers.py holding K simulated workers between them: each is
the real worker (own Zenoh client session logged in with the farm's login, liveliness token,
lease queries, heartbeats, result batches with their lease capability's HMAC, acks) whose slots
return real precomputed results (same shape as a real run: ``iterations``-point curve, best
position, metrics; map runs: path and metrics) after ``--run-ms`` per run instead of computing.
One job is submitted through the REST API with its bearer token: ``--cells`` cells (functions
F1.. in turn; or one map cell per ``--map``) of ``--runs`` runs each. Bounded: the job is
cancelled after ``--seconds``.

Reported (markdown on stdout, everything as JSON with ``--json``): accepted runs/s (the job's
runs over the coordinator's first-lease-to-last-result time), the coordinator process's CPU per
accepted run (user + system from /proc over the job), ack latency (a worker's put of a result to
its ack) and lease round trip (query to reply) p50/p99, store bytes per run (SQLite after the
coordinator closed it) and MCAP bytes per run, the coordinator's RSS over time (anonymous and
file-backed; at 0/25/50/75/100 % of each job's runs and its slope over the second half:
scripts/bench/farm_memory.py), the workers the
coordinator saw alive, and how the runs were spread over the workers (min/median/max per worker,
workers with none). The machine is shared: read times next to the load averages reported.

``--profile OUT``: samples the coordinator with py-spy (``pip install py-spy``; not a dependency)
over the job(s) and prints its top functions by own and cumulative samples (one raw file per
measurement: OUT with the tree and K in its name).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import secrets
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx
from coordinator import summarize  # scripts/bench/coordinator.py
from farm_memory import memory_profile, proc_memory, profile_line  # scripts/bench/farm_memory.py
from polling import wait_until  # scripts/bench/polling.py

ROOT = Path(__file__).resolve().parents[2]


def tree_env(root: Path) -> dict[str, str]:
    """The environment that runs the coordinator and the simulator of checkout ``root``."""
    env = {**os.environ, "PYTHONPATH": str(root / "services"), "PYTHONUNBUFFERED": "1"}
    env.pop("SWARMPATH_TOKEN", None)
    return env
CLK_TCK = os.sysconf("SC_CLK_TCK")


def note(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def proc_cpu(pid: int) -> float:
    """CPU seconds (user + system) of one process, from /proc (its memory: proc_memory)."""
    text = Path(f"/proc/{pid}/stat").read_text()
    fields = text[text.rindex(")") + 2:].split()
    return (int(fields[11]) + int(fields[12])) / CLK_TCK


def children_cpu(pid: int) -> float:
    """CPU seconds of the live children of ``pid`` (the coordinator's MCAP recorder process)."""
    total = 0.0
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                text = (entry / "stat").read_text()
            except OSError:
                continue
            fields = text[text.rindex(")") + 2:].split()
            if int(fields[1]) == pid:
                total += (int(fields[11]) + int(fields[12])) / CLK_TCK
    return total


def percentile(values: list[float], q: float) -> float:
    if not values:
        return float("nan")
    values = sorted(values)
    return values[min(len(values) - 1, int(q / 100 * len(values)))]


def job_spec(args: argparse.Namespace) -> dict[str, Any]:
    if args.map:
        return {"kind": "map", "planners": [args.planner], "maps": args.map, "runs": args.runs,
                "seed": 1}
    functions = [f"F{i}" for i in range(1, 14)]
    cells = [(functions[i % 13], args.dim + i // 13) for i in range(args.cells)]
    return {"kind": "benchmark", "algorithms": [args.algorithm],
            "functions": sorted({f for f, _ in cells}, key=functions.index),
            "dims": sorted({d for _, d in cells}), "runs": args.runs, "agents": args.agents,
            "iterations": args.iterations, "seed": 1,
            # the simulated slots compute a few template runs per cell with the spec's backend:
            # numpy keeps numba's first compile (seconds per simulator process) out of the job
            "backend": "numpy"}


class Farm:
    """The coordinator and the simulator processes (started in __enter__, stopped in __exit__)."""

    def __init__(self, args: argparse.Namespace, data: Path, root: Path = ROOT):
        self.args = args
        self.data = data
        self.root = root
        self.token = secrets.token_urlsafe(24)
        self.login = ("farm", secrets.token_urlsafe(24))
        self.http_port, self.zenoh_port = free_port(), free_port()
        self.coordinator: subprocess.Popen[bytes] | None = None
        self.rss_bare = 0.0
        self.sims: list[tuple[subprocess.Popen[bytes], Path]] = []
        self.client = httpx.Client(base_url=f"http://127.0.0.1:{self.http_port}", timeout=30.0,
                                   headers={"Authorization": f"Bearer {self.token}"})
        self.log = open(data / "farm.log", "ab")

    def __enter__(self) -> Farm:
        try:
            self._start()
        except BaseException:
            self.__exit__()
            raise
        return self

    def _start(self) -> None:
        a = self.args
        users = self.data / "users.txt"
        users.write_text(f"{self.login[0]}:{self.login[1]}\n")
        users.chmod(0o600)
        self.coordinator = subprocess.Popen(
            [sys.executable, "-m", "swarmpath.cli", "coordinator",
             "--http", f"127.0.0.1:{self.http_port}",
             "--zenoh", f"tcp/127.0.0.1:{self.zenoh_port}", "--data", str(self.data / "store"),
             "--auth-dictionary", str(users), "--lease-seconds", str(a.lease_seconds),
             "--log-level", a.log_level,
             *(["--zenoh-config", str(a.zenoh_config)] if a.zenoh_config else [])],
            stdout=self.log, stderr=self.log, start_new_session=True,
            env={**tree_env(self.root), "SWARMPATH_TOKEN": self.token})
        self.wait(lambda: self.client.get("/healthz").status_code == 200, 60, "coordinator")
        self.rss_bare = proc_memory(self.coordinator.pid)[0]  # before any worker connects
        procs = max(1, min(a.procs, a.workers))
        env = {**tree_env(self.root), "SWARMPATH_ZENOH_USER": self.login[0],
               "SWARMPATH_ZENOH_PASSWORD": self.login[1]}
        for p in range(procs):
            count = a.workers // procs + (1 if p < a.workers % procs else 0)
            stats = self.data / f"sim-{p}.json"
            cmd = [sys.executable, str(self.root / "scripts" / "bench" / "farm_workers.py"),
                   "--connect", f"tcp/127.0.0.1:{self.zenoh_port}", "--count", str(count),
                   "--id-prefix", f"{self.login[0]}-sim{p}",  # ids of the farm's login
                   "--slots", str(a.slots), "--run-ms", str(a.run_ms),
                   "--max-runs", str(a.runs_per_lease), "--max-leases", str(a.max_leases),
                   "--seconds", str(a.seconds + 120), "--stats", str(stats),
                   "--log-level", a.log_level]
            if a.run_jitter:
                cmd += ["--run-jitter", str(a.run_jitter)]
            if a.wrong_capability:
                cmd.append("--wrong-capability")
            self.sims.append((subprocess.Popen(cmd, stdout=self.log, stderr=self.log, env=env,
                                               start_new_session=True), stats))

    def wait(self, cond: Any, timeout: float, what: str, poll: float = 0.2) -> None:
        def exited() -> str | None:
            if self.coordinator is not None and self.coordinator.poll() is not None:
                return "the coordinator exited"
            return None

        wait_until(cond, timeout, what, exited, f"see {self.log.name}", poll)

    def alive(self) -> int:
        return sum(1 for w in self.client.get("/workers").json() if w["alive"])

    def metrics(self) -> dict[str, float]:
        out = {}
        for line in self.client.get("/metrics").text.splitlines():
            if line and not line.startswith("#"):
                name, value = line.split()
                out[name.removeprefix("swarmpath_")] = float(value)
        return out

    def sim_cpu(self) -> float:
        """CPU seconds of the simulator processes so far (to tell when they, not the
        coordinator, are the limit)."""
        total = 0.0
        for proc, _ in self.sims:
            with contextlib.suppress(OSError):
                total += proc_cpu(proc.pid)
        return total

    def stop_sims(self) -> list[dict[str, Any]]:
        for proc, _ in self.sims:
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
        out: list[dict[str, Any]] = []
        for proc, stats in self.sims:
            try:
                proc.wait(60)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(10)
            if stats.is_file():
                out += json.loads(stats.read_text())["workers"]
        return out

    def stop_coordinator(self) -> None:
        proc = self.coordinator
        if proc is None or proc.poll() is not None:
            return
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(30)
        except subprocess.TimeoutExpired:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(10)

    def __exit__(self, *exc: object) -> None:
        for proc, _ in self.sims:
            if proc.poll() is None:
                proc.kill()
                proc.wait(10)
        self.stop_coordinator()
        self.client.close()
        self.log.close()


def store_bytes(store: Path) -> int:
    return sum(p.stat().st_size for p in store.glob("swarmpath.sqlite3*") if p.is_file())


def one_job(args: argparse.Namespace, farm: Farm, spec: dict[str, Any], pid: int, t0: float,
            rss: list[tuple[float, int, float, float, float]]) -> tuple[str, dict[str, Any]]:
    """Submit one job and wait for its end (cancel it after ``args.seconds``), sampling the
    coordinator's memory into ``rss`` (seconds, runs finished, RSS, anonymous, file MB);
    returns its id and final status."""
    r = farm.client.post("/jobs", json=spec)
    r.raise_for_status()
    job = r.json()["id"]
    note(f"farm: job {job} ({r.json()['runs_total']} runs) on {args.workers} workers x "
         f"{args.slots} slots")
    status: dict[str, Any] = {}
    rss.append((round(time.monotonic() - t0, 2), 0, *proc_memory(pid)))
    while True:
        status = farm.client.get(f"/jobs/{job}").json()
        rss.append((round(time.monotonic() - t0, 2),
                    int(status["runs_done"]) + int(status["runs_failed"]), *proc_memory(pid)))
        if status["state"] in ("done", "failed", "cancelled"):
            break
        if time.monotonic() - t0 > args.seconds:
            note(f"farm: {args.seconds} s are up: cancelling job {job}")
            status = farm.client.delete(f"/jobs/{job}").raise_for_status().json()
            break
        time.sleep(0.5)
    return job, status


def run(args: argparse.Namespace, data: Path, root: Path = ROOT) -> dict[str, Any]:
    """One measurement: a coordinator and ``args.workers`` simulated workers of checkout
    ``root``, one job, everything under ``data``."""
    data.mkdir(parents=True, exist_ok=True)
    spec = job_spec(args)
    with Farm(args, data, root) as farm:
        assert farm.coordinator is not None
        pid = farm.coordinator.pid
        farm.wait(lambda: farm.alive() >= args.workers, 60 + args.workers * 0.2,
                  f"{args.workers} workers alive", poll=0.5)
        alive_before = farm.alive()
        idle0 = proc_cpu(pid) + children_cpu(pid)
        time.sleep(args.idle_seconds)  # K live workers, nothing to lease: what they cost
        idle = proc_cpu(pid) + children_cpu(pid) - idle0
        spy = profiler(args, pid, data)  # attached before the CPU count starts
        store0 = store_bytes(data / "store")
        load0 = os.getloadavg()[0]
        cpu0, rss0 = proc_cpu(pid), proc_memory(pid)[0]
        rec0 = children_cpu(pid)
        sim0 = farm.sim_cpu()
        t0 = time.monotonic()
        rss: list[tuple[float, int, float, float, float]] = []
        rss_jobs: list[float] = []  # RSS at the end of each successive job
        profiles: list[dict[str, Any]] = []  # the memory over each job
        finished = last = 0
        span = 0.0
        for _ in range(args.jobs):
            first = len(rss)
            job, status = one_job(args, farm, spec, pid, t0, rss)
            rss_jobs.append(round(proc_memory(pid)[0], 1))
            profiles.append(memory_profile(rss[first:], int(status["runs_total"])))
            last = int(status["runs_done"]) + int(status["runs_failed"])
            finished += last
            span += (float(status["finished"] or time.time()) - float(status["started"] or 0)) \
                if status.get("started") else float("nan")
        cpu1, rss1 = proc_cpu(pid), proc_memory(pid)[0]
        rec1 = children_cpu(pid)
        profile = stop_profiler(spy)
        sim1 = farm.sim_cpu()
        load1 = os.getloadavg()[0]
        metrics = farm.metrics()
        table = farm.client.get("/workers").json()
        sims = farm.stop_sims()
        farm.stop_coordinator()
    done = finished
    per_worker = sorted(int(w["runs_done"]) for w in table)
    rtt = [x for w in sims for x in w["lease_rtt_ms"]]
    ack = [x for w in sims for x in w["ack_ms"]]
    mcap = data / "store" / "mcap" / f"{job}.mcap"
    return {
        "workers": args.workers, "slots": args.slots, "procs": min(args.procs, args.workers),
        "run_ms": args.run_ms, "spec": spec, "job": job, "state": status["state"],
        "runs_total": status["runs_total"] * args.jobs, "runs_finished": done,
        "seconds": round(span, 3), "runs_per_s": round(done / span, 1) if span > 0 else None,
        "coordinator_cpu_s": round(cpu1 - cpu0, 2),
        "cpu_ms_per_run": round((cpu1 - cpu0) * 1e3 / max(1, done), 4),
        "recorder_cpu_ms_per_run": round((rec1 - rec0) * 1e3 / max(1, done), 4),
        "simulator_cpu_s": round(sim1 - sim0, 2),
        "idle_cpu_ms_per_worker_s": round(idle * 1e3 / max(args.idle_seconds, 1e-9)
                                          / args.workers, 4) if args.idle_seconds else None,
        "ack_ms_p50": round(percentile(ack, 50), 2), "ack_ms_p99": round(percentile(ack, 99), 2),
        "lease_rtt_ms_p50": round(percentile(rtt, 50), 2),
        "lease_rtt_ms_p99": round(percentile(rtt, 99), 2),
        "store_bytes_per_run": round((store_bytes(data / "store") - store0) / max(1, done)),
        "mcap_bytes_per_run": round(mcap.stat().st_size / max(1, last)) if mcap.is_file()
        else None,
        "rss_mb": {"bare": round(farm.rss_bare, 1), "start": round(rss0, 1),
                   "max": round(max([rss0] + [x[2] for x in rss]), 1),
                   "end": round(rss1, 1)},
        "rss_end_of_each_job_mb": rss_jobs,
        "memory": profiles,
        "rss_series": [(t, n, round(x, 1), round(a, 1), round(f, 1))
                       for t, n, x, a, f in rss[:: max(1, len(rss) // 40)]],
        "alive_seen": alive_before, "table_entries": len(table),
        "runs_per_worker": {"min": per_worker[0] if per_worker else 0,
                            "median": statistics.median(per_worker) if per_worker else 0,
                            "max": per_worker[-1] if per_worker else 0,
                            "none": sum(1 for x in per_worker if x == 0)},
        "metrics": {k: metrics.get(k) for k in (
            "results_accepted_total", "results_duplicate_total", "results_stale_total",
            "messages_unproven_total", "messages_overload_total", "leases_total",
            "lease_requeues_total", "workers_refused_total", "lease_requests_busy_total")},
        "load": [round(load0, 2), round(load1, 2)],
        "profile": profile,
    }


def profiler(args: argparse.Namespace, pid: int, data: Path) -> tuple[Any, Path] | None:
    """py-spy sampling the coordinator (``--profile``), or None."""
    if args.profile is None:
        return None
    out = args.profile.with_name(f"{args.profile.stem}-{data.name}{args.profile.suffix}")
    proc = subprocess.Popen(
        [str(Path(sys.executable).with_name("py-spy")), "record", "--pid", str(pid),
         "--rate", str(args.rate), "--format", "raw", "--threads", "--nonblocking",
         "-o", str(out)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(1.0)  # attached before the job starts
    return proc, out


def stop_profiler(spy: tuple[Any, Path] | None) -> str | None:
    """Stop py-spy; the summary of its samples."""
    if spy is None:
        return None
    proc, out = spy
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(60)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(10)
    return summarize(out) if out.exists() else None


def markdown(results: list[dict[str, Any]]) -> str:
    head = ("| tree | K | slots | runs | s | runs/s | coord CPU ms/run | recorder CPU ms/run "
            "| sim CPU s | ack p50/p99 ms | lease RTT p50/p99 ms | store B/run | MCAP B/run | "
            "RSS MB start/max/end | alive | runs/worker min/med/max (none) | load |")
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for r in results:
        w = r["runs_per_worker"]
        lines.append(
            f"| {r['tree']} | {r['workers']} | {r['slots']} | "
            f"{r['runs_finished']}/{r['runs_total']} | {r['seconds']} | {r['runs_per_s']} | "
            f"{r['cpu_ms_per_run']} | {r.get('recorder_cpu_ms_per_run', '')} | "
            f"{r['simulator_cpu_s']} | "
            f"{r['ack_ms_p50']}/{r['ack_ms_p99']} | {r['lease_rtt_ms_p50']}/"
            f"{r['lease_rtt_ms_p99']} | {r['store_bytes_per_run']} | {r['mcap_bytes_per_run']} "
            f"| {r['rss_mb']['start']}/{r['rss_mb']['max']}/{r['rss_mb']['end']} | "
            f"{r['alive_seen']} | {w['min']}/{w['median']}/{w['max']} ({w['none']}) | "
            f"{r['load'][0]}-{r['load'][1]} |")
        if len(r.get("rss_end_of_each_job_mb", [])) > 1:
            lines.append(f"\n(K = {r['workers']}, {r['tree']}: RSS MB at the end of each of "
                         f"{len(r['rss_end_of_each_job_mb'])} successive jobs: "
                         f"{', '.join(map(str, r['rss_end_of_each_job_mb']))})\n")
        if r["rss_mb"].get("bare"):
            per = (r["rss_mb"]["start"] - r["rss_mb"]["bare"]) * 1024 / r["workers"]
            lines.append(f"\n(K = {r['workers']}, {r['tree']}: coordinator RSS "
                         f"{r['rss_mb']['bare']} MB before any worker connected, "
                         f"{r['rss_mb']['start']} MB with them alive: {per:.0f} KB per "
                         "connected worker)\n")
        for i, profile in enumerate(r.get("memory", [])):
            lines.append(f"\n(K = {r['workers']}, {r['tree']}, job {i + 1}: "
                         f"{profile_line(profile)})\n")
        if r.get("idle_cpu_ms_per_worker_s") is not None:
            lines.append(f"\n(K = {r['workers']}, {r['tree']}: idle, the coordinator and its "
                         f"recorder spent {r['idle_cpu_ms_per_worker_s']} ms of CPU per worker "
                         "per second)\n")
    base = {r["workers"]: r for r in results if r["tree"] == "baseline"}
    for r in results:
        b = base.get(r["workers"])
        if r["tree"] == "this" and b is not None and b["runs_per_s"] and r["cpu_ms_per_run"]:
            speed = r["runs_per_s"] / b["runs_per_s"]
            cpu = b["cpu_ms_per_run"] / r["cpu_ms_per_run"]
            lines.append(f"\nK = {r['workers']}: runs/s x{speed:.2f}, coordinator CPU per run "
                         f"/ {cpu:.2f} (this tree against the baseline)")
    return "\n".join(lines)


def parse(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", "-k", default="2",
                    help="simulated workers K; a comma list (2,20,200) measures each in turn")
    ap.add_argument("--baseline", type=Path,
                    help="also measure this checkout (e.g. `git archive` of main before a change, "
                    "extracted) alternately with this one, and print the ratios")
    ap.add_argument("--slots", type=int, default=1, help="slots per simulated worker")
    ap.add_argument("--procs", type=int, default=2, help="simulator processes holding them")
    ap.add_argument("--runs", type=int, default=2000, help="runs per cell")
    ap.add_argument("--cells", type=int, default=1, help="benchmark cells (F1, F2, ...)")
    ap.add_argument("--algorithm", default="GWO")
    ap.add_argument("--iterations", type=int, default=500, help="curve length")
    ap.add_argument("--agents", type=int, default=2)
    ap.add_argument("--dim", type=int, default=2)
    ap.add_argument("--map", action="append", help="map runs (with paths) on this preset map")
    ap.add_argument("--planner", default="MFB")
    ap.add_argument("--run-ms", type=float, default=0.0, help="simulated compute per run")
    ap.add_argument("--run-jitter", type=float, default=0.0,
                    help="each group of runs takes run-ms x runs x U(1 - J, 1 + J)")
    ap.add_argument("--runs-per-lease", type=int, default=1000,
                    help="a worker's max_runs per lease (the coordinator sizes below it)")
    ap.add_argument("--max-leases", type=int, default=32, help="leases per bundle at most")
    ap.add_argument("--lease-seconds", type=float, default=30.0)
    ap.add_argument("--zenoh-config", type=Path,
                    help="JSON file of extra Zenoh settings for the coordinator (its "
                    "--zenoh-config), e.g. a smaller transport/link/tx/batch_size")
    ap.add_argument("--seconds", type=float, default=300.0, help="cancel the job after this")
    ap.add_argument("--jobs", type=int, default=1,
                    help="successive jobs on the same coordinator (RSS at the end of each)")
    ap.add_argument("--idle-seconds", type=float, default=0.0,
                    help="before the job: measure the coordinator's CPU this long with the K "
                    "workers alive and nothing to lease (per worker per second)")
    ap.add_argument("--wrong-capability", action="store_true",
                    help="negative control: results proven with a wrong key (never accepted)")
    ap.add_argument("--json", type=Path, help="write the whole result here")
    ap.add_argument("--data", type=Path, help="keep the data directory here (default: temp)")
    ap.add_argument("--log-level", default="warning")
    ap.add_argument("--profile", type=Path,
                    help="py-spy raw stacks of the coordinator over the job, one file per "
                    "measurement named after this one")
    ap.add_argument("--rate", type=int, default=200, help="py-spy samples per second")
    args = ap.parse_args(argv)
    try:
        args.worker_counts = [int(k) for k in str(args.workers).split(",")]
    except ValueError:
        ap.error(f"--workers: {args.workers!r} is not a comma list of integers")
    if args.baseline is not None and not (
            args.baseline / "scripts" / "bench" / "farm_workers.py").is_file():
        ap.error(f"--baseline: {args.baseline} has no scripts/bench/farm_workers.py")
    if min(args.worker_counts) < 1 or args.slots < 1 or args.runs < 1 or args.cells < 1:
        ap.error("--workers, --slots, --runs and --cells must be positive")
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse(argv)
    results: list[dict[str, Any]] = []
    trees = [("this", ROOT)] + ([("baseline", args.baseline)] if args.baseline else [])
    with contextlib.ExitStack() as stack:
        if args.data is None:
            data = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="farm-")))
        else:
            data = args.data
        for k in args.worker_counts:
            for label, root in trees:
                note(f"farm: {label} tree, K = {k}")
                res = run(argparse.Namespace(**{**vars(args), "workers": k}),
                          data / f"{label}-k{k}", root.resolve())
                res["tree"] = label
                results.append(res)
                if args.json:
                    args.json.write_text(json.dumps(results, indent=1))
    print(markdown(results))
    for r in results:
        if r.get("profile"):
            print(f"\n### py-spy, {r['tree']} tree, K = {r['workers']}\n\n{r['profile']}")
    return 0 if all(r["state"] == "done" for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())
