"""How far 10 runs of IPOP-CMA-ES can move a bbob cell: pycma against pycma, and against swarmpath.

The ``cmaes-pycma-bbob-d5`` table holds 10 pycma runs per function. On cells whose errors are
either solved (below COCO's 1e-8) or stuck near 1-10 in a few runs, the mean of 10 runs is set
by how many stuck runs those 10 happen to hold. This script runs both sides at many more runs,
at the table's setting (bbob, instance 1, D = 5, 500 x D evaluations over all restarts):

- pycma through ``pycma_reference.run`` (the very function that wrote the table; run r is seed r,
  so the table's runs are the first 10 here) -- no swarmpath code;
- swarmpath's CMA-ES as ``swarmpath reproduce cmaes-pycma-bbob-d5`` runs it (20 evaluations per
  iteration, 124 iterations, ``max_evaluations`` 2500, seed 1; its runs 0-9 are the table's
  measured runs),

and prints per function, with errors floored at 1e-8 as the table compares them: the mean,
median, 90 % quantile, the runs above 1e-8, 1e-2 and 1, the rank-sum test of the two samples,
the log10 ratio of the two means, and the means of consecutive blocks of 10 runs of each side
(pycma's own blocks show how far a 10-run mean moves with the seeds alone):

    .venv/bin/python scripts/evidence/pycma_spread.py --functions 7,10,11,12,13 --runs 100
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

FLOOR = 1e-8  # COCO's final target, the table's error_floor
DIM, BUDGET = 5, 2500


def pycma_errors(number: int, runs: int) -> np.ndarray:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from pycma_reference import run

    return np.array([run(number, DIM, 1, BUDGET, r) for r in range(1, runs + 1)])


def swarmpath_errors(number: int, runs: int) -> np.ndarray:
    from swarmpath.optimizers.api import minimize

    result = minimize("CMA-ES", f"bbob:f{number}", dim=DIM, agents=20, iterations=BUDGET // 20 - 1,
                      runs=runs, seed=1, backend="numpy", max_evaluations=BUDGET)
    return np.asarray(result.best_fitness, dtype=float)


def describe(label: str, x: np.ndarray) -> str:
    return (f"  {label}: mean {x.mean():.3g}, median {np.median(x):.3g}, q90 "
            f"{np.quantile(x, 0.9):.3g}, max {x.max():.3g}; runs above 1e-8 {np.sum(x > FLOOR)}, "
            f"above 1e-2 {np.sum(x > 1e-2)}, above 1 {np.sum(x > 1)}")


def blocks(x: np.ndarray) -> list[float]:
    return [float(b.mean()) for b in x[: len(x) // 10 * 10].reshape(-1, 10)]


def main(argv: list[str] | None = None) -> int:
    from scipy.stats import mannwhitneyu

    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--functions", default="7,10,11,12,13", help="bbob function numbers")
    p.add_argument("--runs", type=int, default=100, help="runs per side (a multiple of 10)")
    args = p.parse_args(argv)
    for number in (int(f) for f in args.functions.split(",")):
        ref = np.maximum(pycma_errors(number, args.runs), FLOOR)
        ours = np.maximum(swarmpath_errors(number, args.runs), FLOOR)
        ref_blocks, our_blocks = blocks(ref), blocks(ours)
        print(f"bbob:f{number}, {args.runs} runs per side (errors floored at 1e-8):")
        print(describe("pycma    ", ref))
        print(describe("swarmpath", ours))
        print(f"  rank-sum p {mannwhitneyu(ref, ours).pvalue:.2g}; log10(mean swarmpath / mean "
              f"pycma) {np.log10(ours.mean() / ref.mean()):+.2f}; the table's 10 runs: "
              f"{np.log10(our_blocks[0] / ref_blocks[0]):+.2f}")
        print("  10-run means, pycma:     " + " ".join(f"{b:.1e}" for b in ref_blocks))
        print("  10-run means, swarmpath: " + " ".join(f"{b:.1e}" for b in our_blocks))
        print(f"  pycma's own 10-run means span {np.log10(max(ref_blocks) / min(ref_blocks)):.1f} "
              f"decades", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
