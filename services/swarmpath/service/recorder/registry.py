"""The coordinator's recorders: one per running job, opened on demand (rebuilt from the store),
finalized when the job ends, recovered after a restart."""

from __future__ import annotations

import logging
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from mcap.writer import CompressionType

from swarmpath.service.recorder.common import chunk_compression, final_path, intact, no_room
from swarmpath.service.recorder.job import FLUSH_INTERVAL, JobRecorder

log = logging.getLogger("swarmpath.recorder")


class Recorders:
    """The recorders of a coordinator: opened on demand from the store, thread-safe."""

    def __init__(
        self, store: Any, *, flush_interval: float = FLUSH_INTERVAL,
        compression: CompressionType | None = None,
    ):
        self.store = store
        self.data_dir = Path(store.data_dir)
        self.flush_interval = flush_interval
        # None: the documented setting (chunk_compression), read once per coordinator
        self.compression = chunk_compression() if compression is None else compression
        self._open: dict[str, JobRecorder] = {}
        self._lock = threading.RLock()

    def path(self, job_id: str) -> Path:
        return final_path(self.data_dir, job_id)

    def ready(self, job_id: str) -> bool:
        """True when the job's finalized MCAP exists."""
        return self.path(job_id).exists()

    def open(self, job_id: str) -> JobRecorder:
        """The job's recorder; a new one starts a fresh .part from the store's results."""
        with self._lock:
            rec = self._open.get(job_id)
            if rec is not None:
                return rec
            status = self.store.job_status(job_id)
            if status is None:
                raise KeyError(f"unknown job {job_id!r}")
            spec = self.store.job_spec(job_id)
            rec = JobRecorder(
                self.path(job_id), job_id, status.kind, spec.model_dump(mode="json"),
                status.created, flush_interval=self.flush_interval, compression=self.compression,
                pins=status.pins,
            )
            try:
                for record in self.store.iter_run_records(job_id):
                    rec.add(record)
                rec.flush()
            except BaseException:
                rec.abandon()
                raise
            self._open[job_id] = rec
            return rec

    def is_open(self, job_id: str) -> bool:
        with self._lock:
            return job_id in self._open

    def discard(self, job_id: str) -> None:
        """Drop the job's recorder after a write failed (disk full): the next ``open`` (or
        ``finish``) writes the file again from the store, so nothing is lost."""
        with self._lock:
            rec = self._open.pop(job_id, None)
        if rec is not None:
            rec.abandon()

    def add(self, job_id: str, record: dict[str, Any]) -> bool:
        with self._lock:
            return self.open(job_id).add(record)

    def record_run(self, job_id: str, run_id: int) -> bool:
        """Write an accepted run, reading it back from the store."""
        record = self.store.run_record(job_id, run_id)
        if record is None:
            return False
        return self.add(job_id, record)

    def finish(self, job_id: str) -> Path:
        """Finalize the job's file (rebuilding it from the store if no recorder is open)."""
        with self._lock:
            rec = self.open(job_id)
            status = self.store.job_status(job_id)
            stored = status.runs_done + status.runs_failed if status else 0
            if len(rec.written) < stored:
                # A concurrent batch stored its results but has not handed them to the recorder
                # yet (it will find the file finalized): take them from the store now.
                for record in self.store.iter_run_records(job_id):
                    rec.add(record)
            summary = self.store.summary(job_id)
            try:
                path = rec.finish(summary, status.state if status else "done")
            except OSError:
                self.discard(job_id)
                raise
            del self._open[job_id]
            return path

    def tick(self) -> int:
        """Flush every recorder whose interval elapsed (call about once a second). A recorder
        that cannot write for want of room is discarded (its file is rebuilt from the store
        later) and the first such error raised after the others were flushed."""
        flushed, full = 0, None
        with self._lock:
            for job_id, rec in list(self._open.items()):
                try:
                    flushed += rec.flush_if_due()
                except OSError as exc:
                    if not no_room(exc):
                        raise
                    self.discard(job_id)
                    full = full or exc
        if full is not None:
            raise full
        return flushed

    def recover(self) -> list[str]:
        """After a restart: reopen (rebuild) unfinished jobs' files and finalize finished jobs
        whose file is missing or not whole (truncated: no footer or summary, :func:`intact`),
        from the store. Returns the job ids touched."""
        touched = []
        for job_id in self.store.unfinished_jobs():
            self.open(job_id)
            touched.append(job_id)
        for status in self._final_jobs_without_file():
            self.finish(status.id)
            touched.append(status.id)
        return touched

    def _final_jobs_without_file(self) -> Iterator[Any]:
        for state in ("done", "failed", "cancelled"):
            offset = 0
            while True:
                page = self.store.list_jobs(state, limit=500, offset=offset)
                if not page:
                    break
                for status in page:
                    path = self.path(status.id)
                    if not path.exists():
                        yield status
                    elif not intact(path):  # written again from the store by finish()
                        log.warning("the MCAP of job %s is not whole (truncated?): rebuilding "
                                    "it from the store", status.id)
                        path.unlink()
                        yield status
                offset += len(page)

    def close(self) -> None:
        """Shutdown: flush and close every open recorder without finalizing."""
        with self._lock:
            for rec in self._open.values():
                rec.close()
            self._open.clear()
