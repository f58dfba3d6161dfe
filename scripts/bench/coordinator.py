#!/usr/bin/env python3
"""The coordinator's CPU per run on a job of tiny runs with Table-2-sized results.

    .venv/bin/python scripts/bench/coordinator.py [--runs 20000] [--workers 2] [--iterations 500]
                                                  [--profile OUT.txt] [--rate 100]

Starts ``swarmpath up --workers N`` (one slot each; free loopback ports, a fresh data directory),
submits one job of GWO on F1-F4, 2 dims, 2 agents, ``--iterations`` iterations (each result carries
a curve of that many points) and ``--runs`` runs, waits for its end and prints one Markdown row:
runs, seconds (the coordinator's ``finished - started``), runs/s, CPU seconds of the coordinator
process (``swarmpath up`` itself: REST, Zenoh router, result intake, store) during the job and
per run, the same for its MCAP recorder process (which follows the store on its own core), CPU
of the workers and slots, and the 1-minute load average before and after.

``--profile OUT``: samples the coordinator process with py-spy (``pip install py-spy``; not a
dependency of the project) during the job and writes its ``--format raw`` stacks to OUT; the
script then prints the top functions by own and by cumulative samples.
"""

from __future__ import annotations

import argparse
import collections
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from service import Up, elapsed


def spec(runs: int, iterations: int) -> dict[str, object]:
    """``runs`` runs over F1-F4 (a cell holds at most 10,000 runs)."""
    return {"kind": "benchmark", "algorithms": ["GWO"], "functions": ["F1", "F2", "F3", "F4"],
            "dims": [2], "agents": 2, "iterations": iterations, "runs": max(1, runs // 4),
            "seed": 1}


def summarize(raw: Path, top: int = 25) -> str:
    """Top functions of py-spy's raw (collapsed) stacks, by own and by cumulative samples."""
    own: collections.Counter[str] = collections.Counter()
    cum: collections.Counter[str] = collections.Counter()
    total = 0
    for line in raw.read_text().splitlines():
        stack, _, count = line.rpartition(" ")
        if not count.isdigit():
            continue
        n = int(count)
        total += n
        frames = [f.split(" (")[0] + " (" + f.split(" (")[1].split(":")[0].rsplit("/", 1)[-1]
                  + ")" if " (" in f else f for f in stack.split(";")]
        if frames:
            own[frames[-1]] += n
        for f in set(frames):
            cum[f] += n
    lines = [f"{total} samples", "", "own %  | function"]
    lines += [f"{100 * n / total:5.1f}  | {f}" for f, n in own.most_common(top)]
    lines += ["", "cum %  | function"]
    lines += [f"{100 * n / total:5.1f}  | {f}" for f, n in cum.most_common(top)]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=20_000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--iterations", type=int, default=500)
    ap.add_argument("--profile", type=Path, default=None, help="py-spy raw output file")
    ap.add_argument("--rate", type=int, default=100, help="py-spy samples per second")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="swarmpath-bench-") as d, \
            Up(args.workers, Path(d)) as up:
        spy = None
        if args.profile is not None:
            spy = subprocess.Popen(
                [str(Path(sys.executable).with_name("py-spy")), "record",
                 "--pid", str(up.proc.pid), "--rate", str(args.rate),
                 "--format", "raw", "--threads", "--nonblocking", "-o", str(args.profile)],
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            time.sleep(1.0)
        st = up.run_job(spec(args.runs, args.iterations), timeout=3600)
        if spy is not None:
            spy.send_signal(signal.SIGINT)
            spy.wait(60)
    secs, total = elapsed(st), st["runs_total"]
    cpu = st["cpu"]
    print("| runs | s | runs/s | coordinator CPU s | per run | recorder CPU s | per run "
          "| workers / slots CPU s | load before -> after |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    print(f"| {total} | {secs:.2f} | {total / secs:,.0f} | {cpu['coordinator']:.2f} "
          f"| {1000 * cpu['coordinator'] / total:.3f} ms | {cpu['recorder']:.2f} "
          f"| {1000 * cpu['recorder'] / total:.3f} ms | {cpu['workers']:.1f} / "
          f"{cpu['slots']:.1f} | {st['load'][0]:.2f} -> {st['load'][1]:.2f} |")
    if args.profile is not None and args.profile.exists():
        print()
        print(summarize(args.profile))
    return 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    sys.exit(main())
