"""Sums and matrix-vector products added in a C loop's order, vectorized over points.

The references (COCO, the CEC codes) add ``acc += a[j] * b[j]`` for j = 0, 1, ...; numpy's
reductions and matmul add in other orders (pairwise, blocked). The difference is in the last
bits, and the chaotic functions (BBOB f16/f19, Weierstrass, Katsuura, the composition weights)
turn last bits of a rotated point into 1e-9 of f. These helpers repeat the references' order,
one numpy operation per coordinate, still vectorized over all points at once.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def rotate(x: Array, matrix: Array, offset: float = 0.0) -> Array:
    """offset + matrix @ x for every point x of X (..., d): row i is
    ``offset + x[0] m[i, 0] + x[1] m[i, 1] + ...`` added left to right."""
    x = np.asarray(x, dtype=float)
    acc = np.full((*x.shape[:-1], matrix.shape[0]), offset)
    for j in range(x.shape[-1]):
        acc += x[..., j, None] * matrix[:, j]
    return acc


def sequential(terms: Array) -> Array:
    """Sum over the last axis added first to last."""
    terms = np.asarray(terms, dtype=float)
    if terms.shape[-1] == 0:
        return np.zeros(terms.shape[:-1])
    return np.asarray(np.cumsum(terms, axis=-1)[..., -1])


def sequential_sum(terms: Array) -> float:
    """sum of a 1-D ``terms`` added first to last."""
    return float(sequential(terms)) if np.size(terms) else 0.0
