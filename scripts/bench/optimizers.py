#!/usr/bin/env python3
"""Optimizer speed: swarmpath against mealpy, and the ICOOT paper's Table 2 study.

    .venv/bin/python scripts/bench/optimizers.py [--part mealpy|table2|batch|all]

Part ``mealpy``: GWO, PSO, BA and FDO on F1 (30 dims, 30 agents, 500 iterations). mealpy 3.0.3
(the ``bench`` extra: ``pip install -e '.[bench]'``) solves one run at a time: a few runs are
timed (``--mealpy-runs``, 3 by default); swarmpath computes 30 runs as one batch and its time per
run is the batch's seconds / 30. Target: swarmpath >= 30x faster per run.

Part ``table2``: PSO, SSA, FDO, mCOOT, COOT, ICOOT x F1-F13 x 30 dims x 30 runs x 500
iterations in this one process, on ``--threads`` threads (2). Target: < 60 s in total.
``--layout stacked`` (default) computes each algorithm's noiseless functions as one stacked
batch and F7 alone (``minimize_many``: the same numbers as one ``minimize`` per cell),
``cells`` one ``minimize`` per cell, ``both`` runs the two side by side and prints their ratio.
``--chunk-elements`` (0: each stack in one chunk) is ``minimize_many``'s ``chunk_elements``: on
two threads, large chunks mean fewer numpy calls and fewer hand-offs of the GIL.

Part ``batch``: CPU milliseconds per run of the Table 2 algorithms (30 agents, 30 dims, 500
iterations) when ``--batches`` runs (30, 100, 300 by default) are computed in one ``minimize``
call, on ``--batch-functions`` (F1, F9, F12 by default: a cheap, a cosine and a sine kernel).
The paper-scale target of the service (78 cells x 1000 runs in < 15 min on two worker processes)
needs about 20 ms per run on average.

Algorithms not registered yet are skipped (and listed). The output is markdown (stdout) ready to
paste into docs/benchmarks.md, with the machine's load average next to the numbers; progress
notes go to stderr.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import platform
import sys
import time
import warnings
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np

from swarmpath.evidence.stats import describe
from swarmpath.functions import get_function
from swarmpath.optimizers import list_optimizers, minimize, minimize_many

# swarmpath name -> (mealpy module, class): the original variant of each algorithm.
MEALPY_CLASSES = {
    "GWO": ("GWO", "OriginalGWO"),
    "PSO": ("PSO", "OriginalPSO"),
    "BA": ("BA", "OriginalBA"),
    "FDO": ("FDO", "OriginalFDO"),
}
TABLE2_ALGORITHMS = ("PSO", "SSA", "FDO", "mCOOT", "COOT", "ICOOT")
TABLE2_FUNCTIONS = [f"F{i}" for i in range(1, 14)]
DIM, AGENTS, ITERATIONS = 30, 30, 500


def note(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def load() -> str:
    one, five, fifteen = os.getloadavg()
    return f"{one:.2f} / {five:.2f} / {fifteen:.2f}"


def available(wanted: tuple[str, ...] | list[str]) -> tuple[list[str], list[str]]:
    registered = set(list_optimizers())
    have = [a for a in wanted if a in registered]
    missing = [a for a in wanted if a not in registered]
    if missing:
        note(f"not registered yet, skipped: {', '.join(missing)}")
    return have, missing


# ----------------------------------------------------------------------------------- mealpy
def import_mealpy() -> Any:
    try:
        return importlib.import_module("mealpy")
    except ModuleNotFoundError:
        sys.exit(
            "mealpy is not installed: install the bench extra first\n"
            "    .venv/bin/python -m pip install -e '.[bench]'   (mealpy==3.0.3)"
        )


def mealpy_seconds(
    mealpy: Any, algorithm: str, runs: int, seed: int
) -> tuple[float, float, list[float]]:
    """Mean wall and CPU seconds of one mealpy run (over ``runs`` runs) and their best fitness."""
    module_name, class_name = MEALPY_CLASSES[algorithm]
    cls = getattr(getattr(mealpy, module_name), class_name)
    f = get_function("F1")
    kernel: Callable[[np.ndarray], Any] = f.kernel
    problem = {
        "bounds": mealpy.FloatVar(lb=(f.lower,) * DIM, ub=(f.upper,) * DIM, name="x"),
        "minmax": "min",
        "obj_func": lambda x: float(kernel(x)),
        "log_to": None,  # mealpy's logging off (errors only)
    }
    wall, cpu, best = [], [], []
    for r in range(runs):
        model = cls(epoch=ITERATIONS, pop_size=AGENTS)
        w0, c0 = time.perf_counter(), time.process_time()
        agent = model.solve(problem, seed=seed + r)
        wall.append(time.perf_counter() - w0)
        cpu.append(time.process_time() - c0)
        best.append(float(agent.target.fitness))
    return float(np.mean(wall)), float(np.mean(cpu)), best


def part_mealpy(mealpy_runs: int, runs: int, seed: int) -> list[str]:
    mealpy = import_mealpy()
    logging.getLogger("mealpy").setLevel(logging.ERROR)
    algorithms, missing = available(list(MEALPY_CLASSES))
    lines = [
        f"### swarmpath vs mealpy {getattr(mealpy, '__version__', '?')}: F1, {DIM} dims, "
        f"{AGENTS} agents, {ITERATIONS} iterations",
        "",
        f"Seconds per run, wall (CPU). mealpy: mean of {mealpy_runs} runs, one at a time; "
        f"swarmpath: {runs} runs in one batch, seconds / {runs}. Speed-up on CPU time (wall).",
        "",
        "| algorithm | mealpy s/run | swarmpath s/run | speed-up | mealpy avg best | "
        "swarmpath avg best | load 1/5/15 min |",
        "| --- | ---: | ---: | ---: | ---: | ---: | --- |",
    ]
    for a in algorithms:
        note(f"mealpy {a}: {mealpy_runs} runs ...")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            m_wall, m_cpu, m_best = mealpy_seconds(mealpy, a, mealpy_runs, seed)
        note(f"swarmpath {a}: {runs} runs ...")
        c0 = time.process_time()
        res = minimize(a, "F1", DIM, AGENTS, ITERATIONS, runs=runs, seed=seed)
        s_cpu = (time.process_time() - c0) / runs
        s_wall = res.seconds / runs
        lines.append(
            f"| {a} | {m_wall:.3f} ({m_cpu:.3f}) | {s_wall:.4f} ({s_cpu:.4f}) | "
            f"**{m_cpu / s_cpu:.0f}x** ({m_wall / s_wall:.0f}x) | {np.mean(m_best):.2E} | "
            f"{describe(res.best_fitness)['avg']:.2E} | {load()} |"
        )
    for a in missing:
        lines.append(f"| {a} | | | not registered yet | | | |")
    return lines


# ----------------------------------------------------------------------------------- table 2
def table2_stacks() -> list[list[str]]:
    """Each algorithm's functions as tasks: one stack of the noiseless functions, then each noisy
    one (F7) alone (``minimize_many`` never stacks it; as tasks of their own, these small ones
    fill the threads' tails)."""
    noisy = [f for f in TABLE2_FUNCTIONS if get_function(f).noisy]
    return [[f for f in TABLE2_FUNCTIONS if f not in noisy], *[[f] for f in noisy]]


def _timed_task(algorithm: str, functions: list[str], runs: int, seed: int,
                layout: str, chunk: int) -> tuple[str, list[str], float]:
    """Table 2 cells of one algorithm; returns their CPU seconds (this thread's time).

    ``cells``: one ``minimize`` call per function. ``stacked``: one ``minimize_many`` call for
    all of them (the same numbers, run for run; see docs/algorithms.md) with ``chunk_elements``
    = ``chunk``.
    """
    c0 = time.thread_time()
    if layout == "cells":
        for function in functions:
            minimize(algorithm, function, DIM, AGENTS, ITERATIONS, runs=runs, seed=seed)
    else:
        minimize_many(algorithm, functions, DIM, AGENTS, ITERATIONS, runs=runs, seed=seed,
                      chunk_elements=chunk)
    return algorithm, functions, time.thread_time() - c0


def part_table2(runs: int, seed: int, threads: int = 2, layout: str = "stacked",
                chunk: int = 0) -> list[str]:
    if layout == "both":
        cells = part_table2(runs, seed, threads, "cells", chunk)
        stacked = part_table2(runs, seed, threads, "stacked", chunk)
        ratio = _total_wall(cells) / _total_wall(stacked)
        return [*cells, "", *stacked, "", f"Cells / stacked wall time, same run: {ratio:.2f}x."]
    algorithms, missing = available(TABLE2_ALGORITHMS)
    cpu = dict.fromkeys(algorithms, 0.0)
    cpu_by_function = dict.fromkeys(TABLE2_FUNCTIONS, 0.0)
    load_before = load()
    w_start, c_start = time.perf_counter(), time.process_time()
    if layout == "cells":
        tasks = [(a, [fn]) for a in algorithms for fn in TABLE2_FUNCTIONS]
    else:
        stacks = table2_stacks()  # the big stacks of every algorithm first, then the small ones
        tasks = [(a, stack) for stack in stacks for a in algorithms]
    # Tasks are independent: numpy releases the GIL inside array operations, so a thread pool
    # keeps both cores busy within one process.
    note(f"table2 ({layout}): {len(tasks)} tasks x {runs} runs on {threads} thread(s) ...")
    with ThreadPoolExecutor(max_workers=threads) as pool:
        done = pool.map(lambda t: _timed_task(t[0], t[1], runs, seed, layout, chunk), tasks)
        for a, fns, seconds in done:
            cpu[a] += seconds
            for fn in fns:  # a stack's time is shared evenly among its functions
                cpu_by_function[fn] += seconds / len(fns)
    total_wall, total_cpu = time.perf_counter() - w_start, time.process_time() - c_start
    n = len(TABLE2_FUNCTIONS)
    lines = [
        f"### ICOOT paper Table 2 setting: F1-F13, {DIM} dims, {AGENTS} agents, {ITERATIONS} "
        f"iterations, {runs} runs, one process, {threads} thread(s), {layout}"
        + (f" (chunk_elements {chunk})" if layout == "stacked" else ""),
        "",
        f"| algorithm | CPU s ({n} functions x {runs} runs) | CPU s per function |",
        "| --- | ---: | ---: |",
    ]
    for a in algorithms:
        lines.append(f"| {a} | {cpu[a]:.1f} | {cpu[a] / n:.2f} |")
    for a in missing:
        lines.append(f"| {a} | not registered yet | |")
    lines += [
        f"| **total** ({len(algorithms)} of {len(TABLE2_ALGORITHMS)} algorithms) | "
        f"**{total_cpu:.1f}** | |",
        "",
        f"**Wall time: {total_wall:.1f} s** (target < 60 s). Load average (1/5/15 min) before: "
        f"{load_before}; after: {load()}.",
    ]
    if layout == "cells":
        lines += [
            "",
            "CPU seconds per function, summed over the algorithms above:",
            "",
            "| " + " | ".join(TABLE2_FUNCTIONS) + " |",
            "|" + " ---: |" * n,
            "| " + " | ".join(f"{cpu_by_function[f]:.1f}" for f in TABLE2_FUNCTIONS) + " |",
        ]
    return lines


def _total_wall(lines: list[str]) -> float:
    line = next(x for x in lines if x.startswith("**Wall time: "))
    return float(line.split()[2])


# ------------------------------------------------------------------------------------ batch
def part_batch(batches: list[int], functions: list[str], seed: int) -> list[str]:
    algorithms, _ = available(TABLE2_ALGORITHMS)
    load_before = load()
    lines = [
        f"### CPU ms per run by batch size: {DIM} dims, {AGENTS} agents, {ITERATIONS} iterations, "
        f"mean over {', '.join(functions)}",
        "",
        "| algorithm | " + " | ".join(f"{b} runs" for b in batches) + " |",
        "| --- |" + " ---: |" * len(batches),
    ]
    totals = dict.fromkeys(batches, 0.0)
    for a in algorithms:
        cells = []
        for b in batches:
            note(f"batch {a}: {b} runs x {len(functions)} functions ...")
            c0 = time.process_time()
            for fn in functions:
                minimize(a, fn, DIM, AGENTS, ITERATIONS, runs=b, seed=seed)
            ms = (time.process_time() - c0) * 1000.0 / (b * len(functions))
            totals[b] += ms
            cells.append(f"{ms:.1f}")
        lines.append(f"| {a} | " + " | ".join(cells) + " |")
    n = len(algorithms)
    lines += [
        "| **mean** | " + " | ".join(f"**{totals[b] / n:.1f}**" for b in batches) + " |",
        "",
        f"Load average (1/5/15 min) before: {load_before}; after: {load()}.",
    ]
    return lines


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--part", choices=("mealpy", "table2", "batch", "all"), default="all")
    parser.add_argument("--mealpy-runs", type=int, default=3, help="mealpy runs timed each")
    parser.add_argument("--runs", type=int, default=30, help="swarmpath runs per cell (batched)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--threads", type=int, default=2, help="table2: tasks run concurrently")
    parser.add_argument("--layout", choices=("stacked", "cells", "both"), default="stacked",
                        help="table2: one minimize_many per algorithm for its noiseless functions "
                        "(stacked), one minimize per cell (cells), or both side by side")
    parser.add_argument("--chunk-elements", type=int, default=0,
                        help="table2, stacked: minimize_many's chunk_elements (0: one chunk)")
    parser.add_argument("--batches", default="30,100,300", help="batch: runs per minimize call")
    parser.add_argument("--batch-functions", default="F1,F9,F12", help="batch: functions")
    args = parser.parse_args(argv)
    if args.mealpy_runs < 1 or args.runs < 1:
        parser.error("--mealpy-runs and --runs must be >= 1")

    lines = [
        f"Machine: {platform.machine()}, {os.cpu_count()} CPUs, Python "
        f"{platform.python_version()}, numpy {np.__version__}; registered: "
        f"{', '.join(list_optimizers())}.",
        "",
    ]
    if args.part in ("mealpy", "all"):
        lines += [*part_mealpy(args.mealpy_runs, args.runs, args.seed), ""]
    if args.part in ("table2", "all"):
        lines += [
            *part_table2(args.runs, args.seed, args.threads, args.layout,
                         args.chunk_elements),
            "",
        ]
    if args.part in ("batch", "all"):
        batches = [int(b) for b in args.batches.split(",")]
        functions = [f.strip() for f in args.batch_functions.split(",") if f.strip()]
        lines += [*part_batch(batches, functions, args.seed), ""]
    print("\n".join(lines).rstrip())


if __name__ == "__main__":
    main()
