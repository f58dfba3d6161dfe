#!/usr/bin/env python3
"""Cost of the statistical tests of a job summary (docs/statistics.md).

    .venv/bin/python scripts/bench/stats_cost.py [--runs 30,1000] [--repeat 5]

Times :func:`swarmpath.service.summary_stats.benchmark_statistics` (every algorithm against the
last one by the Wilcoxon rank-sum test, Holm over the table, Friedman per dimension): what
``GET /jobs/{id}/summary`` adds to a benchmark summary. Two job shapes: the ICOOT paper's Table 2
(6 algorithms x F1-F13 x 30 dims = 78 cells) and a larger one (9 algorithms x 13 functions x
3 dims = 351 cells), each at every ``--runs`` per cell. The run values are lognormal draws from a
fixed seed (the tests' cost depends on the sizes only). Prints a markdown table with the best of
``--repeat`` wall times and the machine's load average.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

from swarmpath.service.summary_stats import benchmark_statistics

SHAPES = {"Table 2 (6 x 13 x 1)": (6, 13, (30,)), "9 x 13 x 3": (9, 13, (30, 100, 500))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", default="30,1000", help="runs per cell, comma-separated")
    parser.add_argument("--repeat", type=int, default=5, help="timings per case (best kept)")
    args = parser.parse_args()
    rng = np.random.default_rng(1)
    print(f"Python {platform.python_version()}, load average {os.getloadavg()[0]:.1f} at the "
          "start.\n")
    print("| job shape | cells | runs per cell | tests | seconds (best of "
          f"{args.repeat}) |\n| --- | ---: | ---: | ---: | ---: |")
    for label, (n_algos, n_functions, dims) in SHAPES.items():
        algorithms = [f"A{i}" for i in range(n_algos)]
        rows = [{"algorithm": a, "function": f"F{f + 1}", "dim": d}
                for a in algorithms for f in range(n_functions) for d in dims]
        for runs in (int(r) for r in args.runs.split(",")):
            values = [rng.lognormal(size=runs).tolist() for _ in rows]
            best = float("inf")
            for _ in range(args.repeat):
                started = time.perf_counter()
                benchmark_statistics([dict(r) for r in rows], values, algorithms)
                best = min(best, time.perf_counter() - started)
            tests = (n_algos - 1) * n_functions * len(dims)
            print(f"| {label} | {len(rows)} | {runs} | {tests} | {best:.3f} |")
    print(f"\nLoad average {os.getloadavg()[0]:.1f} at the end.")


if __name__ == "__main__":
    main()
