"""Binary series of a run (curve, best position, path) in the ``results.series`` column."""

from __future__ import annotations

import json
import math
import struct
import zlib
from typing import Any

import numpy as np

from swarmpath.service.store.base import _dumps

_F8 = np.dtype("<f8")  # the arrays' dtype: float64, little-endian

#: Binary series (see encode_series): this prefix, then (header length as uint32 LE, header
#: JSON, the arrays' float64 LE bytes in header order), not compressed: compressing cost more
#: coordinator CPU than writing the bytes (docs/benchmarks.md, coordinator profile).
SERIES_MAGIC = b"SPS2"
#: The earlier form: the same body, zlib-compressed (still read).
SERIES_MAGIC_ZLIB = b"SPS1"
_HEADS: dict[tuple[tuple[str, tuple[int, ...]], ...], bytes] = {}  # header bytes by shapes


def encode_series(series: dict[str, Any]) -> bytes | None:
    """A run's series (curve, best position, path rows) for the ``results.series`` column: the
    arrays as float64 bytes, exact and far cheaper to write than JSON text; None if empty.
    (Rows written before this format hold zlib of it, or zlib(JSON); :func:`decode_series`
    reads all three.)"""
    shapes: list[tuple[str, tuple[int, ...]]] = []
    parts: list[bytes] = []
    for name, value in series.items():
        if value is None:
            continue
        arr = np.asarray(value, dtype="<f8")
        shapes.append((name, arr.shape))
        parts.append(arr.tobytes())
    if not shapes:
        return None
    key = tuple(shapes)
    head = _HEADS.get(key)
    if head is None:
        text = _dumps([[name, list(shape)] for name, shape in shapes]).encode()
        head = len(text).to_bytes(4, "little") + text
        if len(_HEADS) < 4096:
            _HEADS[key] = head
    return SERIES_MAGIC + head + b"".join(parts)


def raw_series(shapes: list[tuple[str, str, list[int]]], raw: bytes) -> bytes | None:
    """The ``results.series`` value of arrays received as ``raw`` (their float64 LE bytes, one
    after the other, named and shaped by ``shapes``: a result frame's ``[name, dtype, shape]``
    declarations): :func:`encode_series` of the same arrays, without making them first."""
    prefix = series_prefix(shapes)
    return None if prefix is None else prefix + raw


def series_prefix(shapes: list[tuple[str, str, list[int]]]) -> bytes | None:
    """What precedes the arrays' bytes in the ``results.series`` value of arrays declared by
    ``shapes`` (see :func:`raw_series`); None when nothing is declared."""
    if not shapes:
        return None
    key = tuple((name, tuple(shape)) for name, _dtype, shape in shapes)
    head = _HEADS.get(key)
    if head is None:
        text = _dumps([[name, list(shape)] for name, shape in key]).encode()
        head = len(text).to_bytes(4, "little") + text
        if len(_HEADS) < 4096:
            _HEADS[key] = head
    return SERIES_MAGIC + head


def decode_series(blob: bytes | None, arrays: tuple[str, ...] = ()) -> dict[str, Any]:
    """The series of a ``results.series`` value as lists (curve: floats, path: [x, y, t] rows);
    those named in ``arrays`` as read-only float64 arrays over ``blob`` (no copy, no list)."""
    if blob is None:
        return {}
    if not blob.startswith(SERIES_MAGIC):
        if blob.startswith(SERIES_MAGIC_ZLIB):
            return decode_series(SERIES_MAGIC + zlib.decompress(blob[len(SERIES_MAGIC_ZLIB):]),
                                 arrays)
        return dict(json.loads(zlib.decompress(blob)))
    out: dict[str, Any] = {}
    for name, offset, count, shape, floats in _layout(blob):
        if name in arrays or floats is None:
            arr = np.frombuffer(blob, _F8, count, offset)  # positional: parsed faster
            if shape is not None:
                arr = arr.reshape(shape)
            out[name] = arr if name in arrays else arr.tolist()
        else:  # a 1-D list (a best position: two floats) without making an array first
            out[name] = list(floats.unpack_from(blob, offset))
    return out


# (name, byte offset, count, shape if not 1-D, its floats' Struct if 1-D) by header
_Layout = tuple[tuple[str, int, int, tuple[int, ...] | None, struct.Struct | None], ...]
_LAYOUTS: dict[bytes, _Layout] = {}
_last: tuple[bytes, _Layout] = (b"-", ())  # the last header and its layout (one assignment)


def _layout(blob: bytes) -> _Layout:
    """Where each array of an ``SPS2`` value starts, parsed once per distinct header: the
    series of a job's runs all share a few headers (the recorder reads thousands per second)."""
    global _last
    last = _last
    if blob.startswith(last[0]):  # the header of the value before (a run of the same cell)
        return last[1]
    end = len(SERIES_MAGIC) + 4 + int.from_bytes(blob[4:8], "little")
    head = blob[:end]
    layout = _LAYOUTS.get(head)
    if layout is None:
        entries, offset = [], end
        for name, shape in json.loads(head[8:]):
            count = math.prod(shape)
            flat = len(shape) == 1
            entries.append((str(name), offset, count,
                            None if flat else tuple(int(n) for n in shape),
                            struct.Struct(f"<{count}d") if flat else None))
            offset += 8 * count
        layout = tuple(entries)
        if len(_LAYOUTS) < 4096:
            _LAYOUTS[head] = layout
    _last = (head, layout)
    return layout
