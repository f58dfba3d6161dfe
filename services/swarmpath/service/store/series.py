"""Binary series of a run (curve, best position, path) in the ``results.series`` column."""

from __future__ import annotations

import json
import math
import zlib
from typing import Any

from swarmpath.service.store.base import _dumps

#: Binary series (see encode_series): this prefix, then zlib of (header length as uint32 LE,
#: header JSON, the arrays' float64 LE bytes in header order).
SERIES_MAGIC = b"SPS1"


def encode_series(series: dict[str, Any]) -> bytes | None:
    """A run's series (curve, best position, path rows) for the ``results.series`` column: the
    arrays as float64 bytes, exact and about 10x cheaper to write than JSON text; None if
    empty. (Rows written before this format hold zlib(JSON); :func:`decode_series` reads both.)"""
    import numpy as np

    header: list[list[Any]] = []
    parts: list[bytes] = []
    for name, value in series.items():
        if value is None:
            continue
        arr = np.asarray(value, dtype="<f8")
        header.append([name, list(arr.shape)])
        parts.append(arr.tobytes())
    if not header:
        return None
    head = _dumps(header).encode()
    body = len(head).to_bytes(4, "little") + head + b"".join(parts)
    return SERIES_MAGIC + zlib.compress(body, 1)


def decode_series(blob: bytes | None) -> dict[str, Any]:
    """The series of a ``results.series`` value as lists (curve: floats, path: [x, y, t] rows)."""
    if blob is None:
        return {}
    if not blob.startswith(SERIES_MAGIC):
        return dict(json.loads(zlib.decompress(blob)))
    import numpy as np

    body = zlib.decompress(blob[len(SERIES_MAGIC):])
    n = int.from_bytes(body[:4], "little")
    offset = 4 + n
    out: dict[str, Any] = {}
    for name, shape in json.loads(body[4:offset]):
        count = math.prod(shape)
        arr = np.frombuffer(body, dtype="<f8", count=count, offset=offset).reshape(shape)
        offset += 8 * count
        out[name] = arr.tolist()
    return out
