#!/usr/bin/env python3
"""The recorder's own speed: write one job's MCAP from its stored results, as the recorder
process does when it opens a job or catches up (``Store.iter_run_records`` then
``JobRecorder.add``, /results and /curves messages, 1 MiB chunks compressed as
``$SWARMPATH_MCAP_COMPRESSION`` says: lz4 by default, zstd or none).

    .venv/bin/python scripts/bench/recorder_rebuild.py [--runs 20000] [--data /tmp/rec-bench]

The store is filled once (Table-2-sized GWO runs: 2 dims, 500-point curves, two cells) and
reused by later calls with the same ``--data`` and ``--runs``; each call removes the MCAP files
and times the rebuild (CPU seconds of this process). Prints runs/s of one core.
"""

from __future__ import annotations

import argparse
import shutil
import time
from pathlib import Path

import numpy as np

from swarmpath.service.incoming import Incoming
from swarmpath.service.recorder import Recorders
from swarmpath.service.store import Store


def fill(data: Path, runs: int) -> str:
    """A store holding one finished job of ``runs`` accepted runs; its job id."""
    marker = data / f"job-{runs}"
    if marker.is_file():
        return marker.read_text()
    shutil.rmtree(data, ignore_errors=True)
    store = Store(data, synchronous="NORMAL")
    job = store.create_job({
        "kind": "benchmark", "algorithms": ["GWO"], "functions": ["F1", "F2"], "dims": [2],
        "runs": runs // 2, "agents": 2, "iterations": 500, "seed": 7}, now=1e6)
    curve = np.linspace(1.0, 0.0, 500)
    while (lease := store.lease("w1", 200, now=1e6)) is not None:
        store.accept_results([
            Incoming(lease.lease_id, lease.job_id, lease.cell, run, "w1", "ok", None, 0.001,
                     {"best_fitness": 1e-3 * run, "evaluations": 1000}, curve * run,
                     np.zeros(2), None, lease.capability)
            for run in lease.runs], 1e6)
    store.close()
    marker.write_text(job)
    return job


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=20000)
    ap.add_argument("--data", type=Path, default=Path("/tmp/swarmpath-recorder-bench"))
    args = ap.parse_args()
    job = fill(args.data, args.runs)
    shutil.rmtree(args.data / "mcap", ignore_errors=True)
    store = Store(args.data)
    recorders = Recorders(store)
    start = time.process_time()
    recorders.open(job)  # written from the store
    path = recorders.finish(job)
    cpu = time.process_time() - start
    store.close()
    print(f"{args.runs} runs: {cpu:.2f} s CPU, {args.runs / cpu:,.0f} runs/s of one core "
          f"({path.stat().st_size / args.runs:,.0f} MCAP bytes per run)")


if __name__ == "__main__":
    main()
