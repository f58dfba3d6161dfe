"""The markers of a comparison and Holm's correction, shared by :mod:`.compare` (per cell) and
:mod:`.friedman` (over blocks)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from swarmpath.evidence.stats import ALPHA

__all__ = ["ALPHA", "BETTER", "MARKERS", "SAME", "WORSE", "holm"]

BETTER, SAME, WORSE = "+", "=", "-"
MARKERS = (BETTER, SAME, WORSE)


def holm(pvalues: ArrayLike) -> np.ndarray:
    """Holm's step-down adjusted p-values (same order as given, capped at 1).

    Sorted ascending, the i-th smallest (i from 0) is multiplied by m - i, then a running maximum
    keeps the adjusted values monotone; rejecting where adjusted p < alpha is Holm's procedure."""
    p = np.asarray(pvalues, dtype=float).ravel()
    m = p.size
    if m == 0:
        return p.copy()
    order = np.argsort(p, kind="stable")
    scaled = np.minimum(1.0, np.maximum.accumulate(p[order] * (m - np.arange(m))))
    out = np.empty(m)
    out[order] = scaled
    return out
