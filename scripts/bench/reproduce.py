#!/usr/bin/env python3
"""Wall time of ``swarmpath reproduce TABLE`` locally (``-j 2``) and through the service
(``swarmpath up --workers 2`` on free loopback ports, ``--url``).

    .venv/bin/python scripts/bench/reproduce.py [--table icoot-table2] [--runs 1000]
                                                [--skip local|service] [--backend numba]
                                                [--no-stacking] [--no-origin-check]

``--backend`` and ``--no-origin-check`` are passed to ``swarmpath reproduce`` (both ways); the
service's workers stack the leases of a bundle that differ only in the function
(docs/service.md, Stacking) unless ``--no-stacking`` is given, which is passed to ``swarmpath
up``. A benchmark table's study runs twice by default (the origin check: the same runs with the
optimum moved), so it counts twice the runs of the table's cells; the row says how many.

Each row: the command, the runs it made, its wall time (the whole command: the study, the
verdicts, the output), the 1-minute load average before and after, the CPU seconds spent during
the command (user + system: the command itself; through the service also its coordinator, MCAP
recorder, workers and slots, which started and warmed before it), CPU milliseconds per run, and
whether both ways gave the same runs (they must: a run depends only on the spec, the seed and
its index). The service is stopped afterwards (SIGTERM, then SIGKILL). Markdown goes to stdout,
progress to stderr. The machine may be shared: read the timings next to the load; CPU figures
depend on it less.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from service import process_cpu  # scripts/bench/service.py, beside this one

ROOT = Path(__file__).resolve().parents[2]
ENV = {**os.environ, "PYTHONPATH": str(ROOT / "services"), "PYTHONUNBUFFERED": "1"}
ENV.pop("SWARMPATH_TOKEN", None)
CLI = [sys.executable, "-m", "swarmpath.cli"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def load() -> float:
    return os.getloadavg()[0]


ROLES = ("client", "coordinator", "recorder", "workers", "slots")


def timed(args: list[str], service: int | None = None) -> tuple[float, dict, float, float,
                                                                  dict[str, float]]:
    """Run the CLI with ``args``: (wall s, its JSON, load before, load after, CPU s by role
    during the command: the command itself and its children ("client"), and the service's
    processes under pid ``service``)."""
    before = load()
    mine = os.times()
    base = process_cpu(service) if service else {}
    started = time.perf_counter()
    out = subprocess.run([*CLI, *args], env=ENV, check=True, capture_output=True, text=True)
    seconds = time.perf_counter() - started
    spent = process_cpu(service) if service else {}
    done = os.times()
    cpu = {"client": (done.children_user + done.children_system
                      - mine.children_user - mine.children_system)}
    cpu.update({role: spent.get(role, 0.0) - base.get(role, 0.0) for role in spent})
    return seconds, json.loads(out.stdout), before, load(), cpu


def wait_idle(root: int, timeout: float = 1800.0) -> None:
    """Until the service's processes stop spending CPU (the slots' warm-up done): two
    successive 3 s samples within 0.3 CPU s."""
    deadline = time.monotonic() + timeout
    last = -1.0
    while time.monotonic() < deadline:
        time.sleep(3.0)
        now = sum(process_cpu(root).values())
        if now - last < 0.3:
            return
        last = now
    raise RuntimeError(f"the service was still busy after {timeout} s")


def wait_http(url: str, timeout: float = 60.0) -> None:
    import httpx

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            if httpx.get(f"{url}/healthz", timeout=1.0).status_code == 200:
                return
        except httpx.HTTPError:
            pass
        time.sleep(0.5)
    raise RuntimeError(f"coordinator at {url} did not answer within {timeout} s")


def service_run(args: list[str], up_extra: list[str]) -> tuple[float, dict, float, float,
                                                               dict[str, float]]:
    http, zenoh = free_port(), free_port()
    url = f"http://127.0.0.1:{http}"
    with tempfile.TemporaryDirectory() as data:
        proc = subprocess.Popen(
            [*CLI, "up", "--workers", "2", "--http", f"127.0.0.1:{http}",
             "--zenoh", f"tcp/127.0.0.1:{zenoh}", "--data", data, "--log-level", "warning",
             *up_extra],
            env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
        try:
            wait_http(url)
            wait_idle(proc.pid)
            return timed([*args, "--url", url], proc.pid)
        finally:
            os.killpg(proc.pid, signal.SIGTERM)
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--table", default="icoot-table2")
    ap.add_argument("--runs", type=int, default=1000)
    ap.add_argument("--skip", choices=["local", "service"], action="append", default=[])
    ap.add_argument("--backend", default=None, help="passed to swarmpath reproduce")
    ap.add_argument("--no-origin-check", action="store_true",
                    help="passed to swarmpath reproduce: the table's cells once, not also "
                         "shifted")
    ap.add_argument("--no-stacking", action="store_true",
                    help="the service's workers run every lease alone (swarmpath up "
                         "--no-stacking)")
    opts = ap.parse_args()
    base = ["reproduce", opts.table, "--runs", str(opts.runs), "--json"]
    if opts.backend:
        base += ["--backend", opts.backend]
    if opts.no_origin_check:
        base.append("--no-origin-check")
    up_extra = ["--no-stacking"] if opts.no_stacking else []
    rows, docs = [], []
    if "local" not in opts.skip:
        print("local -j 2 ...", file=sys.stderr)
        seconds, doc, before, after, cpu = timed([*base, "-j", "2"])
        rows.append((f"swarmpath {' '.join(base)} -j 2", doc, seconds, before, after, cpu))
        docs.append(doc)
    if "service" not in opts.skip:
        print("service, 2 workers ...", file=sys.stderr)
        seconds, doc, before, after, cpu = service_run(base, up_extra)
        up = " ".join(["swarmpath up --workers 2", *up_extra])
        rows.append((f"swarmpath {' '.join(base)} --url URL ({up})",
                     doc, seconds, before, after, cpu))
        docs.append(doc)
    print("| command | runs | wall s | load before / after | CPU s: "
          + " / ".join(ROLES) + " | CPU ms per run: all / slots |")
    print("| --- | ---: | ---: | --- | --- | --- |")
    for command, doc, seconds, before, after, cpu in rows:
        runs = study_runs(doc)
        spent = " / ".join(f"{cpu[role]:.1f}" if role in cpu else "-" for role in ROLES)
        slots = f"{1000 * cpu['slots'] / runs:.2f}" if "slots" in cpu else "-"
        print(f"| `{command}` | {runs} | {seconds:.1f} | {before:.1f} / {after:.1f} | {spent} "
              f"| {1000 * sum(cpu.values()) / runs:.2f} / {slots} |")
    if len(docs) == 2:
        same = all([c.get(k) for c in docs[0]["cells"]] == [c.get(k) for c in docs[1]["cells"]]
                   for k in ("runs", "shifted_runs"))
        print(f"\nSame runs both ways: {same}; {docs[0]['unexplained']} unexplained cells.")


def study_runs(doc: dict) -> int:
    """Runs the study made: each cell's runs, and its shifted runs (the origin check)."""
    return sum(len(c.get("runs") or []) + len(c.get("shifted_runs") or []) for c in doc["cells"])


if __name__ == "__main__":
    main()
