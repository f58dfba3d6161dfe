#!/usr/bin/env python3
"""Why FDO's compiled kernel calls numpy's own cbrt: the same kernel with the C library's cbrt.

    PYTHONPATH=services .venv/bin/python scripts/bench/libm_cbrt.py [--runs 3] [--seed 1]

numpy's ``np.cbrt`` table has two float64 loops: the first (the one numpy runs) is picked by CPU
at run time (SVML on AVX-512), the second is the generic loop around the C library's scalar
cbrt. The script checks that the second equals the C library (numba's scalar ``np.cbrt``) and
how often it differs from the first, then runs FDO's kernel with the C library's cbrt bound to
the symbol its numpy loop is called by (``ufuncs.cbrt_inplace``; before the kernel is loaded)
against the numpy reference (F1-F13, 30 dims, 30 agents, 500 iterations) and prints, per run,
the first iteration whose best-so-far differs and both final values.
"""

from __future__ import annotations

import argparse
import ctypes

import llvmlite.binding as llvm
import numpy as np
from numba import carray, cfunc, njit, types

from swarmpath.functions import expand_function_names
from swarmpath.optimizers import minimize
from swarmpath.optimizers.compiled import ufuncs


def c_library_loop() -> ufuncs.Loop:
    """The second float64 loop of np.cbrt (the generic one around the C library's cbrt)."""
    base = id(np.cbrt)
    types = np.cbrt.types
    index = [i for i, t in enumerate(types) if t == "d->d"][1]
    functions = ufuncs._pointer(base + ufuncs._FUNCTIONS)
    data = ufuncs._pointer(base + ufuncs._DATA)
    return (ufuncs.LoopType(ufuncs._pointer(functions + 8 * index)),
            ufuncs._pointer(data + 8 * index))


@njit
def scalar_cbrt(x):  # type: ignore[no-untyped-def]
    out = np.empty_like(x)
    for k in range(x.size):
        out[k] = np.cbrt(x[k])
    return out


_ARGS = types.CPointer(types.CPointer(types.float64))
_SIZES = types.CPointer(types.int64)


@cfunc(types.void(_ARGS, _SIZES, _SIZES, types.voidptr))
def c_library_cbrt_loop(args, dimensions, steps, data):  # type: ignore[no-untyped-def]
    """numpy's loop convention around the C library's cbrt (contiguous float64 only)."""
    n = dimensions[0]
    source = carray(args[0], n)
    target = carray(args[1], n)
    for k in range(n):
        target[k] = np.cbrt(source[k])


def apply(loop: ufuncs.Loop, x: np.ndarray) -> None:
    """x <- loop(x) in place, called from Python with numpy's loop convention."""
    args = (ctypes.c_void_p * 2)(x.ctypes.data, x.ctypes.data)
    dimensions = (ctypes.c_int64 * 1)(x.size)
    steps = (ctypes.c_int64 * 2)(8, 8)
    loop[0](ctypes.addressof(args), ctypes.addressof(dimensions), ctypes.addressof(steps),
            loop[1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    libm = c_library_loop()
    x = np.random.default_rng(0).standard_normal(100_000) ** 2
    y = x.copy()
    apply(libm, y)
    assert np.array_equal(y, scalar_cbrt(x)), "the second loop is not the C library's cbrt"
    print(f"C library's cbrt differs from np.cbrt on {np.mean(y != np.cbrt(x)):.1%} of "
          "100 000 squared normals")
    llvm.add_symbol("swarmpath_numpy_cbrt_dd", c_library_cbrt_loop.address)
    equal = total = 0
    for f in expand_function_names("F1-F13"):
        kw = dict(runs=args.runs, seed=args.seed, dim=30, agents=30, iterations=500)
        ref = minimize("FDO", f, **kw)
        fast = minimize("FDO", f, backend="numba", **kw)
        for k in range(args.runs):
            total += 1
            differ = np.nonzero(ref.curve[k] != fast.curve[k])[0]
            if differ.size == 0:
                equal += 1
                print(f"{f} run {k}: equal")
            else:
                print(f"{f} run {k}: differs from iteration {differ[0] + 1}; final "
                      f"{ref.best_fitness[k]:.6g} (numpy) vs {fast.best_fitness[k]:.6g}")
    print(f"{equal} of {total} runs equal to the reference with the C library's cbrt")


if __name__ == "__main__":
    main()
