"""Jobs: create, read, list, cancel; their cells."""

from __future__ import annotations

import json
import sqlite3
import time
import uuid
from typing import Any

from swarmpath.plugins.pins import pin_names, spec_requirements
from swarmpath.service.job_contents import contents
from swarmpath.service.protocol import (
    BenchmarkJobSpec,
    JobState,
    JobStatus,
    MapJobSpec,
    expand_cells,
    first_runs,
    load_job_spec,
    parse_job_spec,
    runs_total,
)
from swarmpath.service.store.base import FINAL_STATES, JOB_STATES, StoreBase, StoreError


class JobsMixin(StoreBase):
    """Jobs: create, read, list, cancel; their cells."""

    def create_job(
        self, spec: BenchmarkJobSpec | MapJobSpec | dict[str, Any], now: float | None = None
    ) -> str:
        """Store a validated spec and its cells, its extensions pinned to the origins and code
        digests this process has (swarmpath.plugins.pins); returns the job id once committed."""
        if isinstance(spec, dict):
            spec = parse_job_spec(spec)
        now = time.time() if now is None else now
        with self._tx() as db:
            return self._insert_job(db, spec, now)[0]

    @staticmethod
    def _insert_job(db: sqlite3.Connection, spec: BenchmarkJobSpec | MapJobSpec,
                    now: float, pins: dict[str, dict[str, str]] | None = None) -> tuple[str, int]:
        """The job's row and its cells' rows, in the caller's transaction: (id, seq). ``pins``:
        the job's pinned extensions (default: pinned now)."""
        if pins is None:
            pins = pin_names(spec_requirements(spec))
        cells = expand_cells(spec)
        for _ in range(10):
            job_id = uuid.uuid4().hex[:12]
            if db.execute("SELECT 1 FROM jobs WHERE id = ?", (job_id,)).fetchone() is None:
                break
        else:  # pragma: no cover - 48 random bits colliding ten times
            raise StoreError("could not allocate a job id")
        cur = db.execute(
            "INSERT INTO jobs (id, kind, spec, state, runs_per_cell, cells_total, runs_total,"
            " created, pins) VALUES (?, ?, ?, 'queued', ?, ?, ?, ?, ?)",
            (job_id, spec.kind, spec.model_dump_json(), spec.runs, len(cells), runs_total(spec),
             now, json.dumps(pins, sort_keys=True)),
        )
        seq = int(cur.lastrowid or 0)
        db.executemany(
            "INSERT INTO cells (job_seq, idx, key, spec, runs) VALUES (?, ?, ?, ?, ?)",
            ((seq, i, c.key, c.model_dump_json(), first_runs(spec)) for i, c in enumerate(cells)),
        )
        return job_id, seq

    def job_spec(self, job_id: str) -> BenchmarkJobSpec | MapJobSpec | None:
        with self._read() as db:
            row = db.execute("SELECT spec FROM jobs WHERE id = ?", (job_id,)).fetchone()
        return None if row is None else load_job_spec(row["spec"])

    def _status(self, row: sqlite3.Row) -> JobStatus:
        pins = json.loads(row["pins"] or "{}")
        state, waiting = row["state"], None
        if state not in FINAL_STATES and self.live_extensions is not None:
            waiting = self._waiting(row, pins, self.live_extensions())
            if waiting is not None:
                state = "waiting"
        return JobStatus(
            id=row["id"],
            kind=row["kind"],
            state=state,
            runs_total=row["runs_total"],
            runs_done=row["runs_done"],
            runs_failed=row["runs_failed"],
            created=row["created"],
            started=row["started"],
            finished=row["finished"],
            waiting=waiting,
            pins=pins,
        )

    def job_pins(self, job_id: str) -> dict[str, dict[str, str]]:
        """The extensions the job was pinned to at submission (empty for an unknown job)."""
        with self._read() as db:
            row = db.execute("SELECT pins FROM jobs WHERE id = ?", (job_id,)).fetchone()
        return {} if row is None else dict(json.loads(row["pins"] or "{}"))

    def job_status(self, job_id: str) -> JobStatus | None:
        with self._read() as db:
            row = self._job_row(db, job_id)
        return None if row is None else self._status(row)

    def list_jobs(
        self, state: str | None = None, limit: int = 100, offset: int = 0
    ) -> list[JobStatus]:
        """Jobs, newest first, optionally only those in ``state``."""
        if state is not None and state not in (*JOB_STATES, "waiting"):
            raise ValueError(f"unknown state {state!r}; valid: {', '.join(JOB_STATES)}, waiting")
        sql = "SELECT * FROM jobs"
        args: list[Any] = []
        if state == "waiting":  # computed, not stored: among the jobs that are not final
            sql += " WHERE state IN ('queued', 'running')"
        elif state is not None:
            sql += " WHERE state = ?"
            args.append(state)
        sql += " ORDER BY seq DESC LIMIT ? OFFSET ?"
        args += [max(0, int(limit)), max(0, int(offset))]
        with self._read() as db:
            rows = db.execute(sql, args).fetchall()
        out = [self._status(r).model_copy(update={"contents": self._contents_of(r)})
               for r in rows]
        return [s for s in out if s.state == "waiting"] if state == "waiting" else out

    def job_contents(self, job_id: str) -> str | None:
        """What the job runs, in one line (:mod:`swarmpath.service.job_contents`)."""
        with self._read() as db:
            row = db.execute("SELECT id, spec FROM jobs WHERE id = ?", (job_id,)).fetchone()
        return None if row is None else self._contents_of(row)

    _CONTENTS_KEPT = 4096

    def _contents_of(self, row: sqlite3.Row) -> str:
        """A job's contents line, parsed once per job (a spec never changes; the cache is
        bounded and starts over when full)."""
        cache: dict[str, str] = self.__dict__.setdefault("_contents_cache", {})
        line = cache.get(row["id"])
        if line is None:
            if len(cache) >= self._CONTENTS_KEPT:
                cache.clear()
            line = cache[row["id"]] = contents(json.loads(row["spec"]))
        return line

    def cancel(self, job_id: str, now: float | None = None) -> JobState | None:
        """Cancel a queued or running job (its leases end, nothing more is leased or accepted).
        Returns the job's state afterwards (unchanged if already final); None if unknown."""
        now = time.time() if now is None else now
        with self._tx() as db:
            row = self._job_row(db, job_id)
            if row is None:
                return None
            if row["state"] in FINAL_STATES:
                return row["state"]
            seq = row["seq"]
            db.execute(
                "UPDATE jobs SET state = 'cancelled', finished = ? WHERE seq = ?", (now, seq)
            )
            db.execute(
                "UPDATE leases SET state = 'cancelled', ended = ? "
                "WHERE job_seq = ? AND state = 'active'",
                (now, seq),
            )
            db.execute("DELETE FROM requeue WHERE job_seq = ?", (seq,))
        return "cancelled"

    def cells(self, job_id: str) -> list[dict[str, Any]] | None:
        """The job's cells: index, key, spec, runs, done, failed, next_run."""
        with self._read() as db:
            job = self._job_row(db, job_id)
            if job is None:
                return None
            rows = db.execute(
                "SELECT idx, key, spec, runs, next_run, done, failed FROM cells "
                "WHERE job_seq = ? ORDER BY idx",
                (job["seq"],),
            ).fetchall()
        return [
            {
                "index": r["idx"], "key": r["key"], "spec": json.loads(r["spec"]),
                "runs": r["runs"], "next_run": r["next_run"], "done": r["done"],
                "failed": r["failed"],
            }
            for r in rows
        ]

    def unfinished_jobs(self) -> list[str]:
        with self._read() as db:
            return [
                r[0] for r in db.execute(
                    "SELECT id FROM jobs WHERE state IN ('queued', 'running') ORDER BY seq"
                )
            ]
