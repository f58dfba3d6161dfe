#!/usr/bin/env python3
"""Wall time of ``swarmpath reproduce TABLE`` locally (``-j 2``) and through the service
(``swarmpath up --workers 2`` on free loopback ports, ``--url``).

    .venv/bin/python scripts/bench/reproduce.py [--table icoot-table2] [--runs 1000]
                                                [--skip local|service] [--backend numba]
                                                [--no-stacking]

``--backend`` is passed to ``swarmpath reproduce`` (both ways); the service's workers stack the
leases of a bundle that differ only in the function (docs/service.md, Stacking) unless
``--no-stacking`` is given, which is passed to ``swarmpath up``.

Each row: the command, its wall time (the whole command: the study, the verdicts, the output),
the 1-minute load average before and after, and whether both ways gave the same runs (they must:
a run depends only on the spec, the seed and its index). The service is stopped afterwards
(SIGTERM, then SIGKILL). Markdown goes to stdout, progress to stderr. The machine may be shared:
read the timings next to the load.
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


def timed(args: list[str]) -> tuple[float, dict, float, float]:
    before = load()
    started = time.perf_counter()
    out = subprocess.run([*CLI, *args], env=ENV, check=True, capture_output=True, text=True)
    seconds = time.perf_counter() - started
    return seconds, json.loads(out.stdout), before, load()


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


def service_run(args: list[str], up_extra: list[str]) -> tuple[float, dict, float, float]:
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
            return timed([*args, "--url", url])
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
    ap.add_argument("--no-stacking", action="store_true",
                    help="the service's workers run every lease alone (swarmpath up "
                         "--no-stacking)")
    opts = ap.parse_args()
    base = ["reproduce", opts.table, "--runs", str(opts.runs), "--json"]
    if opts.backend:
        base += ["--backend", opts.backend]
    up_extra = ["--no-stacking"] if opts.no_stacking else []
    rows, docs = [], []
    if "local" not in opts.skip:
        print("local -j 2 ...", file=sys.stderr)
        seconds, doc, before, after = timed([*base, "-j", "2"])
        rows.append((f"swarmpath {' '.join(base)} -j 2", seconds, before, after))
        docs.append(doc)
    if "service" not in opts.skip:
        print("service, 2 workers ...", file=sys.stderr)
        seconds, doc, before, after = service_run(base, up_extra)
        up = " ".join(["swarmpath up --workers 2", *up_extra])
        rows.append((f"swarmpath {' '.join(base)} --url URL ({up})",
                     seconds, before, after))
        docs.append(doc)
    print("| command | wall s | load before / after |")
    print("| --- | --- | --- |")
    for command, seconds, before, after in rows:
        print(f"| `{command}` | {seconds:.1f} | {before:.1f} / {after:.1f} |")
    if len(docs) == 2:
        same = [a["runs"] for a in docs[0]["cells"]] == [b["runs"] for b in docs[1]["cells"]]
        print(f"\nSame runs both ways: {same}; {docs[0]['unexplained']} unexplained cells.")


if __name__ == "__main__":
    main()
