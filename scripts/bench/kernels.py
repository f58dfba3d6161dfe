#!/usr/bin/env python3
"""CPU per run of the numba backend against an independent fused loop (and the numpy reference).

    PYTHONPATH=services .venv/bin/python scripts/bench/kernels.py [--algorithms PSO,GWO]
        [--functions F1,F9] [--runs 30] [--rounds 5] [--numpy]

The setting is the ICOOT paper's Table 2 (30 dims, 30 agents, 500 iterations, seed 1). For each
algorithm and function:

* ``numba``: the backend's kernel called for each run as ``minimize(..., backend="numba")``
  calls it (``run_generator(1, r)``, the compiled objective, the packed parameters);
* ``fused``: the algorithm's loop of ``fused_*.py``, written apart from the kernels (one
  ``@njit`` call per run, the run's PCG64 generator drawn directly in swarmpath's order, the
  objective's code inlined), called once per run with ``run_generator(1, r)``. Before timing,
  every run's best value is checked to be the backend's, bit for bit: a different number would
  mean other work (the script stops);
* ``numpy`` (with ``--numpy``): the reference, ``minimize`` of the same runs in one batch.

A round times the runs one by one, the kernel's and the fused loop's alternately (which goes
first alternating too), so that both see the same load; the table gives each column's median
over the rounds and the median (min-max) of the rounds' numba / fused ratios. CPU time is this
process's (``time.process_time``); compilation happens (and the kernels are cached) before
timing. The load average at the start and the end and the
tree (``git describe``) close the output: the machine is shared, read the ratios.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from collections.abc import Callable

import numpy as np
from fused_common import OBJECTIVES
from fused_loops import LOOPS

from swarmpath.functions import expand_function_names, get_function
from swarmpath.optimizers import list_optimizers, minimize
from swarmpath.optimizers.compiled import find_kernel
from swarmpath.optimizers.compiled.objectives import objective_for
from swarmpath.optimizers.compiled.run import kernel_for
from swarmpath.optimizers.streams import run_generator

DIM, AGENTS, ITERATIONS, SEED = 30, 30, 500, 1


def cpu(fn: Callable[[], object]) -> float:
    started = time.process_time()
    fn()
    return time.process_time() - started


def bench_cell(algo: str, name: str, runs: int, rounds: int, with_numpy: bool) -> dict:
    fn = get_function(name)
    lower, upper, shift = np.full(DIM, fn.lower), np.full(DIM, fn.upper), np.zeros(DIM)
    loop = LOOPS[algo](OBJECTIVES[name])
    kernel, _, params = kernel_for(algo, None, "none")
    objective = objective_for(fn)
    kw = dict(dim=DIM, agents=AGENTS, iterations=ITERATIONS, runs=runs, seed=SEED)

    def fused(r: int) -> float:
        return loop(run_generator(SEED, r), lower, upper, AGENTS, ITERATIONS)[0]

    def numba(r: int) -> float:  # what minimize_compiled does for run r
        return kernel.run(run_generator(SEED, r), objective, False, shift, lower, upper, AGENTS,
                          ITERATIONS, params)[0]

    print(f"compiling and checking {algo} {name} ...", file=sys.stderr)
    ours = minimize(algo, name, backend="numba", **kw).best_fitness
    theirs = np.array([fused(r) for r in range(runs)])
    if not np.array_equal(ours, theirs):
        diff = np.flatnonzero(ours != theirs)
        sys.exit(f"{algo} {name}: the fused loop's bests differ from the backend's in runs "
                 f"{diff.tolist()} (e.g. {theirs[diff[0]]!r} vs {ours[diff[0]]!r})")
    columns: dict[str, list[float]] = {"numba": [], "fused": [], "numpy": []}
    for k in range(rounds):
        spent = {"numba": 0.0, "fused": 0.0}
        for r in range(runs):  # run by run, the order alternating
            for column in ("numba", "fused") if (k + r) % 2 == 0 else ("fused", "numba"):
                fn_ = numba if column == "numba" else fused
                spent[column] += cpu(lambda fn_=fn_, r=r: fn_(r))
        for column, seconds in spent.items():
            columns[column].append(seconds / runs * 1e3)
        if with_numpy:
            columns["numpy"].append(cpu(lambda: minimize(algo, name, **kw)) / runs * 1e3)
    ratios = [a / b for a, b in zip(columns["numba"], columns["fused"], strict=True)]
    return {
        "median": {c: statistics.median(v) for c, v in columns.items() if v},
        "ratio": statistics.median(ratios), "low": min(ratios), "high": max(ratios),
    }


def tree() -> str:
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    try:
        return subprocess.run(["git", "-C", root, "describe", "--always", "--dirty"],
                              capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--algorithms", default=",".join(a for a in list_optimizers() if a in LOOPS))
    ap.add_argument("--functions", default="F1,F9")
    ap.add_argument("--runs", type=int, default=30)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--numpy", action="store_true", help="also time the numpy reference")
    args = ap.parse_args()
    algos = [a.strip() for a in args.algorithms.split(",") if a.strip()]
    missing = [a for a in algos if find_kernel(a) is None or a not in LOOPS]
    if missing:
        ap.error(f"--algorithms: no kernel or no fused loop for {', '.join(missing)}")
    functions = expand_function_names(args.functions)
    unknown = [f for f in functions if f not in OBJECTIVES]
    if unknown:
        ap.error(f"--functions: the fused loops have {', '.join(OBJECTIVES)}, not "
                 f"{', '.join(unknown)}")
    if args.runs < 1 or args.rounds < 1:
        ap.error("--runs and --rounds must be >= 1")
    before = os.getloadavg()
    head = "| algorithm | function | numba ms/run | fused ms/run | numba / fused (min-max) |"
    rule = "| --- | --- | ---: | ---: | ---: |"
    if args.numpy:
        head += " numpy ms/run | numpy / numba |"
        rule += " ---: | ---: |"
    lines = [head, rule]
    for algo in algos:
        for name in functions:
            cell = bench_cell(algo, name, args.runs, args.rounds, args.numpy)
            m = cell["median"]
            line = (f"| {algo} | {name} | {m['numba']:.2f} | {m['fused']:.2f} | "
                    f"**{cell['ratio']:.2f}x** ({cell['low']:.2f}-{cell['high']:.2f}) |")
            if args.numpy:
                line += f" {m['numpy']:.2f} | {m['numpy'] / m['numba']:.2f}x |"
            lines.append(line)
            print(line, file=sys.stderr)
    after = os.getloadavg()
    lines += ["", f"{DIM} dims, {AGENTS} agents, {ITERATIONS} iterations, {args.runs} runs, "
              f"median of {args.rounds} alternating rounds; the fused loops' bests equal the "
              f"backend's in every run. Load average {before[0]:.2f} at the start, "
              f"{after[0]:.2f} at the end ({os.cpu_count()} CPUs); tree {tree()}."]
    print("\n".join(lines))


if __name__ == "__main__":
    main()
