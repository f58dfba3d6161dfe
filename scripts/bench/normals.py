#!/usr/bin/env python3
"""Cost of one buffered block of random numbers: numpy's Generator vs numba's, same numbers.

    PYTHONPATH=services .venv/bin/python scripts/bench/normals.py [--blocks 300] [--repeats 5]

Fills blocks of ``streams.BLOCK`` uniforms and standard normals from a PCG64 generator the way
``RunStreams`` refills (numpy: ``Generator.random/standard_normal(out=row)``) and the way the
compiled kernels do (numba's ``Generator.random/standard_normal`` inside @njit), checks that the
two give the same numbers, and prints the best of ``--repeats`` in ns per number (process CPU
time) and the load average.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from numba import njit

from swarmpath.optimizers.streams import BLOCK


@njit(cache=True)
def fill_numba(rng, out, blocks, normal):  # type: ignore[no-untyped-def]
    for _ in range(blocks):
        if normal:
            out[:] = rng.standard_normal(out.size)
        else:
            out[:] = rng.random(out.size)


def fill_numpy(rng: np.random.Generator, out: np.ndarray, blocks: int, normal: bool) -> None:
    for _ in range(blocks):
        if normal:
            rng.standard_normal(out=out)
        else:
            rng.random(out=out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--blocks", type=int, default=300)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    a, b = np.empty(BLOCK), np.empty(BLOCK)
    for normal in (False, True):
        fill_numpy(np.random.default_rng(3), a, 2, normal)
        fill_numba(np.random.default_rng(3), b, 2, normal)
        assert np.array_equal(a, b), "numba's generator does not give numpy's numbers"
    before = os.getloadavg()[0]
    print("| numbers | numpy ns each | numba ns each | numpy / numba |")
    print("| --- | ---: | ---: | ---: |")
    for normal in (False, True):
        best = {"numpy": np.inf, "numba": np.inf}
        for _ in range(args.repeats):
            for name, fill in (("numpy", fill_numpy), ("numba", fill_numba)):
                rng = np.random.default_rng(1)
                started = time.process_time()
                fill(rng, a, args.blocks, normal)
                best[name] = min(best[name], time.process_time() - started)
        ns = {k: v / (args.blocks * BLOCK) * 1e9 for k, v in best.items()}
        kind = "standard normals" if normal else "uniforms"
        print(f"| {kind} | {ns['numpy']:.2f} | {ns['numba']:.2f} | "
              f"{ns['numpy'] / ns['numba']:.2f}x |")
    print(f"\nLoad average {before:.2f} at start, {os.getloadavg()[0]:.2f} at the end.")


if __name__ == "__main__":
    main()
