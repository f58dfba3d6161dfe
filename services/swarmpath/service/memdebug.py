"""A debugging hook for the coordinator's memory: with ``SWARMPATH_TRACEMALLOC=DIR`` set, the
process traces its Python allocations (``tracemalloc``, 10 frames) and writes a snapshot to
``DIR/<n>-<job id>.tracemalloc`` each time a job ends; compare two with
``tracemalloc.Snapshot.load(a).compare_to(tracemalloc.Snapshot.load(b), "traceback")``. Off
(and free) without the variable. Native allocations (SQLite, Zenoh, zstd) are not traced."""

from __future__ import annotations

import os
import tracemalloc
from pathlib import Path

ENV = "SWARMPATH_TRACEMALLOC"
_count = [0]


def start() -> None:
    if os.environ.get(ENV) and not tracemalloc.is_tracing():
        tracemalloc.start(10)


def dump(job_id: str) -> None:
    where = os.environ.get(ENV)
    if not where or not tracemalloc.is_tracing():
        return
    Path(where).mkdir(parents=True, exist_ok=True)
    _count[0] += 1
    tracemalloc.take_snapshot().dump(str(Path(where) / f"{_count[0]:03d}-{job_id}.tracemalloc"))
