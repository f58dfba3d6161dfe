#!/usr/bin/env python3
"""Per-run exports of a big benchmark job: how fast every run streams out as CSV, Parquet and
JSON lines (``GET /jobs/{id}/runs?format=...``), and the IOHprofiler files written from the JSON
lines (``swarmpath results JOB --format ioh``).

    .venv/bin/python scripts/bench/exports.py [--runs 100]

The job is the ICOOT paper's Table 2 (6 algorithms x F1-F13 x 30 dims x 500 iterations x
``--runs`` runs per cell: 7,800 runs at 100, 78,000 at 1000) with synthetic results fed through
the coordinator's result handler (scripts/bench/dashboard.py ``fill``). The coordinator serves
REST with uvicorn on a free loopback port in this process; each export is downloaded once with
httpx. Markdown goes to stdout, progress to stderr.
"""

from __future__ import annotations

import argparse
import platform
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "services"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import synthetic  # noqa: E402  (scripts/bench/synthetic.py)
from dashboard import FUNCTIONS, TABLE2_ALGORITHMS  # noqa: E402
from service import note  # noqa: E402


def fill(core: Any, spec: dict[str, Any]) -> str:
    """Submit ``spec`` and hand the coordinator's result handler synthetic results (monotone
    best-so-far curves, each result proven with its lease's capability, as a worker sends them).
    """
    job, done = synthetic.fill(core, spec, spec["agents"] * (spec["iterations"] + 1))
    if done.runs_done != done.runs_total:
        raise SystemExit(f"only {done.runs_done} of {done.runs_total} results were accepted")
    return job


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100, help="runs per cell")
    args = parser.parse_args()

    from swarmpath.evidence.ioh import write_ioh
    from swarmpath.service.client import ServiceClient
    from swarmpath.service.coordinator import CoordinatorSettings, create_app

    spec = {"kind": "benchmark", "algorithms": TABLE2_ALGORITHMS, "functions": FUNCTIONS,
            "dims": [30], "runs": args.runs, "agents": 30, "iterations": 500, "seed": 1}
    with tempfile.TemporaryDirectory() as tmp:
        app = create_app(CoordinatorSettings(data_dir=Path(tmp) / "d", synchronous="NORMAL"),
                         use_zenoh=False)
        server, thread, url = synthetic.start_server(app)
        rows = []
        try:
            job = fill(app.state.core, spec)
            total = app.state.core.store.job_status(job).runs_total
            note(f"  {total} runs stored")
            with httpx.Client(base_url=url, timeout=600) as http:
                for fmt in ("csv", "parquet", "jsonl"):
                    t = time.perf_counter()
                    size = 0
                    with http.stream("GET", f"/jobs/{job}/runs", params={"format": fmt}) as r:
                        r.raise_for_status()
                        for chunk in r.iter_bytes():
                            size += len(chunk)
                    s = time.perf_counter() - t
                    rows.append(f"| `?format={fmt}` | {s:.1f} | {total / s:,.0f} | "
                                f"{size / 1e6:.1f} |")
                    note(f"  {fmt}: {s:.1f} s")
            with ServiceClient(url) as client:
                t = time.perf_counter()
                written = write_ioh(client.iter_runs(job), Path(tmp) / "ioh", job)
                s = time.perf_counter() - t
                size = sum(p.stat().st_size for p in written.files)
                rows.append(f"| `--format ioh` ({written.runs} runs, {len(written.files)} "
                            f"files) | {s:.1f} | {total / s:,.0f} | {size / 1e6:.1f} |")
        finally:
            server.should_exit = True
            thread.join(10)
    print(f"Exports of a {total:,}-run benchmark job (500-iteration curves), "
          f"{platform.python_implementation()} {platform.python_version()}, "
          f"command: `scripts/bench/exports.py --runs {args.runs}`\n")
    print("| export | seconds | runs/s | MB |")
    print("| --- | --- | --- | --- |")
    print("\n".join(rows))


if __name__ == "__main__":
    main()
