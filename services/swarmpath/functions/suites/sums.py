"""Sums added in a C loop's order, and rotations, vectorized over points.

The references (COCO, the CEC codes) add ``acc += a[j] * b[j]`` for j = 0, 1, ...; numpy's
reductions add pairwise. The difference is in the last bits; where it matters (COCO's
Gram-Schmidt, whose last bits the chaotic f16/f19 turn into 1e-9 of f) the suites add in the
references' order with :func:`sequential` (a cumulative sum: left to right).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def rotate(x: Array, matrix: Array, offset: float = 0.0) -> Array:
    """offset + matrix @ x for every point x of X (..., d), as one matmul. Its sums add in BLAS
    order, not the references' left to right; measured on every golden case that moves no value
    by more than 3.2e-11 of max(|f|, |f - f_opt|) (bbob f19; adding in the C order gave
    3.4e-11 at 1.5-4x the cost), so the order that matters is the rotations' own construction
    (``bbob_instances``, Gram-Schmidt summed in order)."""
    out = np.matmul(np.asarray(x, dtype=float), matrix.T)
    if offset:
        out += offset
    return np.asarray(out)


def sequential(terms: Array) -> Array:
    """Sum over the last axis added first to last."""
    terms = np.asarray(terms, dtype=float)
    if terms.shape[-1] == 0:
        return np.zeros(terms.shape[:-1])
    return np.asarray(np.cumsum(terms, axis=-1)[..., -1])


def sequential_sum(terms: Array) -> float:
    """sum of a 1-D ``terms`` added first to last."""
    return float(sequential(terms)) if np.size(terms) else 0.0
