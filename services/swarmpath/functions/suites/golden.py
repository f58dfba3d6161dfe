"""Where the golden values are taken: the points, the cases, the agreement rule.

``scripts/suites/golden.py`` evaluates the references (COCO's ``cocoex``; the organisers' CEC
2017 and 2022 C codes) at :func:`points` for every :func:`cases` entry and stores the values in
``tests/data/golden/<suite>.npz``; ``tests/test_suites_golden.py`` recomputes the points and
compares swarmpath's values with :func:`agree`.

The points need no random generator (whose streams may change between numpy versions): a
Kronecker sequence, coordinate j of point k being frac(offset + (k + 1) sqrt(p_j)) for the j-th
prime p_j, spread evenly over the box; then the instance's optimum itself and points within
1e-3 of the box width around it (where errors are small and digits cancel).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

BOX_POINTS = 1000
NEAR_POINTS = 23
#: agreement: |ours - reference| <= RTOL * max(|reference|, |reference - f_opt|)
RTOL = 1e-10
#: COCO's dimensions of the bbob suite, and three instances (1, 2 as in every COCO year, and 71
#: of the 2018-2020 set); the CEC suites have their official data only (instance 1)
BBOB_DIMENSIONS = (2, 3, 5, 10, 20, 40)
BBOB_INSTANCES = (1, 2, 71)


def _primes(count: int) -> list[int]:
    found: list[int] = []
    candidate = 2
    while len(found) < count:
        if all(candidate % p for p in found if p * p <= candidate):
            found.append(candidate)
        candidate += 1
    return found


def points(dim: int, lower: float, upper: float, x_opt: Array, salt: int) -> Array:
    """(BOX_POINTS + 1 + NEAR_POINTS, dim): box points, x_opt, points near x_opt (in the box)."""
    alpha = np.array([math.sqrt(p) % 1.0 for p in _primes(dim)])
    offset = (salt * 0.6180339887498949) % 1.0
    k = np.arange(1, BOX_POINTS + 1, dtype=float)[:, None]
    unit = (offset + k * alpha) % 1.0
    box = lower + (upper - lower) * unit
    near = x_opt + 1e-3 * (upper - lower) * (2.0 * unit[:NEAR_POINTS] - 1.0)
    near = np.clip(near, lower, upper)
    return np.vstack([box, np.asarray(x_opt, dtype=float)[None, :], near])


def agree(ours: Array, reference: Array, f_opt: float) -> NDArray[np.bool_]:
    """Where ``ours`` equals ``reference`` within RTOL (infinities must match exactly)."""
    ours = np.asarray(ours, dtype=float)
    reference = np.asarray(reference, dtype=float)
    finite = np.isfinite(reference) & np.isfinite(ours)
    with np.errstate(invalid="ignore", over="ignore"):
        scale = np.maximum(np.abs(reference), np.abs(reference - f_opt))
        close = np.abs(ours - reference) <= RTOL * np.where(finite, scale, 0.0)
    return np.where(finite, close, ours == reference)


def cases(suite: str) -> list[tuple[str, int, int]]:
    """(function name, dim, instance) of every golden case of ``suite``: every function, every
    dimension the suite defines (bbob: COCO's), three instances (CEC: its one)."""
    from swarmpath.functions import get_suite

    out: list[tuple[str, int, int]] = []
    for fn in get_suite(suite).functions:
        dims = getattr(fn, "dimensions", None) or BBOB_DIMENSIONS
        instances = getattr(fn, "instances", None) or BBOB_INSTANCES
        out.extend((fn.name, d, i) for d in dims for i in instances)
    return out


def key(name: str, dim: int, instance: int) -> str:
    return f"{name}|{dim}|{instance}"


def salt(number: int, dim: int, instance: int) -> int:
    return number * 7919 + dim * 104729 + instance
