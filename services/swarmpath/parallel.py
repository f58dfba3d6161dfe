"""Independent tasks in spawned worker processes, with their progress reported to the parent.

Threads share the GIL between numpy calls (two threads gave 1.33x one on the Table 2 study), so
the command line computes independent tasks in processes. Children are started with the *spawn*
method (never forked: no inherited locks or library threads), limit BLAS/OpenMP to one thread each
(one process per core), and ignore Ctrl-C: the parent stops them. ``compute(task, report)`` must
be a module-level function; it calls ``report(n)`` to add ``n`` units of progress, which reach the
parent's ``on_progress`` at most every ``PROGRESS_SECONDS``.

A child is one warm process for all the tasks it gets (imports and per-process caches, such as
the exact optimum of a map, paid once). It imports only what its tasks need: this module lives
outside the ``cli`` package, whose import loads typer and every command (about 0.3 s of CPU per
child), and ``compute`` should too (``swarmpath.plan_runs`` for ``swarmpath plan``).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import queue as queue_module
import signal
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from typing import Any, TypeVar

T = TypeVar("T")
R = TypeVar("R")
Compute = Callable[[T, Callable[[int], None]], R]

PROGRESS_SECONDS = 0.2
#: Most processes a command accepts (--jobs).
MAX_JOBS = 256
_SINGLE_THREADED = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
_progress: Any = None  # in a child: the parent's progress queue (set by _init_child)


def usable_cpus() -> int:
    """CPUs this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def run_tasks(
    compute: Compute[T, R],
    tasks: Sequence[T],
    jobs: int,
    on_progress: Callable[[int], None] | None = None,
    on_done: Callable[[T], None] | None = None,
) -> list[R]:
    """``compute(task, report)`` for every task, results in task order.

    ``jobs`` = 1 computes in this process; more start that many child processes (at most one per
    task). ``on_done(task)`` is called in this process when a task finished. The first task that
    raises stops the others and its exception is raised here.
    """
    with TaskPool(min(jobs, max(len(tasks), 1)) if jobs >= 1 else jobs) as pool:
        return pool.run(compute, tasks, on_progress, on_done)


class TaskPool:
    """Child processes kept for several batches of tasks (:meth:`run`), so that a computation in
    rounds (``swarmpath bench --race``) pays for starting them once. Use it as a context
    manager; ``jobs`` = 1 computes in this process. The children start with the first batch of
    more than one task."""

    def __init__(self, jobs: int):
        if jobs < 1:
            raise ValueError("jobs must be >= 1")
        self.jobs = jobs
        self._pool: ProcessPoolExecutor | None = None
        self._progress: Any = None

    def __enter__(self) -> TaskPool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._progress.close()
            self._pool = None

    def run(
        self,
        compute: Compute[T, R],
        tasks: Sequence[T],
        on_progress: Callable[[int], None] | None = None,
        on_done: Callable[[T], None] | None = None,
    ) -> list[R]:
        """:func:`run_tasks` of one batch on this pool's processes."""
        report = on_progress or _ignore
        if self.jobs == 1 or (self._pool is None and len(tasks) <= 1):
            out = []
            for task in tasks:
                out.append(compute(task, report))
                if on_done is not None:
                    on_done(task)
            return out
        if self._pool is None:
            ctx = multiprocessing.get_context("spawn")
            self._progress = ctx.Queue()
            with _single_threaded_children():
                self._pool = ProcessPoolExecutor(self.jobs, mp_context=ctx,
                                                 initializer=_init_child,
                                                 initargs=(self._progress,))
        pool, progress = self._pool, self._progress
        results: dict[int, R] = {}
        sent = received = 0  # progress put on the queue by the children / taken from it here
        try:
            with _single_threaded_children():
                futures: dict[Future[tuple[R, int, int]], int] = {
                    pool.submit(_child, compute, task): i for i, task in enumerate(tasks)
                }
            pending = set(futures)
            while pending:
                finished, pending = wait(pending, timeout=PROGRESS_SECONDS,
                                         return_when=FIRST_COMPLETED)
                received += _drain(progress, report)
                for future in finished:
                    i = futures[future]
                    results[i], put, rest = future.result()  # a task's exception is raised here
                    sent += put
                    report(rest)
                    if on_done is not None:
                        on_done(tasks[i])
            received += _drain(progress, report, sent - received)  # what is still in flight
        except BaseException:
            _stop(pool)
            self.close()
            raise
        return [results[i] for i in range(len(tasks))]


def _ignore(_n: int) -> None:
    return None


@contextlib.contextmanager
def _single_threaded_children() -> Iterator[None]:
    """Children inherit the environment at spawn: one BLAS/OpenMP thread each."""
    saved = {k: os.environ.get(k) for k in _SINGLE_THREADED}
    for k in _SINGLE_THREADED:
        os.environ.setdefault(k, "1")
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _stop(pool: ProcessPoolExecutor) -> None:
    """Terminate the children now (a failed task or Ctrl-C: nobody wants the other results)."""
    for process in list(getattr(pool, "_processes", {}).values()):
        with contextlib.suppress(Exception):
            process.terminate()


def _drain(progress: Any, report: Callable[[int], None], expect: int = 0) -> int:
    """Report what the queue holds; with ``expect`` > 0 wait (up to 5 s) for that much."""
    got = 0
    while True:
        try:
            n = progress.get(timeout=5.0) if got < expect else progress.get_nowait()
        except queue_module.Empty:
            return got
        got += n
        report(n)


def _init_child(progress: Any) -> None:
    global _progress
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent stops its children
    _progress = progress


def _child(compute: Compute[T, R], task: T) -> tuple[R, int, int]:
    """(result, progress put on the queue, progress not yet reported): the parent reports the
    rest itself, and waits for everything put to arrive before it returns."""
    pending = put = 0
    last = time.monotonic()

    def report(n: int) -> None:
        nonlocal pending, put, last
        pending += n
        now = time.monotonic()
        if now - last >= PROGRESS_SECONDS:
            _progress.put(pending)
            put, pending, last = put + pending, 0, now

    result = compute(task, report)
    return result, put, pending
