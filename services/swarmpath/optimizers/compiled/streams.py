"""One run's :class:`~swarmpath.optimizers.streams.RunStreams`, emulated inside compiled code.

A stream is the tuple ``(rng, buf, meta)``: the run's ``numpy.random.Generator`` (the one
``run_generator(seed, r)`` returns), a float64 buffer with one row per kind (:data:`RANDOM`,
:data:`NORMAL`) and int64 bookkeeping (:func:`open_stream`).

:func:`take` reserves ``size`` consecutive numbers of one kind and returns the offset of the first
in ``buf[kind]``. A draw of ``k`` parts of ``size`` numbers (``random_parts(k, ...)``) is one
:func:`take` of ``k * size``: part ``i`` is the slice ``[offset + i * size, offset + (i + 1) *
size)``. Two ways of filling give the numbers of the reference:

* ``open_stream(rng, capacity, True)`` (buffered), for a kernel that draws both kinds (FDO):
  where the refills of ``RunStreams._draw``/``_refill`` fall decides which of the generator's
  numbers are uniforms and which normals, so the stream refills exactly when and as they do:
  when a draw does not fit in the rest of the block of its kind, the unused tail moves to the
  front and the block is completed with fresh numbers up to ``max(BLOCK, size)``. The fresh
  numbers are generated lazily, when a take first reaches them, which changes no number as long
  as no other block was refilled in between: before any refill the newest block is completed
  (that is the generator order of the reference). A take of numbers not generated yet writes
  them to the front of the row (everything before them was used), so a kernel reads its numbers
  from the same few kilobytes, in the L1 cache, right after they were written, instead of
  walking a 64 KiB block filled long before: FDO ran 10% slower with eager blocks
  (scripts/bench/kernels.py).
* ``open_stream(rng, capacity, False)`` (direct), for a kernel that draws one kind only: every
  ``take`` draws its ``size`` numbers from the generator into the front of the buffer (offset
  0). A generator that only ever gives one kind gives the same sequence whatever blocks it is
  asked for, so these are the reference's numbers too, in a buffer of ``capacity`` numbers.
  A take of the other kind afterwards raises ValueError (it would not be the reference's).

Either way a take may move or overwrite the numbers of earlier takes of its kind: use them
before the next take (an evaluation of a noisy function takes too).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from swarmpath.optimizers.compiled.norefcount import NO_REFCOUNT
from swarmpath.optimizers.streams import BLOCK

RANDOM = 0
NORMAL = 1
# meta: per kind k, at 3 k: the position of the next unused number, the width of the block
# (-1: none yet) and how much of it is generated; then the kind whose block is the newest (-1:
# none), and 1 for a direct stream.
_POS, _WIDTH, _MADE = 0, 1, 2
_NEWEST = 6
_DIRECT = 7


@njit(cache=True)
def open_stream(rng, capacity, mixed):
    """The stream of one run: ``capacity`` is the largest single draw the kernel makes;
    ``mixed``: whether it draws both kinds (buffered) or only one (direct)."""
    buf = np.empty((2, max(BLOCK, capacity) if mixed else capacity))
    meta = np.zeros(8, dtype=np.int64)
    meta[_WIDTH] = -1
    meta[3 + _WIDTH] = -1
    meta[_NEWEST] = -1
    meta[_DIRECT] = 0 if mixed else 1
    return rng, buf, meta


@njit(cache=True, **NO_REFCOUNT)
def _fill(rng, kind, row, start, stop):
    """row[start:stop] <- fresh numbers of ``kind``, one generator call each (what the
    generator's own fill does, without an array to allocate and copy)."""
    if kind == RANDOM:
        for j in range(start, stop):
            row[j] = rng.random()
    else:
        for j in range(start, stop):
            row[j] = rng.standard_normal()


@njit(cache=True, **NO_REFCOUNT)
def _refill(stream, kind, size):
    rng, buf, meta = stream
    new = max(BLOCK, size)
    if new > buf.shape[1]:
        raise ValueError("a draw larger than the stream's capacity")
    newest = meta[_NEWEST]
    if newest >= 0:  # complete the newest block: the reference generated it before this one
        k = 3 * newest
        _fill(rng, newest, buf[newest], meta[k + _MADE], meta[k + _WIDTH])
        meta[k + _MADE] = meta[k + _WIDTH]
    k = 3 * kind
    position = meta[k + _POS]
    tail = 0 if meta[k + _WIDTH] < 0 else meta[k + _WIDTH] - position
    row = buf[kind]
    for j in range(tail):  # forward copy: the destination starts before the source
        row[j] = row[position + j]
    meta[k + _POS] = 0
    meta[k + _WIDTH] = new
    meta[k + _MADE] = tail
    meta[_NEWEST] = kind


@njit(cache=True, **NO_REFCOUNT)
def take(stream, kind, size):
    """Reserve ``size`` numbers of ``kind``: their offset in ``stream[1][kind]``."""
    rng, buf, meta = stream
    if meta[_DIRECT]:
        if size > buf.shape[1]:
            raise ValueError("a draw larger than the stream's capacity")
        if meta[3 * (1 - kind) + _POS]:
            raise ValueError("a direct stream draws one kind of numbers only")
        meta[3 * kind + _POS] = 1
        _fill(rng, kind, buf[kind], 0, size)
        return 0
    k = 3 * kind
    if meta[k + _WIDTH] < 0 or meta[k + _POS] + size > meta[k + _WIDTH]:
        _refill(stream, kind, size)
    start = meta[k + _POS]
    stop = start + size
    made = meta[k + _MADE]
    meta[k + _POS] = stop
    if stop <= made:  # generated already (a completed block)
        return start
    meta[k + _MADE] = stop
    if start == made:  # none of them: generated into the front, all before it was used
        _fill(rng, kind, buf[kind], 0, size)
        return 0
    _fill(rng, kind, buf[kind], made, stop)  # the rest of a tail carried over
    return start


@njit(cache=True, **NO_REFCOUNT)
def random_into(stream, out):
    """Fill the contiguous array ``out`` (any shape) with the next uniforms, in C order."""
    flat = out.reshape(out.size)
    start = take(stream, RANDOM, flat.size)
    row = stream[1][RANDOM]
    for j in range(flat.size):
        flat[j] = row[start + j]


@njit(cache=True, **NO_REFCOUNT)
def normal_into(stream, out):
    """Fill the contiguous array ``out`` with the next standard normals, in C order."""
    flat = out.reshape(out.size)
    start = take(stream, NORMAL, flat.size)
    row = stream[1][NORMAL]
    for j in range(flat.size):
        flat[j] = row[start + j]
