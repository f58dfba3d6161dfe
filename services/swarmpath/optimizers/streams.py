"""Per-run random streams: the basis of the reproducibility contract.

Run r of a study with seed s draws every random number from its own generator, seeded by
``SeedSequence(s, spawn_key=(r, purpose))``. A batch of runs is therefore just a stack of
independent streams: run r gives the same numbers whether it is computed alone, as the first of
two or the fifth of thirty, on any worker, in any order.

Draws come out shaped (runs, *shape). The per-run loop here is the only Python loop over runs in
an optimizer step: one C-level fill per run, everything else is array arithmetic.

Draws are buffered in blocks when the streams own their generators (``for_runs``): every run
fills ``block`` numbers of its own stream into one row of a (runs, block) array, one buffer per
kind (uniform, normal), and a draw copies the next columns. A run's uniforms are consumed in
exactly the order an unbuffered stream would deliver them (a refill carries the unused tail
over), so buffering changes no number of an algorithm that draws only uniforms; it removes the
per-draw loop over runs. An algorithm that draws both kinds gets the same numbers as if each
refill were a draw of its own; the refill points depend only on ``block`` and the sequence of
draw sizes, never on the number of runs, so run r still depends only on (seed, r).
``integers`` goes to the generators directly (unbuffered, rarely used).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

# spawn_key purposes: keep streams used for different things independent of each other.
OPTIMIZER = 0
SHIFT = 1
SIMULATION = 2
ROTATE = 3

#: Uniforms buffered per run by ``for_runs`` (64 KiB per run).
BLOCK = 8192


def run_generator(seed: int, run: int, purpose: int = OPTIMIZER) -> np.random.Generator:
    """The generator of run ``run`` for ``purpose`` under study seed ``seed``."""
    if seed < 0 or run < 0:
        raise ValueError("seed and run must be non-negative integers")
    sequence = np.random.SeedSequence(seed, spawn_key=(run, purpose))
    return np.random.Generator(np.random.PCG64(sequence))


class RunStreams:
    """Independent generators, one per run, drawing stacked arrays shaped (runs, *shape).

    ``block`` > 0 buffers uniform draws (see the module docstring); use it only when nothing else
    draws from the generators (``for_runs`` does, with :data:`BLOCK`). Every draw is a new
    contiguous array that the caller may overwrite.
    """

    def __init__(self, generators: Sequence[np.random.Generator], block: int = 0):
        if not generators:
            raise ValueError("at least one run is needed")
        if block < 0:
            raise ValueError("block must be >= 0")
        self.generators = list(generators)
        self.block = int(block)
        # per kind of draw: [buffer (runs, width), position of the next unused column]
        self._buffers: dict[str, list[Any]] = {}

    @classmethod
    def for_runs(
        cls,
        seed: int,
        runs: Sequence[int] | int,
        purpose: int = OPTIMIZER,
        block: int | None = None,
    ) -> RunStreams:
        indices = range(runs) if isinstance(runs, int) else runs
        return cls(
            [run_generator(seed, r, purpose) for r in indices], BLOCK if block is None else block
        )

    @property
    def runs(self) -> int:
        return len(self.generators)

    def random(self, *shape: int) -> Array:
        """U[0, 1) of shape (runs, *shape)."""
        return self._draw("random", shape)

    def uniform(self, low: float | Array, high: float | Array, *shape: int) -> Array:
        """U[low, high) of shape (runs, *shape); low/high broadcast against that shape."""
        return low + (high - low) * self.random(*shape)

    def normal(self, *shape: int) -> Array:
        """Standard normal of shape (runs, *shape)."""
        return self._draw("normal", shape)

    def random_parts(self, parts: int, *shape: int) -> list[Array]:
        """``parts`` consecutive uniform draws of shape (runs, *shape), in one call."""
        return list(self._draw("random", shape, parts))

    def normal_parts(self, parts: int, *shape: int) -> list[Array]:
        """``parts`` consecutive standard normal draws of shape (runs, *shape), in one call."""
        return list(self._draw("normal", shape, parts))

    def _draw(self, kind: str, shape: tuple[int, ...], parts: int = 0) -> Array:
        """One draw (runs, *shape), or with ``parts`` > 0 that many consecutive draws stacked
        as (parts, runs, *shape): each part contiguous, the numbers of ``parts`` single draws."""
        k = max(parts, 1)
        out = np.empty((k, self.runs, *shape))
        size = math.prod(shape)
        if not self.block:
            for r, g in enumerate(self.generators):
                for i in range(k):
                    _fill(g, kind, out[i, r])
            return out if parts else out[0]
        state = self._buffers.get(kind)
        if state is None or state[1] + k * size > state[0].shape[1]:
            state = self._refill(kind, state, k * size)
        buffer, start = state
        state[1] = start + k * size
        # contiguous copies: numpy's in-place arithmetic on strided views is several times
        # slower than the copy, and callers work in place on their draws
        view = buffer[:, start : start + k * size].reshape(self.runs, k, size)
        out.reshape(k, self.runs, size)[...] = view.transpose(1, 0, 2)
        return out if parts else out[0]

    def _refill(self, kind: str, state: list[Any] | None, size: int) -> list[Any]:
        """A new buffer: the unused tail of the old one, then fresh numbers of each run's stream."""
        tail = 0 if state is None else state[0].shape[1] - state[1]
        buffer = np.empty((self.runs, max(self.block, size)))
        if state is not None and tail:
            buffer[:, :tail] = state[0][:, state[1] :]
        for g, row in zip(self.generators, buffer, strict=True):
            _fill(g, kind, row[tail:])
        state = [buffer, 0]
        self._buffers[kind] = state
        return state

    def integers(self, low: int, high: int, *shape: int) -> NDArray[np.int64]:
        """Integers in [low, high) of shape (runs, *shape)."""
        return np.stack([g.integers(low, high, size=shape) for g in self.generators])

    def permutations(self, n: int, *shape: int) -> NDArray[np.int64]:
        """Independent random permutations of range(n): shape (runs, *shape, n)."""
        keys = self.random(*shape, n)
        return np.argsort(keys, axis=-1, kind="stable")


def _fill(generator: np.random.Generator, kind: str, out: Array) -> None:
    if kind == "random":
        generator.random(out=out)
    else:
        generator.standard_normal(out=out)
