#!/usr/bin/env python3
"""CPU per run: the numpy reference, the numba backend and a fused compiled loop, side by side.

    PYTHONPATH=services .venv/bin/python scripts/bench/kernels.py [--algorithms PSO,GWO]
        [--functions F1-F13] [--runs 10] [--repeats 2]

The setting is the ICOOT paper's Table 2 (30 dims, 30 agents, 500 iterations). For each algorithm
with a compiled kernel (``swarmpath.optimizers.compiled``; default: all of them):

* ``numpy``: ``minimize_many`` over the functions (stacked, default chunks; F7 alone), CPU
  seconds / (functions x runs);
* ``numba``: the same call with ``backend="numba"`` (one kernel call per run, from Python);
* ``fused``: the kernel run with an ``evaluate`` whose function is fixed at compile time (the
  function's code inlined, F10's exp one call of numpy's loop per population; through the
  module's ``loop(evaluate, ...)``, or its @njit ``run`` recompiled by
  ``ufuncs.with_objective``; an algorithm with neither gets no fused column), called directly
  per run (no per-run Python beyond the call): what a hand-written compiled loop of the same
  algorithm costs. Its numbers are checked to be the backend's (a different number would mean a
  different trajectory, hence other work).

CPU time (``time.process_time``) of this process; the three are interleaved per function and the
best of ``--repeats`` is kept (the machine is shared). Compilation is done (and cached) before
timing. Output: a markdown table per algorithm with the ratios numpy/numba and numba/fused
(issue 14's target: numba within 1.5x of fused), then the load average.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np
from numba import njit

from swarmpath.functions import expand_function_names, get_function
from swarmpath.optimizers import get_optimizer, minimize_many
from swarmpath.optimizers.compiled import find_kernel, kernel_names
from swarmpath.optimizers.compiled.functions import (
    _E,
    ACKLEY,
    FUNCTION_IDS,
    NOISY,
    WRAPPED,
    ackley_parts,
    numpy_exp,
    value,
)
from swarmpath.optimizers.compiled.streams import RANDOM, take
from swarmpath.optimizers.compiled.ufuncs import with_objective
from swarmpath.optimizers.streams import run_generator

DIM, AGENTS, ITERATIONS = 30, 30, 500


def fused_evaluate(fid: int):
    """``functions.evaluate`` with the function fixed at compile time (``fid`` is a constant of
    the closure: its branches fold away and the function's code is inlined)."""

    @njit
    def evaluate(stream, _fid, shifted, shift, lower, upper, X, F, mask, w):
        m, d = X.shape
        z = w[3]
        e = np.zeros(2 * m if fid == ACKLEY else 0)
        for i in range(m):
            if not mask[i]:
                F[i] = np.inf
                continue
            x = X[i]
            if shifted:
                for j in range(d):
                    z[j] = X[i, j] - shift[j]
                if fid == WRAPPED:
                    for j in range(d):
                        z[j] = ((z[j] - lower[j]) % (upper[j] - lower[j])) + lower[j]
                x = z
            if fid == ACKLEY:
                e[i], e[m + i] = ackley_parts(x, w)
            else:
                F[i] = value(fid, x, w)
        if fid == ACKLEY:
            numpy_exp(e)
            for i in range(m):
                if mask[i]:
                    F[i] = ((-20.0 * e[i] - e[m + i]) + 20.0) + _E
        if fid == NOISY:
            start = take(stream, RANDOM, m)
            row = stream[1][RANDOM]
            for i in range(m):
                F[i] = F[i] + row[start + i]
        for i in range(m):
            if np.isnan(F[i]):
                F[i] = np.inf

    return evaluate


def fused_runner(algo: str, evaluate):
    """The algorithm's kernel with ``evaluate`` as its objective: the module's
    ``loop(evaluate, ...)`` if it has one, else its @njit ``run`` recompiled with that global
    (``ufuncs.with_objective``); None if neither exists."""
    kernel = find_kernel(algo)
    assert kernel is not None
    module = sys.modules[kernel.run.__module__]
    if hasattr(module, "loop"):
        return lambda *args: module.loop(evaluate, *args)
    if hasattr(kernel.run, "py_func"):
        return with_objective(kernel.run, evaluate)
    return None


def cpu(fn) -> float:
    started = time.process_time()
    fn()
    return time.process_time() - started


def bench_algorithm(algo: str, functions: list[str], runs: int, repeats: int) -> list[str]:
    kernel = find_kernel(algo)
    assert kernel is not None
    params = kernel.pack(get_optimizer(algo).resolve_params(None))
    lower = {f: np.full(DIM, get_function(f).lower) for f in functions}
    upper = {f: np.full(DIM, get_function(f).upper) for f in functions}
    shift = np.zeros(DIM)
    fused = {f: fused_runner(algo, fused_evaluate(FUNCTION_IDS[f])) for f in functions}
    if any(v is None for v in fused.values()):
        return [f"#### {algo}: no fused loop (its module has no loop(evaluate, ...)) ", ""]
    kw = dict(dim=DIM, agents=AGENTS, iterations=ITERATIONS, runs=runs, seed=1)

    def fused_runs(f: str, n: int) -> list[tuple[float, np.ndarray]]:
        return [fused[f](run_generator(1, r), FUNCTION_IDS[f], False, shift, lower[f], upper[f],
                         AGENTS, ITERATIONS, params)[:2] for r in range(n)]

    print(f"compiling {algo} ...", file=sys.stderr)
    minimize_many(algo, functions, **{**kw, "runs": 1, "iterations": 2}, backend="numba")
    for f in functions:
        fused_runs(f, 1)
    # numbers: the fused loop computes the backend's runs (else it would time other work)
    check = minimize_many(algo, functions, **{**kw, "runs": 2}, backend="numba")
    for f, res in zip(functions, check, strict=True):
        for (value_, _x), ref in zip(fused_runs(f, 2), res.best_fitness, strict=True):
            gap = abs(value_ - ref) / max(abs(ref), 1e-300)
            if gap > 0.0:
                print(f"  note: {algo} {f} fused {value_!r} backend {ref!r}", file=sys.stderr)

    best = {"numpy": np.inf, "numba": np.inf}
    fused_cpu = {f: np.inf for f in functions}
    for _ in range(repeats):
        best["numpy"] = min(best["numpy"], cpu(lambda: minimize_many(algo, functions, **kw)))
        best["numba"] = min(best["numba"], cpu(
            lambda: minimize_many(algo, functions, **kw, backend="numba")))
        for f in functions:
            fused_cpu[f] = min(fused_cpu[f], cpu(lambda f=f: fused_runs(f, runs)))
    per_numba = {}
    for f in functions:  # per function, numba: one more timed pass (cheap)
        per_numba[f] = cpu(lambda f=f: minimize_many(algo, [f], **kw, backend="numba")) / runs
    n = len(functions) * runs
    numpy_ms, numba_ms = best["numpy"] / n * 1e3, best["numba"] / n * 1e3
    fused_ms = sum(fused_cpu.values()) / n * 1e3
    lines = [
        f"#### {algo}: {', '.join(functions)}, {DIM} dims, {AGENTS} agents, {ITERATIONS} "
        f"iterations, {runs} runs per function",
        "",
        "| function | numba ms/run | fused ms/run | numba / fused |",
        "| --- | ---: | ---: | ---: |",
    ]
    for f in functions:
        a, b = per_numba[f] * 1e3, fused_cpu[f] / runs * 1e3
        lines.append(f"| {f} | {a:.2f} | {b:.2f} | {a / b:.2f}x |")
    lines += [
        "",
        "| CPU ms per run (all functions) | numpy | numba | fused | numpy / numba | "
        "numba / fused |",
        "| --- | ---: | ---: | ---: | ---: | ---: |",
        f"| {algo} | {numpy_ms:.2f} | {numba_ms:.2f} | {fused_ms:.2f} | "
        f"{numpy_ms / numba_ms:.2f}x | {numba_ms / fused_ms:.2f}x |",
        "",
    ]
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--algorithms", default=",".join(kernel_names()))
    ap.add_argument("--functions", default="F1-F13")
    ap.add_argument("--runs", type=int, default=10)
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    algos = [a.strip() for a in args.algorithms.split(",") if a.strip()]
    missing = [a for a in algos if find_kernel(a) is None]
    if missing:
        ap.error(f"--algorithms: no kernel for {', '.join(missing)} (kernels: "
                 f"{', '.join(kernel_names())})")
    functions = expand_function_names(args.functions)
    before = os.getloadavg()
    out: list[str] = []
    for algo in algos:
        out += bench_algorithm(algo, functions, args.runs, args.repeats)
    after = os.getloadavg()
    out.append(f"Load average {before[0]:.2f} at start, {after[0]:.2f} at the end "
               f"({os.cpu_count()} CPUs).")
    print("\n".join(out))


if __name__ == "__main__":
    main()
