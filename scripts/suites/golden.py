#!/usr/bin/env python3
"""Generate the suites' golden values from the reference implementations.

    scripts/suites/golden.py bbob                       # needs cocoex (coco-experiment)
    scripts/suites/golden.py cec2017 LIB INPUT_DIR [--symbol NAME]
    scripts/suites/golden.py cec2022 LIB INPUT_DIR [--symbol NAME]

For bbob the reference is COCO's own ``cocoex.BareProblem("bbob", f, d, i)``. For the CEC
suites it is the organisers' C code (``cec17_test_func`` / ``cec22_test_func``, signature
``(double *x, double *f, int nx, int mx, int func_num)``) in a shared library LIB that you built
from their files yourself (swarmpath ships neither their code nor a way to build it), with
C linkage under ``--symbol`` (default: the function's name); INPUT_DIR is the directory that
holds their ``input_data`` (the code opens ``input_data/...`` relative to the working
directory). The points and the cases are :mod:`swarmpath.functions.suites.golden`'s; the values
go to ``tests/data/golden/<suite>.npz`` (float64, one array per function, dimension and
instance) with each case's f_opt, and the script prints how swarmpath's values agree.
"""

from __future__ import annotations

import argparse
import ctypes
import os
import sys
from pathlib import Path

import numpy as np

from swarmpath.functions import get_function
from swarmpath.functions.suites import golden

OUT = Path(__file__).resolve().parents[2] / "tests" / "data" / "golden"


def bbob_reference(number: int, dim: int, instance: int, X: np.ndarray) -> np.ndarray:
    import cocoex

    problem = cocoex.BareProblem("bbob", number, dim, instance)
    return np.array([problem(x) for x in X])


def c_reference(lib: Path, symbol: str, workdir: Path):
    library = ctypes.CDLL(str(lib.resolve()))
    function = getattr(library, symbol)
    pointer = ctypes.POINTER(ctypes.c_double)

    def evaluate(number: int, dim: int, instance: int, X: np.ndarray) -> np.ndarray:
        X = np.ascontiguousarray(X, dtype=np.float64)
        out = np.zeros(len(X))
        here = os.getcwd()
        os.chdir(workdir)
        try:
            function(X.ctypes.data_as(pointer), out.ctypes.data_as(pointer), dim, len(X), number)
        finally:
            os.chdir(here)
        return out

    return evaluate


def generate(suite: str, reference) -> int:
    arrays: dict[str, np.ndarray] = {}
    worst = 0.0
    failures = 0
    for name, dim, instance in golden.cases(suite):
        fn = get_function(name).with_instance(instance)  # type: ignore[attr-defined]
        x_opt, f_opt = fn.x_opt(dim), fn.f_opt(dim)
        X = golden.points(dim, fn.lower, fn.upper, x_opt, golden.salt(fn.number, dim, instance))
        ref = reference(fn.number, dim, instance, X)
        arrays[golden.key(name, dim, instance)] = np.append(ref, f_opt)
        ours = fn.value(X)
        ok = golden.agree(ours, ref, f_opt)
        failures += int(np.count_nonzero(~ok))
        finite = np.isfinite(ref) & np.isfinite(ours)
        scale = np.maximum(np.abs(ref), np.abs(ref - f_opt))[finite]
        if scale.size:
            worst = max(worst, float(np.max(np.abs(ours - ref)[finite] / scale)))
    OUT.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(OUT / f"{suite}.npz", **arrays)
    print(f"{suite}: {len(arrays)} cases x {golden.BOX_POINTS + 1 + golden.NEAR_POINTS} points "
          f"-> {OUT / (suite + '.npz')}; worst difference {worst:.2e} of "
          f"max(|f|, |f - f_opt|); {failures} points outside {golden.RTOL:g}")
    return 1 if failures else 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("suite", choices=("bbob", "cec2017", "cec2022"))
    parser.add_argument("lib", nargs="?", type=Path, help="CEC: the shared library")
    parser.add_argument("input_dir", nargs="?", type=Path,
                        help="CEC: the directory holding input_data/")
    parser.add_argument("--symbol", help="CEC: the function's exported name")
    args = parser.parse_args(argv)
    if args.suite == "bbob":
        return generate("bbob", bbob_reference)
    if args.lib is None or args.input_dir is None:
        parser.error(f"{args.suite} needs LIB and INPUT_DIR")
    symbol = args.symbol or ("cec17_test_func" if args.suite == "cec2017" else "cec22_test_func")
    return generate(args.suite, c_reference(args.lib, symbol, args.input_dir))


if __name__ == "__main__":
    sys.exit(main())
