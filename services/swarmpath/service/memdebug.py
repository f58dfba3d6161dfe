"""A debugging hook for the coordinator's memory: with ``SWARMPATH_TRACEMALLOC=DIR`` set, the
process traces its Python allocations (``tracemalloc``, 10 frames) and writes a snapshot to
``DIR/<n>-<job id>.tracemalloc`` each time a job ends, and to ``DIR/<n>-signal.tracemalloc``
each time it receives SIGUSR1 (a snapshot in the middle of a job: ``kill -USR1 PID``). Compare
two with ``tracemalloc.Snapshot.load(a).compare_to(tracemalloc.Snapshot.load(b), "traceback")``.
Off (and free, SIGUSR1 untouched) without the variable. Native allocations (SQLite, Zenoh, the
allocator's free lists) are not traced: /proc/PID/status tells them apart (scripts/bench/farm.py
reports the anonymous and file-backed resident memory over the job)."""

from __future__ import annotations

import os
import signal
import threading
import tracemalloc
from pathlib import Path
from types import FrameType

ENV = "SWARMPATH_TRACEMALLOC"
_count = [0]


def start() -> None:
    if os.environ.get(ENV) and not tracemalloc.is_tracing():
        tracemalloc.start(10)


def _on_signal(_signum: int, _frame: FrameType | None) -> None:
    dump("signal")


def install_signal() -> None:
    """SIGUSR1 dumps a snapshot (only with the variable set; a signal handler can only be set
    from the main thread, where this module is first imported by ``swarmpath coordinator``:
    the coordinator itself is built in a worker thread)."""
    if os.environ.get(ENV) and threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGUSR1, _on_signal)


def dump(label: str) -> None:
    where = os.environ.get(ENV)
    if not where or not tracemalloc.is_tracing():
        return
    Path(where).mkdir(parents=True, exist_ok=True)
    _count[0] += 1
    tracemalloc.take_snapshot().dump(str(Path(where) / f"{_count[0]:03d}-{label}.tracemalloc"))


install_signal()
