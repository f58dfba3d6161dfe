"""The MCAP recorder in its own process, following the store: :class:`RecorderProcess`.

Writing the MCAP (JSON of every result and curve, compressed chunks) was the largest part of the
coordinator's CPU per run (docs/benchmarks.md, coordinator profile). The files are a view of the
SQLite store (:mod:`swarmpath.service.recorder`), so another process can write them: it opens the
same store (WAL: its reads never block the coordinator's writes), and whenever the coordinator
says that a job has new results (:meth:`RecorderProcess.poke`, one small pipe message per result
group), it reads the rows after the last one it wrote and hands them to the job's
:class:`~swarmpath.service.recorder.job.JobRecorder`, exactly as a rebuild from the store does:
the same records, in the same (acceptance) order, so the file has the same content as one
written in the coordinator. It also catches up every open job once a second, flushes on the
recorders' timer, and finishes a job's file when the coordinator asks (:meth:`finish`, which
waits for the answer). Durability is the store's: an acknowledged result is committed before
any poke, and a recorder that dies is restarted, rebuilding its open files from the store.

The coordinator side has the methods of :class:`~swarmpath.service.recorder.Recorders` that the
coordinator uses (``ready``, ``path``, ``finish``, ``tick``, ``recover``, ``close``) plus
:meth:`poke`; ``follows_store`` tells them apart.
"""

from __future__ import annotations

import fcntl
import logging
import multiprocessing
import os
import threading
import time
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

from swarmpath.service.recorder.common import chunk_compression, final_path, no_room

log = logging.getLogger("swarmpath.recorder")

CATCH_UP_SECONDS = 1.0  # every open job is caught up at least this often
FULL_RETRY_SECONDS = 5.0  # a job's file that hit a full disk is tried again this much later
REPLY_SECONDS = 600.0  # a finish or recover (a rebuild of a large job) may take this long


class RecorderProcess:
    """The coordinator's handle on the recorder process (see the module docstring)."""

    follows_store = True

    def __init__(self, data_dir: Path | str, synchronous: str = "FULL"):
        self.data_dir = Path(data_dir)
        chunk_compression()  # a bad setting fails here, naming it, not in the other process
        self.synchronous = synchronous
        self._lock = threading.Lock()
        self._ctx = multiprocessing.get_context("spawn")
        self._proc: Any = None
        self._conn: Connection | None = None
        self._closed = False
        self._start()

    def _start(self, recover: bool = False) -> None:
        here, there = self._ctx.Pipe()
        self._proc = self._ctx.Process(
            target=serve, args=(str(self.data_dir), self.synchronous, there, recover),
            name="swarmpath-recorder", daemon=True)
        self._proc.start()
        there.close()
        self._conn = here

    def _alive(self) -> Connection:
        """The pipe to a live recorder (restarted when it died; it rebuilds from the store)."""
        if self._proc is None or not self._proc.is_alive():
            log.error("the recorder process is gone (exit code %s): restarting it",
                      None if self._proc is None else self._proc.exitcode)
            self._start(recover=True)
        assert self._conn is not None
        return self._conn

    def _call(self, *msg: Any) -> Any:
        with self._lock:
            conn = self._alive()
            conn.send(msg)
            if not conn.poll(REPLY_SECONDS):
                raise TimeoutError(f"the recorder did not answer {msg[0]!r} within "
                                   f"{REPLY_SECONDS:.0f} s")
            ok, value = conn.recv()
        if not ok:
            raise RuntimeError(f"recorder: {value}")
        return value

    # -------------------------------------------------------------------- the Recorders API
    def path(self, job_id: str) -> Path:
        return final_path(self.data_dir, job_id)

    def ready(self, job_id: str) -> bool:
        return self.path(job_id).exists()

    def poke(self, job_id: str, platforms: dict[str, dict[str, str]] | None = None) -> None:
        """The job has new results in the store (no answer is awaited); ``platforms``: the
        numeric platform of the workers that sent them (worker id -> platform)."""
        if self._closed:
            return
        with self._lock:
            try:
                self._alive().send(("poke", job_id, platforms or {}))
            except (OSError, ValueError):  # a broken pipe: the next call restarts it
                log.warning("poking the recorder about job %s failed", job_id)

    def finish(self, job_id: str) -> Path:
        return Path(self._call("finish", job_id))

    def recover(self) -> list[str]:
        return list(self._call("recover"))

    def tick(self) -> int:
        """The recorder flushes on its own timer; this only restarts it when it died."""
        if not self._closed:
            with self._lock:
                self._alive()
        return 0

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        try:
            if self._proc is not None and self._proc.is_alive():
                self._call("close")
        except Exception:
            log.exception("closing the recorder failed")
        if self._proc is not None:
            self._proc.join(10)
            if self._proc.is_alive():
                self._proc.kill()
        if self._conn is not None:
            self._conn.close()


# ------------------------------------------------------------------------ the other process
def serve(data_dir: str, synchronous: str, conn: Connection, recover: bool = False) -> None:
    """The recorder process: answer the coordinator's messages until ``close`` (``recover``: a
    restart; first rebuild what the previous recorder left)."""
    from swarmpath.service.recorder.common import mcap_dir
    from swarmpath.service.recorder.registry import Recorders
    from swarmpath.service.store import Store

    # One writer of a data directory's files at a time: the recorder of a coordinator killed a
    # moment ago may still be closing them; the lock is the OS's, released when it exits.
    mcap_dir(data_dir).mkdir(parents=True, exist_ok=True)
    lock = open(mcap_dir(data_dir) / ".recorder.lock", "a+b")  # held until the process exits
    fcntl.flock(lock, fcntl.LOCK_EX)
    parent = os.getppid()
    store = Store(data_dir, synchronous=synchronous)
    recorders = Recorders(store)
    last: dict[str, int] = {}  # job -> position of the last result handed to its recorder
    platforms: dict[str, dict[str, dict[str, str]]] = {}  # job -> worker -> platform, to note
    dirty: set[str] = set()
    caught_up = time.monotonic()
    # Disk full: a job whose file could not be written is dropped and written again from the
    # store after FULL_RETRY_SECONDS (job -> when), logged once a minute; the process goes on
    # (it used to exit and be restarted, rebuilding every file into the full disk again).
    blocked: dict[str, float] = {}
    logged = [-1e9]

    def full(exc: BaseException, job_id: str | None) -> None:
        for job in [job_id] if job_id else [j for j in last if not recorders.is_open(j)]:
            recorders.discard(job)
            last.pop(job, None)
            blocked[job] = time.monotonic() + FULL_RETRY_SECONDS
        if time.monotonic() - logged[0] >= 60.0:
            logged[0] = time.monotonic()
            log.error("recorder: the disk is full (%s): MCAP files wait, rewritten from the "
                      "store when there is room", exc)

    def catch_up(job_id: str) -> None:
        noted = platforms.pop(job_id, {})
        # finished: nothing more goes into it (a job followed here is only finished by "finish",
        # which forgets it: no file look-up per catch-up)
        if job_id not in last and recorders.ready(job_id):
            return
        for worker, platform in noted.items():
            recorders.open(job_id).note_platform(worker, platform)
        if job_id not in last:
            last[job_id] = store.last_result_rowid()
            recorders.open(job_id)  # new: written from the store up to (at least) there
        newest = store.last_result_rowid()
        if newest > last[job_id]:
            rec = recorders.open(job_id)
            # up to newest: results stored meanwhile wait for the next catch-up (read once,
            # not now and again from last[job_id] then)
            for i, record in enumerate(store.iter_run_records(job_id, after=last[job_id],
                                                              upto=newest)):
                rec.add(record)  # runs already written are skipped
                if i % 1000 == 999 and os.getppid() != parent:
                    raise EOFError("the coordinator is gone")
            last[job_id] = newest

    def handle(kind: str, arg: Any) -> Any:
        if kind == "finish":
            catch_up(arg)
            last.pop(arg, None)
            return str(recorders.finish(arg))
        if kind == "recover":
            touched = recorders.recover()
            dirty.update(store.unfinished_jobs())
            return touched
        raise ValueError(f"unknown message {kind!r}")

    if recover:
        handle("recover", None)
    try:
        while True:
            if conn.poll(0.2):
                while True:  # everything waiting, then one catch-up for all the pokes
                    kind, *args = conn.recv()
                    if kind == "poke":
                        dirty.add(args[0])
                        if len(args) > 1 and args[1]:
                            platforms.setdefault(args[0], {}).update(args[1])
                    elif kind == "close":
                        recorders.close()
                        store.close()
                        conn.send((True, None))
                        return
                    else:
                        try:
                            reply = (True, handle(kind, args[0] if args else None))
                        except Exception as exc:  # the coordinator raises it; we go on
                            if no_room(exc):
                                full(exc, args[0] if args and isinstance(args[0], str)
                                     else None)
                            else:
                                log.exception("recorder: %s failed", kind)
                            reply = (False, f"{type(exc).__name__}: {exc}")
                        conn.send(reply)
                    if not conn.poll(0):
                        break
            now = time.monotonic()
            if now - caught_up >= CATCH_UP_SECONDS:
                dirty.update(last)
                dirty.update(job for job, at in blocked.items() if at <= now)
                caught_up = now
            for job_id in sorted(dirty):
                if blocked.get(job_id, 0.0) > now:
                    continue
                try:
                    catch_up(job_id)
                    blocked.pop(job_id, None)
                except EOFError:
                    raise
                except Exception as exc:
                    if not no_room(exc):
                        log.exception("recorder: writing job %s failed", job_id)
                        continue
                    full(exc, job_id)
            dirty.clear()
            try:
                recorders.tick()
            except OSError as exc:  # a file that cannot grow: dropped, rebuilt when there is room
                if not no_room(exc):
                    raise
                full(exc, None)
    except (EOFError, OSError):  # the coordinator is gone: leave the .part files
        recorders.close()
        store.close()
