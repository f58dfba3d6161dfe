"""One run's :class:`~swarmpath.optimizers.streams.RunStreams`, emulated inside compiled code.

A stream is the tuple ``(rng, buf, meta)``: the run's ``numpy.random.Generator`` (the one
``run_generator(seed, r)`` returns), a (2, capacity) float64 buffer with one row per kind
(:data:`RANDOM`, :data:`NORMAL`) and an int64 (2, 2) array holding, per kind, the position of the
next unused number and the width of the buffered block (-1: nothing buffered yet).

:func:`take` reserves ``size`` consecutive numbers of one kind and returns the offset of the first
in ``buf[kind]``, refilling exactly when and as ``RunStreams._draw``/``_refill`` do: when the draw
does not fit in the rest of the block, the unused tail moves to the front and fresh numbers of
that kind are drawn from the generator up to ``max(BLOCK, size)``. A draw of ``k`` parts of
``size`` numbers (``random_parts(k, ...)``) is one :func:`take` of ``k * size``: part ``i`` is
the slice ``[offset + i * size, offset + (i + 1) * size)``. The generator is therefore called in
the same order with the same sizes as by the numpy reference, so every number is the same.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from swarmpath.optimizers.streams import BLOCK

RANDOM = 0
NORMAL = 1


@njit(cache=True)
def open_stream(rng, capacity):
    """The stream of one run: ``capacity`` is the largest single draw the kernel makes."""
    buf = np.empty((2, max(BLOCK, capacity)))
    meta = np.zeros((2, 2), dtype=np.int64)
    meta[0, 1] = -1
    meta[1, 1] = -1
    return rng, buf, meta


@njit(cache=True)
def _refill(stream, kind, size):
    rng, buf, meta = stream
    position = meta[kind, 0]
    width = meta[kind, 1]
    tail = 0 if width < 0 else width - position
    new = max(BLOCK, size)
    if new > buf.shape[1]:
        raise ValueError("a draw larger than the stream's capacity")
    row = buf[kind]
    for j in range(tail):  # forward copy: the destination starts before the source
        row[j] = row[position + j]
    if kind == RANDOM:
        row[tail:new] = rng.random(new - tail)
    else:
        row[tail:new] = rng.standard_normal(new - tail)
    meta[kind, 0] = 0
    meta[kind, 1] = new


@njit(cache=True)
def take(stream, kind, size):
    """Reserve ``size`` numbers of ``kind``: their offset in ``stream[1][kind]``."""
    meta = stream[2]
    if meta[kind, 1] < 0 or meta[kind, 0] + size > meta[kind, 1]:
        _refill(stream, kind, size)
    start = meta[kind, 0]
    meta[kind, 0] = start + size
    return start


@njit(cache=True)
def random_into(stream, out):
    """Fill the contiguous array ``out`` (any shape) with the next uniforms, in C order."""
    flat = out.reshape(out.size)
    start = take(stream, RANDOM, flat.size)
    row = stream[1][RANDOM]
    for j in range(flat.size):
        flat[j] = row[start + j]


@njit(cache=True)
def normal_into(stream, out):
    """Fill the contiguous array ``out`` with the next standard normals, in C order."""
    flat = out.reshape(out.size)
    start = take(stream, NORMAL, flat.size)
    row = stream[1][NORMAL]
    for j in range(flat.size):
        flat[j] = row[start + j]
