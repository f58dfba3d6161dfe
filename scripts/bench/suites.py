#!/usr/bin/env python3
"""Evaluations per second of the suites: swarmpath's vectorized numpy and its compiled
objectives (numba backend) against calling the reference point by point.

    PYTHONPATH=services .venv/bin/python scripts/bench/suites.py [--suite bbob] [--dims 10,40]
        [--points 900] [--repeats 5]
        [--cec2017 LIB INPUT_DIR] [--cec2022 LIB INPUT_DIR] [--symbol-suffix _c]

References: bbob: ``cocoex.BareProblem`` called once per point (how an optimizer drives
COCO); CEC: the organisers' ``cec17_test_func`` / ``cec22_test_func`` from a shared library you
built from their code (as for scripts/suites/golden.py), called once per point (mx = 1) and once
for the whole batch (mx = points: the C code's own speed without the per-call overhead).
swarmpath's numpy evaluates the batch of ``--points`` points as runs x ``--population`` agents
(30 x 30 by default) in one call, as the numpy backend does; its compiled objective (where
there is one) is called once per population of ``--population`` points, as a kernel calls it,
and checked equal to the numpy values bit for bit. Every figure is the best of ``--repeats`` in
process CPU time, measured side by side in one run; each row also checks that the values agree
(golden.agree).
Prints one row per function and a median line per suite and dimension, and the load average.
BLAS runs on one thread, as in the study processes (swarmpath.parallel): on a loaded machine
its threads' spinning otherwise costs 10-50x the matmul of a rotation.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # before numpy loads its BLAS

import argparse  # noqa: E402
import ctypes  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from swarmpath.functions import get_function, list_functions  # noqa: E402
from swarmpath.functions.suites import golden  # noqa: E402


def best_time(call: Callable[[], object], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.process_time()
        call()
        times.append(time.process_time() - start)
    return max(min(times), 1e-9)


Reference = Callable[[int, np.ndarray, int], np.ndarray]


def cec_library(lib: Path, symbol: str, workdir: Path) -> Reference:
    function = getattr(ctypes.CDLL(str(lib.resolve())), symbol)
    pointer = ctypes.POINTER(ctypes.c_double)

    def evaluate(number: int, X: np.ndarray, per_call: int) -> np.ndarray:
        X = np.ascontiguousarray(X)
        out = np.zeros(len(X))
        here = os.getcwd()
        os.chdir(workdir)
        try:
            for start in range(0, len(X), per_call):
                rows = X[start:start + per_call]
                function(rows.ctypes.data_as(pointer), out[start:].ctypes.data_as(pointer),
                         X.shape[1], len(rows), number)
        finally:
            os.chdir(here)
        return out

    return evaluate


def compiled_caller(fn: object, dim: int, rows: int) -> Callable[[np.ndarray], np.ndarray] | None:
    """The function's compiled objective (numba backend) evaluating X in populations of
    ``rows`` points, called through its pointer from compiled code once per population, as a
    kernel calls it; None if it has none or numba is missing. Its data array and buffers are
    made outside the timing."""
    try:
        from numba import njit

        from swarmpath.optimizers.compiled import objectives
    except ImportError:
        return None
    if not objectives.has_objective(fn):  # type: ignore[arg-type]
        return None
    data = np.ascontiguousarray(objectives.data_for(fn, dim))  # type: ignore[arg-type]
    address = objectives.objective_for(fn, data)[0]  # type: ignore[arg-type]
    call = objectives._call

    @njit
    def populations(X, F, mask, work, data):
        n, d = X.shape
        for start in range(0, n, rows):
            m = min(rows, n - start)
            call(address, X, start * d, d, F, start, m, mask, work, 0, data.ctypes.data)

    def evaluate(X: np.ndarray) -> np.ndarray:
        X = np.ascontiguousarray(X)
        out = np.empty(len(X))
        populations(X, out, np.ones(len(X), dtype=np.uint8),
                    np.empty(rows * dim + 3 * dim + 2 * rows), data)
        return out

    return evaluate


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", action="append", choices=("bbob", "cec2017", "cec2022"))
    parser.add_argument("--dims", default=None, help="default: bbob 10,40; cec2017 10,50; "
                        "cec2022 10,20")
    parser.add_argument("--points", type=int, default=900)
    parser.add_argument("--reference-points", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--population", type=int, default=30,
                        help="points per call of a compiled objective (a kernel's agents)")
    parser.add_argument("--cec2017", nargs=2, type=Path, metavar=("LIB", "INPUT_DIR"))
    parser.add_argument("--cec2022", nargs=2, type=Path, metavar=("LIB", "INPUT_DIR"))
    parser.add_argument("--symbol-suffix", default="", help="e.g. _c for a C-linkage wrapper")
    args = parser.parse_args(argv)
    suites = args.suite or ["bbob", "cec2017", "cec2022"]
    defaults = {"bbob": "10,40", "cec2017": "10,50", "cec2022": "10,20"}
    print(f"load average {os.getloadavg()[0]:.2f}; {args.points} points per batch, best of "
          f"{args.repeats}, process CPU time")
    print(f"{'function':<14}{'D':>4}{'numpy/s':>12}{'ref/s':>11}{'ratio':>8}"
          f"{'numba/s':>11}{'numba/numpy':>12}{'C batch/s':>12}")
    rng = np.random.default_rng(1)
    for suite in suites:
        reference: Callable[..., np.ndarray] | None = None
        if suite == "bbob":
            try:
                import cocoex
            except ImportError:
                print("bbob: cocoex not installed (pip install coco-experiment)")
                continue
        else:
            where = getattr(args, suite)
            if where is None:
                print(f"{suite}: no reference library given (--{suite} LIB INPUT_DIR)")
                continue
            name = ("cec17_test_func" if suite == "cec2017" else "cec22_test_func")
            reference = cec_library(where[0], name + args.symbol_suffix, where[1])
        for dim in map(int, (args.dims or defaults[suite]).split(",")):
            ratios, speeds, compiled_ratios = [], [], []
            for name in list_functions(suite):
                fn = get_function(name)
                try:
                    fn.check_dim(dim)  # type: ignore[attr-defined]
                except ValueError:
                    continue
                X = rng.uniform(fn.lower, fn.upper, (args.points, dim))
                # runs x agents, one call: what the numpy backend evaluates (each run's
                # population is one matmul item; one 900-row matmul would sum otherwise)
                batch_shape = (-1, args.population, dim)
                runs = X.reshape(batch_shape)
                ours = fn.value(runs).ravel()  # type: ignore[attr-defined]
                t_ours = best_time(lambda fn=fn, runs=runs: fn.value(runs), args.repeats)
                R = X[: args.reference_points]
                batch = ""
                compiled = compiled_caller(fn, dim, args.population)
                numba_cols = f"{'-':>11}{'-':>12}"
                if compiled is not None:
                    same = np.array_equal(compiled(X),
                                          fn.kernel(runs).ravel())
                    t_numba = best_time(lambda c=compiled, X=X: c(X), args.repeats)
                    compiled_ratios.append(t_ours / t_numba)
                    numba_cols = (f"{args.points / t_numba:11.3g}{t_ours / t_numba:12.2f}"
                                  + ("" if same else " (NOT BIT-EQUAL)"))
                if suite == "bbob":
                    problem = cocoex.BareProblem("bbob", fn.number, dim, 1)  # type: ignore[attr-defined]
                    ref = np.array([problem(x) for x in R])
                    t_ref = best_time(lambda p=problem, R=R: [p(x) for x in R], args.repeats)
                else:
                    assert reference is not None
                    number = fn.number  # type: ignore[attr-defined]
                    ref = reference(number, R, 1)
                    t_ref = best_time(lambda n=number, R=R, c=reference: c(n, R, 1),
                                      args.repeats)
                    t_batch = best_time(lambda n=number, X=X, c=reference: c(n, X, len(X)),
                                        args.repeats)
                    batch = f"{args.points / t_batch:12.3g}"
                ok = golden.agree(ours[: len(R)], ref, fn.f_opt(dim)).all()  # type: ignore[attr-defined]
                speed, ref_speed = args.points / t_ours, len(R) / t_ref
                ratios.append(speed / ref_speed)
                speeds.append(speed)
                flag = "" if ok else "  VALUES DIFFER"
                print(f"{name:<14}{dim:>4}{speed:12.3g}{ref_speed:11.3g}"
                      f"{speed / ref_speed:8.2f}{numba_cols}{batch}{flag}")
            if ratios:
                print(f"{suite + ' median':<14}{dim:>4}{statistics.median(speeds):12.3g}"
                      f"{'':>11}{statistics.median(ratios):8.2f}  (ratio min "
                      f"{min(ratios):.2f}, max {max(ratios):.2f})")
            if compiled_ratios:
                print(f"{suite + ' numba':<14}{dim:>4}  numba / numpy median "
                      f"{statistics.median(compiled_ratios):.2f} (min "
                      f"{min(compiled_ratios):.2f}, max {max(compiled_ratios):.2f})")
    print(f"load average {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
