#!/usr/bin/env python3
"""What one call of a compiled suite objective costs beyond its points, side by side.

    PYTHONPATH=services .venv/bin/python scripts/bench/objective_call_cost.py \\
        [--functions F1,bbob:f1,cec2017:F1,...] [--dim 10] [--calls 20000] [--repeats 3]

Each function's compiled objective is called the way the kernels call it
(``objectives.evaluate``, the whole population in one call) from one compiled loop, with
populations of m = 1 point (HPO and IHPO evaluate one agent at a time) and m = 30 (a population
of the default size); the functions and both sizes alternate within each repeat. Per call
t(m) = a + b m: the CPU ns per point b = (t(30) - t(1)) / 29 and the fixed cost of a call a =
t(1) - b (the pointer call, the data's unpacking and the temporaries the objective allocates:
the CEC objectives allocate theirs per call). Prints a markdown table of the medians: a, b,
a's share of a call at m = 1 and m = 30, and the arrays numba allocates per call (its NRT
counter, ``NUMBA_NRT_STATS``; the same at both sizes).

Last, what one ``np.empty`` costs in a compiled loop (a loop allocating n doubles per pass
against the same loop writing a kept array; 2 million passes each).

``--runs HPO,GWO``: also the CPU ms of one whole run of each (numba, D as above, 1000 x D
evaluations, 30 agents, best of 3 batches of 3 runs) on each function.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

os.environ.setdefault("NUMBA_NRT_STATS", "1")  # numba's allocation counter, read at import

import numpy as np
from numba import njit
from numba.core.runtime import rtsys

from swarmpath.functions import get_function
from swarmpath.optimizers.compiled.objectives import (
    data_for,
    evaluate,
    objective_for,
    work_for,
)
from swarmpath.optimizers.compiled.streams import open_stream
from swarmpath.optimizers.streams import run_generator

DEFAULT = ("F1,F9,bbob:f1,bbob:f15,cec2017:F1,cec2017:F5,cec2017:F11,cec2017:F22,"
           "cec2022:F1,cec2022:F9")


@njit(cache=False)
def _calls(stream, objective, shift, lower, upper, X, F, mask, work, calls):
    for _ in range(calls):
        evaluate(stream, objective, False, shift, lower, upper, X, F, mask, work)


def cpu_per_call(fn, dim: int, m: int, calls: int) -> tuple[float, float]:
    """CPU ns per call of ``fn``'s objective on m points, and numba's allocations per call."""
    lower, upper = (np.ascontiguousarray(np.broadcast_to(b, (dim,)), dtype=float)
                    for b in fn.bounds(dim))
    X = np.random.default_rng(1).uniform(lower, upper, (m, dim))
    objective = objective_for(fn, data_for(fn, dim))
    stream = open_stream(run_generator(1, 0), m, False)
    args = (stream, objective, np.zeros(dim), lower, upper, X, np.empty(m),
            np.ones(m, dtype=np.bool_), work_for(m, dim))
    _calls(*args, 1)  # compiled and warm
    allocated = rtsys.get_allocation_stats().alloc
    started = time.thread_time_ns()
    _calls(*args, calls)
    seconds = (time.thread_time_ns() - started) / calls
    return seconds, (rtsys.get_allocation_stats().alloc - allocated) / calls


@njit(cache=False)
def _allocating(n, passes):
    total = 0.0
    for _ in range(passes):
        a = np.empty(n)
        a[0] = 1.0
        total += a[0]
    return total


@njit(cache=False)
def _writing(a, passes):
    total = 0.0
    for _ in range(passes):
        a[0] = 1.0
        total += a[0]
    return total


def alloc_ns(n: int, passes: int = 2_000_000) -> float:
    """CPU ns of one ``np.empty(n)`` in a compiled loop."""
    _allocating(n, 1)
    _writing(np.empty(n), 1)
    started = time.thread_time_ns()
    _allocating(n, passes)
    allocating = time.thread_time_ns() - started
    started = time.thread_time_ns()
    _writing(np.empty(n), passes)
    return (allocating - (time.thread_time_ns() - started)) / passes


def run_ms(algorithm: str, function: str, dim: int) -> float:
    """CPU ms of one numba run of ``algorithm`` on ``function`` at 1000 x D evaluations."""
    from swarmpath.optimizers import minimize_many
    from swarmpath.optimizers.budget import study_iterations

    kw = dict(dim=dim, agents=30, iterations=study_iterations(algorithm, "1000xD", 1, 30, dim),
              backend="numba", max_evaluations=1000 * dim)
    minimize_many(algorithm, [function], runs=1, **kw)  # compiled and warm
    best = []
    for _ in range(3):
        started = time.thread_time()
        minimize_many(algorithm, [function], runs=3, **kw)
        best.append((time.thread_time() - started) / 3 * 1000)
    return min(best)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--functions", default=DEFAULT)
    parser.add_argument("--dim", type=int, default=10)
    parser.add_argument("--calls", type=int, default=20000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--runs", default="", help="algorithms whose whole runs are timed too")
    args = parser.parse_args()
    fns = [get_function(name) for name in args.functions.split(",")]
    sizes = (1, 30)
    times: dict[tuple[str, int], list[float]] = {(fn.name, m): [] for fn in fns for m in sizes}
    allocations: dict[str, float] = {}
    print(f"D = {args.dim}; {args.calls} calls per timing, median of {args.repeats}, functions "
          "and sizes alternating; load before: " + " ".join(f"{x:.1f}" for x in os.getloadavg()))
    print()
    for _ in range(args.repeats):
        for fn in fns:
            for m in sizes:
                calls = args.calls if m == 1 else max(1, args.calls // 10)
                ns, allocations[fn.name] = cpu_per_call(fn, args.dim, m, calls)
                times[(fn.name, m)].append(ns)
    print("| function | ns per call, m = 1 | m = 30 | b: ns per point | a: ns per call | "
          "a / call, m = 1 | a / call, m = 30 | allocations per call |")
    print("|---|---|---|---|---|---|---|---|")
    for fn in fns:
        t1, t30 = (statistics.median(times[(fn.name, m)]) for m in sizes)
        b = (t30 - t1) / 29
        a = t1 - b
        print(f"| {fn.name} | {t1:.0f} | {t30:.0f} | {b:.0f} | {a:.0f} | {a / t1:.0%} | "
              f"{a / t30:.0%} | {allocations[fn.name]:.0f} |")
    print()
    print("np.empty in a compiled loop: " + ", ".join(
        f"{n} doubles {alloc_ns(n):.0f} ns" for n in (1, 10, 300)))
    if args.runs:
        print()
        print("| CPU ms per run | " + " | ".join(fn.name for fn in fns) + " |")
        print("|---|" + "---|" * len(fns))
        for algorithm in args.runs.split(","):
            row = [run_ms(algorithm, fn.name, args.dim) for fn in fns]
            print(f"| {algorithm} | " + " | ".join(f"{ms:.1f}" for ms in row) + " |")
    print()
    print("load after: " + " ".join(f"{x:.1f}" for x in os.getloadavg()))


if __name__ == "__main__":
    main()
