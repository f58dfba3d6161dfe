"""Results on the wire: one result thinned to fit a message, results packed into batches."""

from __future__ import annotations

import json
import logging
from collections.abc import Sequence
from typing import Any

from swarmpath.service.capability import result_proof
from swarmpath.service.protocol import (
    MAX_BODY_BYTES,
    RunResult,
    encode,
)

log = logging.getLogger("swarmpath.worker")


#: Result batches are cut to stay below this many bytes of JSON (the coordinator drops > 1 MB).
BATCH_BYTES = 512_000
#: A single result larger than this has its curve (and path) thinned to fit.
RESULT_BYTES = MAX_BODY_BYTES - 4096


def _scalar(v: Any) -> bool:
    return v is None or isinstance(v, bool | int | float | str)


def fit_result(
    result: RunResult, limit: int = RESULT_BYTES, capability: str | None = None
) -> bytes:
    """The encoded result, its curve (and path) thinned to evenly spaced samples, first and last
    kept, when it would not fit in one message (``metrics.curve_stride`` records the stride);
    with ``capability`` (the lease's secret) it carries its proof."""
    data = _encode(result, capability)
    stride = 1
    while len(data) > limit and stride < 1 << 20:
        stride *= 2
        changes: dict[str, Any] = {}
        if result.curve:
            changes["curve"] = _thin(result.curve, stride)
            changes["metrics"] = {**result.metrics, "curve_stride": stride}
        if result.path and len(result.path) > 2:
            changes["path"] = _thin(result.path, stride)
        if not changes:
            break
        data = _encode(result.model_copy(update=changes), capability)
    return data


def _encode(result: RunResult, capability: str | None) -> bytes:
    if capability:
        result = result.model_copy(update={"proof": result_proof(capability, result)})
    return encode(result)


def _thin(values: Sequence[Any], stride: int) -> list[Any]:
    out = list(values[::stride])
    if (len(values) - 1) % stride:
        out.append(values[-1])
    return out


def pack_batches(worker: str, results: Sequence[bytes], limit: int = BATCH_BYTES) -> list[bytes]:
    """ResultBatch payloads from encoded results, each at most ``limit`` bytes when possible."""
    head = b'{"worker":' + json.dumps(worker).encode() + b',"results":['
    out: list[bytes] = []
    chunk: list[bytes] = []
    size = len(head) + 2
    for r in results:
        if chunk and size + len(r) + 1 > limit:
            out.append(head + b",".join(chunk) + b"]}")
            chunk, size = [], len(head) + 2
        chunk.append(r)
        size += len(r) + 1
    if chunk:
        out.append(head + b",".join(chunk) + b"]}")
    return out
