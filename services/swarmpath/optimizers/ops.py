"""Array building blocks shared by several optimizers."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from swarmpath.optimizers.streams import RunStreams

Array = NDArray[np.float64]


def linear_chain(a: Array, b: Array) -> Array:
    """Solve y_i = a_i * y_{i-1} + b_i along axis 1 (y_{-1} = 0), vectorized.

    ``a`` is (R, N), ``b`` is (R, N, d). This reproduces an in-place sequential sweep over agents
    (salp followers, coot chain movement: agent i averages with the *already moved* agent i-1)
    without a Python loop over agents: a Hillis-Steele prefix scan of the affine maps
    y -> a_i y + b_i takes ceil(log2 N) whole-array steps.
    """
    A = np.array(a, dtype=float, copy=True)
    B = np.array(b, dtype=float, copy=True)
    n = A.shape[1]
    offset = 1
    while offset < n:
        # compose map i with map i - offset (the earlier one is applied first)
        B[:, offset:] = B[:, offset:] + A[:, offset:, None] * B[:, :-offset]
        A[:, offset:] = A[:, offset:] * A[:, :-offset]
        offset *= 2
    return B


def mantegna_sigma(beta: float) -> float:
    """Scale of the numerator in Mantegna's algorithm for Levy-stable steps."""
    num = math.gamma(1 + beta) * math.sin(math.pi * beta / 2)
    den = math.gamma((1 + beta) / 2) * beta * 2 ** ((beta - 1) / 2)
    return float((num / den) ** (1 / beta))


def levy(streams: RunStreams, *shape: int, beta: float = 1.5, scale: float = 0.01) -> Array:
    """Levy flight steps (Mantegna 1994): scale u / |v|^(1/beta), u ~ N(0, sigma^2), v ~ N(0, 1)."""
    u = streams.normal(*shape) * mantegna_sigma(beta)
    v = streams.normal(*shape)
    return scale * u / np.abs(v) ** (1.0 / beta)


def take_rows(X: Array, idx: NDArray[np.int64]) -> Array:
    """X[r, idx[r]] for X (R, N, d) and idx (R,) -> (R, d)."""
    return X[np.arange(X.shape[0]), idx]
