"""Calls into a child process bounded in memory and time: what the coordinator parses uploads
with, so that no upload can hold its GIL, stall its event loop or grow its memory.

:class:`BoundedRunner` keeps one child (multiprocessing *spawn*; started at the first call, again
after a kill) and makes one call at a time: ``runner.call(fn, *args)`` pickles a module-level
function and its arguments over a pipe, the child runs it under ``RLIMIT_AS`` = its own address
space once warmed up + ``memory_bytes`` (what a call may add) and the parent waits at most
``seconds``. A call over its time is SIGKILLed with its child (:class:`CallTimedOut`); one that
runs out of memory raises :class:`CallOutOfMemory`; a child that dies (a decoder crashing)
raises :class:`CallDied`; an exception of the function is raised again in the parent. ``warm``
(a module-level function: the imports) runs in each new child before its first call, outside
the call's time and before the memory bound. At most ``max_waiting`` calls wait for the child;
more raise :class:`RunnerBusy`. A child whose parent died exits (its pipe closes; a watch thread
checks the parent's pid)."""

from __future__ import annotations

import errno
import os
import pickle
import signal
import threading
import time
from collections.abc import Callable
from typing import Any


class BoundedCallError(RuntimeError):
    """A call that did not return (subclasses say why)."""


class CallTimedOut(BoundedCallError):
    pass


class CallOutOfMemory(BoundedCallError):
    pass


class CallDied(BoundedCallError):
    pass


class RunnerBusy(BoundedCallError):
    pass


def _watch_parent(parent: int) -> None:
    while True:
        time.sleep(0.5)
        if os.getppid() != parent:
            os._exit(3)


def _address_space() -> int:
    """This process's virtual memory size (bytes): what RLIMIT_AS is compared with."""
    with open("/proc/self/statm", encoding="ascii") as f:
        return int(f.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")


def _child(conn: Any, memory_bytes: int, parent: int, warm: Callable[[], Any] | None) -> None:
    """The child: ``warm()`` then ``("ready",)`` out; calls in, ``("ok", value)`` /
    ``("raised", exc)`` / ``("memory", text)`` out."""
    import resource

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides when this ends
    threading.Thread(target=_watch_parent, args=(parent,), daemon=True).start()
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")  # no thread pools reserving address space
    # pickled before the limit: with the address space used up, even pickling a short reply can
    # raise MemoryError, and the parent would only see a child that died
    out_of_memory = pickle.dumps(("memory", "out of memory"))
    # our own imports first, unbounded: how much address space numpy/scipy/numba reserve
    # differs by machine and install (a fixed limit that held on one failed at import on
    # another); the bound is on what a call adds to the warmed-up child
    if warm is not None:
        warm()
    if memory_bytes > 0:
        limit = _address_space() + memory_bytes
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    conn.send(("ready", None))
    while True:
        try:
            message = conn.recv()
        except (EOFError, OSError):
            return
        if message is None:
            return
        try:
            fn, args = message
            reply: tuple[Any, ...] = ("ok", fn(*args))
        except MemoryError as exc:
            reply = ("memory", str(exc))
        except OSError as exc:  # ENOMEM from a system call (an mmap, a listdir) at the limit
            reply = ("memory", str(exc)) if exc.errno == errno.ENOMEM else ("raised", exc)
        except Exception as exc:
            reply = ("raised", exc)
        try:
            conn.send(reply)
        except MemoryError:
            conn.send_bytes(out_of_memory)
        except Exception as exc:  # an unpicklable exception or value
            conn.send(("raised", RuntimeError(f"{type(exc).__name__}: {exc}")))


class BoundedRunner:
    """See the module docstring."""

    #: a child has this long to start and warm up (imports), besides the call's own time
    START_SECONDS = 120.0

    def __init__(self, memory_bytes: int, seconds: float, max_waiting: int = 8,
                 name: str = "swarmpath-bounded", warm: Callable[[], Any] | None = None):
        self.memory_bytes = int(memory_bytes)
        self.seconds = float(seconds)
        self.warm = warm
        self.max_waiting = int(max_waiting)
        self.name = name
        self._lock = threading.Lock()
        self._waiting = 0
        self._count_lock = threading.Lock()
        self._proc: Any = None
        self._conn: Any = None
        self._closed = False

    def _start(self) -> None:
        import multiprocessing

        ctx = multiprocessing.get_context("spawn")
        parent_conn, child_conn = ctx.Pipe()
        self._proc = ctx.Process(
            target=_child, args=(child_conn, self.memory_bytes, os.getpid(), self.warm),
            name=self.name, daemon=True)
        self._proc.start()
        child_conn.close()
        self._conn = parent_conn
        try:  # the call's time starts once the child is ready
            reply = parent_conn.recv() if parent_conn.poll(self.START_SECONDS) else None
        except (EOFError, OSError):
            reply = ("died", None)
        if reply is None or reply[0] != "ready":
            code = self._kill()
            if reply is not None and reply[0] == "memory":
                raise CallOutOfMemory(f"over {self.memory_bytes / 2**20:,.0f} MiB of memory "
                                      "(starting)")
            raise CallDied(f"the child process did not start (exit code {code})")

    def _kill(self) -> int | None:
        proc, self._proc = self._proc, None
        if self._conn is not None:
            self._conn.close()
            self._conn = None
        if proc is None:
            return None
        if proc.is_alive():
            proc.kill()
        proc.join(5.0)
        return proc.exitcode  # type: ignore[no-any-return]

    def call(self, fn: Callable[..., Any], *args: Any) -> Any:
        with self._count_lock:
            if self._waiting >= self.max_waiting:
                raise RunnerBusy(f"{self._waiting} calls are waiting already")
            self._waiting += 1
        try:
            with self._lock:
                return self._call(fn, args)
        finally:
            with self._count_lock:
                self._waiting -= 1

    def _call(self, fn: Callable[..., Any], args: tuple[Any, ...]) -> Any:
        if self._closed:
            raise CallDied("the runner is closed")
        if self._proc is None or not self._proc.is_alive():
            self._kill()
            self._start()
        try:
            self._conn.send((fn, args))
            ready = self._conn.poll(self.seconds)
            reply = self._conn.recv() if ready else None
        except (EOFError, OSError):
            code = self._kill()
            raise CallDied(f"the child process died (exit code {code})") from None
        if reply is None:
            self._kill()
            raise CallTimedOut(f"no answer within {self.seconds:g} s")
        kind, value = reply
        if kind == "ok":
            return value
        if kind == "memory":
            self._kill()  # a fresh child: nothing half-built stays in memory
            raise CallOutOfMemory(f"over {self.memory_bytes / 2**20:,.0f} MiB of memory")
        raise value

    def close(self) -> None:
        """Stop the child (at once if a call is still running)."""
        self._closed = True
        idle = self._lock.acquire(timeout=1.0)
        try:
            if idle and self._conn is not None:
                try:
                    self._conn.send(None)
                    self._proc.join(2.0)
                except (OSError, ValueError, AttributeError):
                    pass
            self._kill()
        finally:
            if idle:
                self._lock.release()
