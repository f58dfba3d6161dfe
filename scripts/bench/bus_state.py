#!/usr/bin/env python3
"""Memory and GET /workers under made-up worker ids (issue 13's bounded-state check).

    .venv/bin/python scripts/bench/bus_state.py [--ids 100000] [--max-workers 1024]

A coordinator core without a network (FastAPI TestClient, a fresh data directory, one queued
job) receives, for each of ``--ids`` made-up worker ids, what a hostile bus client can send: a
lease request, a result batch for a made-up lease, a progress message with a made-up proof, and a
liveliness token (a worker login declaring tokens under many ids). Prints the resident memory
before and after (from /proc/self/status, after a garbage collection), the worker table's size,
the refusals, and the median and maximum time of GET /workers over 20 calls. Markdown on stdout.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "services"))

from fastapi.testclient import TestClient

from swarmpath.service.coordinator import CoordinatorSettings, create_app
from swarmpath.service.protocol import LeaseRequest, encode


def rss_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ids", type=int, default=100_000)
    ap.add_argument("--max-workers", type=int, default=1024)
    args = ap.parse_args()
    os.environ.pop("SWARMPATH_TOKEN", None)
    with tempfile.TemporaryDirectory() as tmp:
        settings = CoordinatorSettings(data_dir=Path(tmp), max_workers=args.max_workers,
                                       synchronous="NORMAL")
        app = create_app(settings, use_zenoh=False)
        with TestClient(app) as client:
            core = app.state.core
            job = client.post("/jobs", json={
                "kind": "benchmark", "algorithms": ["GWO"], "functions": ["F1"], "dims": [2],
                "runs": 10, "agents": 5, "iterations": 5, "seed": 1}).json()["id"]
            for _ in range(50):  # warm the paths measured below
                client.get("/workers")
            gc.collect()
            before = rss_mb()
            started = time.perf_counter()
            for i in range(args.ids):
                worker = f"made-up-{i}"
                core.handle_lease_request(encode(LeaseRequest(worker=worker)))
                batch = {"worker": worker, "results": [{
                    "lease_id": f"L{i}", "job_id": job, "cell": "GWO/F1/2", "run": 0,
                    "worker": worker, "seconds": 0.0, "proof": f"{i:064x}"}]}
                core.handle_results(f"swarmpath/results/{job}", json.dumps(batch).encode())
                progress = {"lease_id": f"L{i}", "job_id": job, "worker": worker,
                            "cell": "GWO/F1/2", "runs": [0], "seq": 1, "proof": f"{i:064x}"}
                core.handle_progress(f"swarmpath/progress/{job}", json.dumps(progress).encode())
                core.worker_alive(worker)
            fed = time.perf_counter() - started
            gc.collect()
            after = rss_mb()
            times = []
            for _ in range(20):
                t0 = time.perf_counter()
                r = client.get("/workers")
                times.append(time.perf_counter() - t0)
            listed, size = len(r.json()), len(r.content)
            table, refused = len(core.worker_table), core.worker_table.refused
    load = os.getloadavg()[0]
    print("| ids | RSS before | RSS after | growth | table | refused | GET /workers "
          "(median, max) | listed | bytes | feed time | load |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    print(f"| {args.ids:,} | {before:.1f} MB | {after:.1f} MB | {after - before:+.1f} MB | "
          f"{table} | {refused:,} | {1000 * statistics.median(times):.1f} ms, "
          f"{1000 * max(times):.1f} ms | {listed} | {size:,} | {fed:.0f} s | {load:.2f} |")


if __name__ == "__main__":
    main()
