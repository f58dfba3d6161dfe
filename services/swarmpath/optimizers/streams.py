"""Per-run random streams: the basis of the reproducibility contract.

Run r of a study with seed s draws every random number from its own generator, seeded by
``SeedSequence(s, spawn_key=(r, purpose))``. A batch of runs is therefore just a stack of
independent streams: run r gives the same numbers whether it is computed alone, as the first of
two or the fifth of thirty, on any worker, in any order.

Draws come out shaped (runs, *shape). The per-run loop here is the only Python loop over runs in
an optimizer step: one C-level fill per run per draw, everything else is array arithmetic.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

# spawn_key purposes: keep streams used for different things independent of each other.
OPTIMIZER = 0
SHIFT = 1
SIMULATION = 2


def run_generator(seed: int, run: int, purpose: int = OPTIMIZER) -> np.random.Generator:
    """The generator of run ``run`` for ``purpose`` under study seed ``seed``."""
    if seed < 0 or run < 0:
        raise ValueError("seed and run must be non-negative integers")
    sequence = np.random.SeedSequence(seed, spawn_key=(run, purpose))
    return np.random.Generator(np.random.PCG64(sequence))


class RunStreams:
    """One independent generator per run, drawing stacked arrays shaped (runs, *shape)."""

    def __init__(self, generators: Sequence[np.random.Generator]):
        if not generators:
            raise ValueError("at least one run is needed")
        self.generators = list(generators)

    @classmethod
    def for_runs(cls, seed: int, runs: Sequence[int] | int, purpose: int = OPTIMIZER) -> RunStreams:
        indices = range(runs) if isinstance(runs, int) else runs
        return cls([run_generator(seed, r, purpose) for r in indices])

    @property
    def runs(self) -> int:
        return len(self.generators)

    def random(self, *shape: int) -> Array:
        """U[0, 1) of shape (runs, *shape)."""
        out = np.empty((self.runs, *shape))
        for g, row in zip(self.generators, out, strict=True):
            g.random(out=row)
        return out

    def uniform(self, low: float | Array, high: float | Array, *shape: int) -> Array:
        """U[low, high) of shape (runs, *shape); low/high broadcast against that shape."""
        return low + (high - low) * self.random(*shape)

    def normal(self, *shape: int) -> Array:
        """Standard normal of shape (runs, *shape)."""
        out = np.empty((self.runs, *shape))
        for g, row in zip(self.generators, out, strict=True):
            g.standard_normal(out=row)
        return out

    def integers(self, low: int, high: int, *shape: int) -> NDArray[np.int64]:
        """Integers in [low, high) of shape (runs, *shape)."""
        return np.stack([g.integers(low, high, size=shape) for g in self.generators])

    def permutations(self, n: int, *shape: int) -> NDArray[np.int64]:
        """Independent random permutations of range(n): shape (runs, *shape, n)."""
        keys = self.random(*shape, n)
        return np.argsort(keys, axis=-1, kind="stable")
