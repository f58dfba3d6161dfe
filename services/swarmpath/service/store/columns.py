"""Reported runs as the coordinator stores them: :class:`ResultColumns`, the results of one lease
(worker, job, cell) as columns, one entry per run.

A columnar result frame (:mod:`swarmpath.service.result_columns`) becomes one without a Python
object per run: its series are views of the payload and each run's stored ``results.series``
value is cut from one buffer made for the whole frame. Results that arrive one by one (a
protocol-4 record frame or a JSON ``ResultBatch``, as :class:`~swarmpath.service.incoming.Incoming`)
are grouped into columns by :func:`from_incoming`, so the store, the acks and the dashboard have
one path. ``capability`` is the lease secret the results were proven with (None: unproven, all
stale); the store accepts them only when that is the secret it holds for the lease.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from swarmpath.service.incoming import Incoming
from swarmpath.service.result_columns import ColumnsFrame, ColumnsHead, column_arrays
from swarmpath.service.store.series import encode_series, series_prefix


@dataclass(slots=True, eq=False)
class ResultColumns:
    """One lease's reported runs as columns (see the module docstring)."""

    lease_id: str
    job_id: str
    cell: str
    worker: str
    capability: str | None
    runs: list[int]
    status: list[str]
    failure: list[str | None]
    seconds: list[float]
    metrics: list[dict[str, Any]]
    #: each run's ``results.series`` value (bytes-like) or None
    series: Sequence[Any] = field(default_factory=list, repr=False)
    #: each run's arrays by name (a sequence per name, None where a run has none)
    arrays: dict[str, Sequence[Any]] = field(default_factory=dict, repr=False)
    #: each run's CPU seconds (None: not measured); empty: none known (an older worker's frame)
    cpu_seconds: Sequence[float | None] = field(default_factory=list, kw_only=True)

    def array(self, name: str, k: int) -> np.ndarray | None:
        values = self.arrays.get(name)
        return None if values is None else values[k]

    def cpu(self, k: int) -> float | None:
        """Run ``k``'s CPU seconds, None when not measured."""
        return self.cpu_seconds[k] if k < len(self.cpu_seconds) else None


def unproven(head: ColumnsHead) -> ResultColumns:
    """A frame that proved nothing: its identity only (for its ack), never stored."""
    n = len(head.runs)
    return ResultColumns(head.lease_id, head.job_id, head.cell, head.worker, None,
                         list(head.runs), list(head.status), [None] * n, [0.0] * n,
                         [{}] * n)


def from_frame(frame: ColumnsFrame, capability: str) -> ResultColumns:
    """A proven frame's columns; its series are views of the payload."""
    h = frame.head
    series, arrays = _series(frame)
    return ResultColumns(h.lease_id, h.job_id, h.cell, h.worker, capability, h.runs, h.status,
                         h.failure, h.seconds, h.metrics, series, arrays,
                         cpu_seconds=h.cpu_seconds or [])


def _series(frame: ColumnsFrame) -> tuple[Sequence[Any], dict[str, Sequence[Any]]]:
    """Each run's stored series and arrays. When every run has every declared array with the
    same rows (a lease's runs normally do), the stored values are rows of one byte matrix (the
    SPS2 prefix, then each array's bytes) and the arrays rows of views of the block."""
    h = frame.head
    n = len(h.runs)
    if not h.arrays:
        return [None] * n, {}
    block = frame.block
    uniform = all(min(a.rows) == max(a.rows) >= 0 for a in h.arrays)
    arrays: dict[str, Sequence[Any]] = {}
    offset = 0
    if uniform:
        shapes = []
        parts = []
        for a in h.arrays:
            rows = a.rows[0]
            shape = [rows] if a.name != "path" else [rows, 3]
            size = rows * (3 if a.name == "path" else 1)
            values = block[offset:offset + n * size].reshape(n, *shape)
            offset += n * size
            arrays[a.name] = values
            shapes.append((a.name, "<f8", shape))
            parts.append(values.reshape(n, size).view(np.uint8))
        prefix = series_prefix(shapes)
        assert prefix is not None
        width = len(prefix) + sum(p.shape[1] for p in parts)
        matrix = np.empty((n, width), dtype=np.uint8)
        matrix[:, :len(prefix)] = np.frombuffer(prefix, dtype=np.uint8)
        col = len(prefix)
        for p in parts:
            matrix[:, col:col + p.shape[1]] = p
            col += p.shape[1]
        flat = memoryview(matrix.reshape(-1))
        return [flat[i * width:(i + 1) * width] for i in range(n)], arrays
    arrays.update(column_arrays(frame))
    series = [encode_series({name: arrays[name][k] for name in arrays}) for k in range(n)]
    return series, arrays


def from_incoming(items: Sequence[Incoming]) -> tuple[list[ResultColumns], list[list[int]]]:
    """Results that came one by one, grouped into columns by (lease, job, cell, worker,
    capability), in the order each group first appears; also each group's indexes in
    ``items``."""
    groups: dict[tuple[Any, ...], tuple[ResultColumns, list[int]]] = {}
    for i, r in enumerate(items):
        key = (r.lease_id, r.job_id, r.cell, r.worker, r.capability)
        got = groups.get(key)
        if got is None:
            cols = ResultColumns(r.lease_id, r.job_id, r.cell, r.worker, r.capability,
                                 [], [], [], [], [], [], {"curve": [], "best_position": [],
                                                          "path": []}, cpu_seconds=[])
            got = groups[key] = (cols, [])
        cols, indexes = got
        indexes.append(i)
        cols.runs.append(r.run)
        cols.status.append(r.status)
        cols.failure.append(r.failure)
        cols.seconds.append(r.seconds)
        cols.cpu_seconds.append(r.cpu_seconds)  # type: ignore[attr-defined]
        cols.metrics.append(r.metrics)
        blob = r.stored_series
        if blob is None and r.capability is not None:
            blob = encode_series({"curve": r.curve, "best_position": r.best_position,
                                  "path": r.path})
        cols.series.append(blob)  # type: ignore[attr-defined]
        for name in ("curve", "best_position", "path"):
            cols.arrays[name].append(getattr(r, name))  # type: ignore[attr-defined]
    return [g[0] for g in groups.values()], [g[1] for g in groups.values()]
