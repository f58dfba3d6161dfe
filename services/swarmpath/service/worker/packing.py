"""Results on the wire: one result as a binary record (thinned to fit a message); a lease's
records put as columnar result frames (:mod:`swarmpath.service.result_columns`, protocol 5),
proven once per frame; records packed into record frames (:mod:`swarmpath.service.result_frame`,
protocol 4, still accepted)."""

from __future__ import annotations

import logging
from collections.abc import Sequence
from typing import Any

import numpy as np

from swarmpath.service.protocol import (
    MAX_BODY_BYTES,
    RunResult,
)
from swarmpath.service.result_columns import pack_columns, pack_message
from swarmpath.service.result_frame import RunResultHead, encode_record, pack_frames

log = logging.getLogger("swarmpath.worker")


#: Result frames are cut to stay below this many bytes (the coordinator drops > 1 MB).
BATCH_BYTES = 900_000
#: A single result larger than this has its curve (and path) thinned to fit.
RESULT_BYTES = MAX_BODY_BYTES - 4096


def _scalar(v: Any) -> bool:
    return v is None or isinstance(v, bool | int | float | str)


def fit_result(
    result: RunResult, limit: int = RESULT_BYTES, capability: str | None = None
) -> bytes:
    """The result as a frame record, its curve (and path) thinned to evenly spaced samples, first
    and last kept, when it would not fit in one message (``metrics.curve_stride`` records the
    stride); with ``capability`` (the lease's secret) it carries its proof."""
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
    head = RunResultHead(
        lease_id=result.lease_id, job_id=result.job_id, cell=result.cell, run=result.run,
        worker=result.worker, status=result.status, failure=result.failure,
        seconds=result.seconds, cpu_seconds=result.cpu_seconds, metrics=result.metrics,
    )
    arrays = {"curve": result.curve, "best_position": result.best_position, "path": result.path}
    if result.path is not None and not result.path:
        arrays["path"] = np.zeros((0, 3))
    return encode_record(head, {k: np.asarray(v, dtype="<f8") for k, v in arrays.items()
                                if v is not None}, capability)


def _thin(values: Sequence[Any], stride: int) -> list[Any]:
    out = list(values[::stride])
    if (len(values) - 1) % stride:
        out.append(values[-1])
    return out


def pack_batches(worker: str, results: Sequence[bytes], limit: int = BATCH_BYTES) -> list[bytes]:
    """Result frames from records (:func:`fit_result`), each at most ``limit`` bytes when
    possible."""
    return pack_frames(worker, results, limit)


def pack_lease_columns(worker: str, results: Sequence[tuple[str, str, bytes]],
                       limit: int = BATCH_BYTES) -> list[bytes]:
    """Messages of columnar result frames of (lease id, its capability, record) triples: one
    lease per frame, proven with the lease's capability, frames back to back in messages of at
    most about ``limit`` bytes."""
    by_lease: dict[str, tuple[str, list[bytes]]] = {}
    for lease_id, capability, data in results:
        by_lease.setdefault(lease_id, (capability, []))[1].append(data)
    frames = [frame for capability, records in by_lease.values()
              for frame in pack_columns(worker, capability or None, records, limit)]
    return pack_message(frames, limit)
