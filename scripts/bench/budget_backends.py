#!/usr/bin/env python3
"""A study budget on the numba backend against numpy: CPU per bbob cell, side by side.

    PYTHONPATH=services .venv/bin/python scripts/bench/budget_backends.py \\
        [--functions bbob:f3,bbob:f8] [--dim 20] [--budget 1000xD] [--agents 30] [--repeats 3]

For each registered optimizer with a kernel: the cell (function, dim) at the budget, as
``swarmpath bench --budget-evals`` runs it (``minimize_many`` with the iterations that spend the
budget and ``max_evaluations``), one run (run 0, seed 1), on ``backend="numpy"`` and on
``"numba"`` in alternation, ``--repeats`` times; the thread's CPU seconds of each call (the
kernels are compiled before the first timing). The two backends' bests, curves, positions and
evaluations must be equal to the last bit (the script stops otherwise). Prints a markdown table
of the medians and their ratio, and the machine's load.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

from swarmpath.optimizers import minimize_many
from swarmpath.optimizers.budget import budget_at, parse_budget, study_iterations
from swarmpath.optimizers.compiled import kernel_names

FIELDS = ("best_fitness", "best_position", "curve", "evaluations")


def cell(algorithm: str, functions: list[str], dim: int, agents: int, budget: str,
         backend: str) -> tuple[float, list]:
    """CPU seconds of the cell's call on ``backend`` and its results."""
    iterations = study_iterations(algorithm, budget, 1, agents, dim)
    started = time.thread_time()
    results = minimize_many(algorithm, functions, dim=dim, agents=agents, iterations=iterations,
                            runs=1, seed=1, backend=backend,
                            max_evaluations=budget_at(budget, dim))
    return time.thread_time() - started, results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--functions", default="bbob:f3,bbob:f8")
    parser.add_argument("--dim", type=int, default=20)
    parser.add_argument("--budget", default="1000xD")
    parser.add_argument("--agents", type=int, default=30)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    budget = parse_budget(args.budget)
    functions = args.functions.split(",")
    print(f"{', '.join(functions)}, D = {args.dim}, budget {budget} evaluations, "
          f"{args.agents} agents, 1 run; CPU s per cell (median of {args.repeats}, backends "
          "alternating); load before: " + " ".join(f"{x:.1f}" for x in os.getloadavg()))
    print()
    print("| optimizer | numpy CPU s | numba CPU s | numpy / numba |")
    print("|---|---|---|---|")
    total = {"numpy": 0.0, "numba": 0.0}
    for algorithm in kernel_names():
        _, warm = cell(algorithm, functions, args.dim, args.agents, budget, "numba")
        if warm[0].backend != "numba":
            raise SystemExit(f"{algorithm}: the budget did not run on numba")
        times: dict[str, list[float]] = {"numpy": [], "numba": []}
        for _ in range(args.repeats):
            results = {}
            for backend in ("numpy", "numba"):
                seconds, results[backend] = cell(algorithm, functions, args.dim, args.agents,
                                                 budget, backend)
                times[backend].append(seconds)
            for a, b in zip(results["numpy"], results["numba"], strict=True):
                for field in FIELDS:
                    if not np.array_equal(getattr(a, field), getattr(b, field)):
                        raise SystemExit(f"{algorithm} {a.function}: {field} differs")
        med = {k: statistics.median(v) for k, v in times.items()}
        for k in total:
            total[k] += med[k]
        print(f"| {algorithm} | {med['numpy']:.3f} | {med['numba']:.3f} | "
              f"{med['numpy'] / med['numba']:.1f} |", flush=True)
    print(f"| all {len(kernel_names())} | {total['numpy']:.2f} | {total['numba']:.2f} | "
          f"{total['numpy'] / total['numba']:.1f} |")
    print()
    print("load after: " + " ".join(f"{x:.1f}" for x in os.getloadavg()))


if __name__ == "__main__":
    main()
