"""Evidence for issue 10: would an optimizer reach a published cell if the function's optimum
sat at the origin?

Runs ALGORITHM on the standard function and on the same function moved so that its minimiser is
the origin (x -> f(x + x*)), at the papers' setting (30 agents, 500 iterations), and prints the
mean, median and minimum best value of both. For the noisy F7 it also prints the expected
minimum of the U[0, 1) noise alone over one run's evaluations, 1 / (n + 1): no algorithm can
average below it.

    PYTHONPATH=services .venv/bin/python scripts/evidence/optimum_at_origin.py IHPO F5,F6,F12,F13
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from swarmpath.functions import BenchmarkFunction, expand_function_names, get_function
from swarmpath.optimizers import minimize


def at_origin(f: BenchmarkFunction) -> BenchmarkFunction:
    c = f.optimum_coordinate
    return replace(f, name=f"{f.name}@0", kernel=lambda x: f.kernel(x + c), optimum_coordinate=0.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("algorithm")
    ap.add_argument("functions")
    ap.add_argument("--dim", type=int, default=30)
    ap.add_argument("--runs", type=int, default=10)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    kw = dict(dim=args.dim, agents=30, iterations=500, runs=args.runs, seed=args.seed)
    for name in expand_function_names(args.functions):
        f = get_function(name)
        std = minimize(args.algorithm, f, **kw)
        moved = minimize(args.algorithm, at_origin(f), **kw).best_fitness
        b = std.best_fitness
        line = (f"{args.algorithm} {name} (optimum {f.optimum_coordinate:g}): mean {b.mean():.4g} "
                f"median {np.median(b):.4g} min {b.min():.4g} | optimum at the origin: mean "
                f"{moved.mean():.4g} median {np.median(moved):.4g} min {moved.min():.4g}")
        if f.noisy:
            n = int(std.evaluations.mean())
            line += f" | noise floor 1/(n+1) with n = {n} evaluations: {1.0 / (n + 1):.3g}"
        print(line, flush=True)


if __name__ == "__main__":
    main()
