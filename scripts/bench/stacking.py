#!/usr/bin/env python3
"""CPU per run of a worker slot's own code, stacked against unstacked, in one process.

    .venv/bin/python scripts/bench/stacking.py [--algorithms PSO,FDO,ICOOT] [--runs 30] [--reps 2]

For each algorithm, the ICOOT paper's Table 2 setting (F1-F13, 30 dims, 30 agents, 500
iterations, seed 1) as one bundle of leases, one lease of ``--runs`` runs per function, computed
the way a slot computes a bundle (``swarmpath.service.worker.stacking.stacked_outcomes``, results
encoded and signed) in three layouts: ``unstacked`` (every lease alone, ``--no-stacking``),
``stacked`` (the worker's default: stacks of at most one of ``minimize``'s chunks, one after the
other) and ``one stack`` (every lease in one ``minimize_many`` batch, its chunks stepped in
turn). Layouts alternate in order from one repetition to the next; the CPU time of this process
is read around each. Markdown goes to stdout. The machine may be shared: read the numbers next
to the load printed with them.
"""

from __future__ import annotations

import argparse
import os
import time

from swarmpath.service.capability import new_capability
from swarmpath.service.protocol import BenchmarkCell, Lease
from swarmpath.service.worker.stacking import stacked_outcomes

#: The functions of the ICOOT paper's Table 2.
TABLE2_FUNCTIONS = [f"F{i}" for i in range(1, 14)]


def bundle(algorithm: str, runs: int) -> list[Lease]:
    out = []
    for i, function in enumerate(TABLE2_FUNCTIONS):
        spec = BenchmarkCell(algorithm=algorithm, function=function, dim=30, agents=30,
                             iterations=500)
        out.append(Lease(lease_id=f"bench{i}", worker="bench", job_id="bench", cell=spec.key,
                         cell_index=i, runs_per_cell=runs, seed=1, runs=list(range(runs)),
                         spec=spec, deadline=0.0, lease_seconds=60.0, heartbeat_seconds=20.0,
                         capability=new_capability()))
    return out


def cpu_ms_per_run(leases: list[Lease], layout: str) -> float:
    import swarmpath.service.worker.stacking as stacking

    limit = stacking.STACK_ELEMENTS
    if layout == "one stack":
        stacking.STACK_ELEMENTS = sum(len(x.runs) * 900 for x in leases)
    try:
        started = time.process_time()
        outcomes = list(stacked_outcomes(leases, [lambda: False] * len(leases),
                                         stacking=layout != "unstacked"))
        seconds = time.process_time() - started
    finally:
        stacking.STACK_ELEMENTS = limit
    assert all(isinstance(o, list) for _i, o in outcomes)
    return 1000 * seconds / sum(len(x.runs) for x in leases)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--algorithms", default="PSO,FDO,ICOOT")
    ap.add_argument("--runs", type=int, default=30, help="runs per cell (one lease per cell)")
    ap.add_argument("--reps", type=int, default=2)
    opts = ap.parse_args()
    layouts = ["unstacked", "stacked", "one stack"]
    algorithms = opts.algorithms.split(",")
    load0 = os.getloadavg()[0]
    table: dict[str, dict[str, list[float]]] = {a: {x: [] for x in layouts} for a in algorithms}
    for rep in range(opts.reps):
        for algorithm in algorithms:
            leases = bundle(algorithm, opts.runs)
            for layout in layouts if rep % 2 == 0 else layouts[::-1]:
                table[algorithm][layout].append(cpu_ms_per_run(leases, layout))
    print(f"CPU ms per run, F1-F13 x {opts.runs} runs, 30 dims, 30 agents, 500 iterations, mean "
          f"of {opts.reps} repetitions; load average (1 min) {load0:.1f} -> "
          f"{os.getloadavg()[0]:.1f}\n")
    print("| algorithm | " + " | ".join(layouts) + " |")
    print("| --- |" + " ---: |" * len(layouts))
    means = {x: 0.0 for x in layouts}
    for algorithm in algorithms:
        cells = []
        for layout in layouts:
            value = sum(table[algorithm][layout]) / opts.reps
            means[layout] += value / len(algorithms)
            cells.append(f"{value:.1f}")
        print(f"| {algorithm} | " + " | ".join(cells) + " |")
    print("| **mean** | " + " | ".join(f"**{means[x]:.1f}**" for x in layouts) + " |")


if __name__ == "__main__":
    main()
