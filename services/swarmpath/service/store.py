"""The durable job queue: jobs, their cells, leases and results in SQLite (WAL) under a data dir.

Plain methods, no network: the coordinator's REST handlers and Zenoh callbacks call them.

Threading
    One SQLite connection guarded by a re-entrant lock: every public method takes the lock for its
    whole transaction, so the store is safe to share between the FastAPI event loop (call it via
    ``asyncio.to_thread`` for long operations such as :meth:`Store.summary`), Zenoh callback
    threads and timers. SQLite serializes writers anyway; the lock also makes the read-modify-write
    sequences (leasing, fencing) atomic within the process. Only one process may open a data dir
    for writing (the coordinator); a second process may read it.

Durability
    ``journal_mode=WAL`` with ``synchronous=FULL`` by default: a method that changed state has
    committed (and fsynced the WAL) before it returns, so a job id handed to a client, or a result
    acknowledged to a worker, survives a process kill or a power cut. (``NORMAL`` survives process
    kills but not power loss.)

Runs are not stored up front: each cell keeps a cursor ``next_run`` (runs below it have been leased
at least once) and a *requeue set* (runs whose lease expired or whose worker vanished before a
result arrived). A result row exists per completed run, unique on (job, cell, run).

Fencing (see docs/service.md): a result is accepted when its lease exists, belongs to the
sending worker, covers that run, the job is not cancelled and the run has no result yet. That
includes the late result of a lease that already expired or was released (its runs requeued):
runs are deterministic, so the late result is the result; it is accepted once, the run leaves the
requeue set, and whichever copy arrives second is a ``duplicate``. Results naming an unknown
lease, another worker's lease, a run outside the lease, or a cancelled job are ``stale``.
"""

from __future__ import annotations

import csv
import io
import json
import math
import sqlite3
import threading
import time
import uuid
import zlib
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from swarmpath.service.protocol import (
    CELL_ADAPTER,
    AckStatus,
    BenchmarkCell,
    BenchmarkJobSpec,
    JobState,
    JobStatus,
    Lease,
    LeaseState,
    MapCell,
    MapJobSpec,
    RunResult,
    expand_cells,
    load_job_spec,
    parse_job_spec,
    runs_total,
)

SCHEMA_VERSION = 1
DB_NAME = "swarmpath.sqlite3"
JOB_STATES: tuple[JobState, ...] = ("queued", "running", "done", "failed", "cancelled")
FINAL_STATES = frozenset({"done", "failed", "cancelled"})

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (
    key   TEXT PRIMARY KEY,
    value TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS jobs (
    seq           INTEGER PRIMARY KEY AUTOINCREMENT,   -- FIFO order, internal foreign key
    id            TEXT NOT NULL UNIQUE,                -- public id
    kind          TEXT NOT NULL CHECK (kind IN ('benchmark', 'map')),
    spec          TEXT NOT NULL,                       -- normalized JobSpec JSON
    state         TEXT NOT NULL
                  CHECK (state IN ('queued', 'running', 'done', 'failed', 'cancelled')),
    runs_per_cell INTEGER NOT NULL,
    cells_total   INTEGER NOT NULL,
    runs_total    INTEGER NOT NULL,
    runs_done     INTEGER NOT NULL DEFAULT 0,
    runs_failed   INTEGER NOT NULL DEFAULT 0,
    lease_turn    INTEGER NOT NULL DEFAULT 0,          -- fairness: turn of its last lease
    created       REAL NOT NULL,
    started       REAL,
    finished      REAL
);
CREATE INDEX IF NOT EXISTS jobs_by_state ON jobs (state, lease_turn, seq);
CREATE TABLE IF NOT EXISTS cells (
    job_seq  INTEGER NOT NULL REFERENCES jobs (seq),
    idx      INTEGER NOT NULL,
    key      TEXT NOT NULL,
    spec     TEXT NOT NULL,                            -- CellSpec JSON
    runs     INTEGER NOT NULL,
    next_run INTEGER NOT NULL DEFAULT 0,               -- runs below it were leased once
    done     INTEGER NOT NULL DEFAULT 0,
    failed   INTEGER NOT NULL DEFAULT 0,
    PRIMARY KEY (job_seq, idx),
    UNIQUE (job_seq, key)
) WITHOUT ROWID;
CREATE INDEX IF NOT EXISTS cells_open ON cells (job_seq, idx) WHERE next_run < runs;
CREATE TABLE IF NOT EXISTS requeue (
    job_seq  INTEGER NOT NULL,
    cell_idx INTEGER NOT NULL,
    run      INTEGER NOT NULL,
    since    REAL NOT NULL,
    PRIMARY KEY (job_seq, cell_idx, run)
) WITHOUT ROWID;
CREATE TABLE IF NOT EXISTS leases (
    lease_id TEXT PRIMARY KEY,
    worker   TEXT NOT NULL,
    job_seq  INTEGER NOT NULL,
    cell_idx INTEGER NOT NULL,
    runs     TEXT NOT NULL,                            -- JSON list of run indices
    pending  INTEGER NOT NULL,                         -- runs of it without a result
    created  REAL NOT NULL,
    deadline REAL NOT NULL,
    state    TEXT NOT NULL
             CHECK (state IN ('active', 'done', 'expired', 'released', 'cancelled')),
    ended    REAL
);
CREATE INDEX IF NOT EXISTS leases_active ON leases (deadline) WHERE state = 'active';
CREATE INDEX IF NOT EXISTS leases_active_worker ON leases (worker) WHERE state = 'active';
CREATE INDEX IF NOT EXISTS leases_active_cell ON leases (job_seq, cell_idx)
    WHERE state = 'active';
CREATE TABLE IF NOT EXISTS results (
    job_seq  INTEGER NOT NULL,
    cell_idx INTEGER NOT NULL,
    run      INTEGER NOT NULL,
    lease_id TEXT NOT NULL,
    worker   TEXT NOT NULL,
    status   TEXT NOT NULL CHECK (status IN ('ok', 'failed')),
    failure  TEXT,                                     -- exception text of a failed run
    value    REAL,                                     -- best_fitness (benchmark), for summaries
    seconds  REAL NOT NULL,
    metrics  TEXT NOT NULL,                            -- JSON object
    series   BLOB,                                     -- encode_series: curve, path, ...
    created  REAL NOT NULL,
    UNIQUE (job_seq, cell_idx, run)                    -- a run has at most one result
);
"""

_COUNTERS = ("leases", "requeued_runs", "results_accepted", "duplicates", "stale")

CellSpec = BenchmarkCell | MapCell
#: Lease sizing: ``runs_for(cell_spec, job_runs_not_leased, leases_already_in_bundle) -> runs``.
RunsFor = Callable[[CellSpec, int, Sequence[Lease]], int]
_STOP = object()  # _pick_runs: the sizer ends the bundle


class StoreError(RuntimeError):
    pass


def _dumps(obj: Any) -> str:
    return json.dumps(obj, separators=(",", ":"), allow_nan=True)


#: Binary series (see encode_series): this prefix, then zlib of (header length as uint32 LE,
#: header JSON, the arrays' float64 LE bytes in header order).
SERIES_MAGIC = b"SPS1"


def encode_series(series: dict[str, Any]) -> bytes | None:
    """A run's series (curve, best position, path rows) for the ``results.series`` column: the
    arrays as float64 bytes, exact and about 10x cheaper to write than JSON text; None if
    empty. (Rows written before this format hold zlib(JSON); :func:`decode_series` reads both.)"""
    import numpy as np

    header: list[list[Any]] = []
    parts: list[bytes] = []
    for name, value in series.items():
        if value is None:
            continue
        arr = np.asarray(value, dtype="<f8")
        header.append([name, list(arr.shape)])
        parts.append(arr.tobytes())
    if not header:
        return None
    head = _dumps(header).encode()
    body = len(head).to_bytes(4, "little") + head + b"".join(parts)
    return SERIES_MAGIC + zlib.compress(body, 1)


def decode_series(blob: bytes | None) -> dict[str, Any]:
    """The series of a ``results.series`` value as lists (curve: floats, path: [x, y, t] rows)."""
    if blob is None:
        return {}
    if not blob.startswith(SERIES_MAGIC):
        return dict(json.loads(zlib.decompress(blob)))
    import numpy as np

    body = zlib.decompress(blob[len(SERIES_MAGIC):])
    n = int.from_bytes(body[:4], "little")
    offset = 4 + n
    out: dict[str, Any] = {}
    for name, shape in json.loads(body[4:offset]):
        count = math.prod(shape)
        arr = np.frombuffer(body, dtype="<f8", count=count, offset=offset).reshape(shape)
        offset += 8 * count
        out[name] = arr.tolist()
    return out


def _json_number(v: Any) -> Any:
    """JSON-safe numbers for REST: non-finite floats become the strings 'inf', '-inf', 'nan'."""
    if isinstance(v, float) and not math.isfinite(v):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")
    return v


def _safe(d: dict[str, Any]) -> dict[str, Any]:
    return {k: _json_number(v) for k, v in d.items()}


class Store:
    """See the module docstring. ``now`` arguments are Unix seconds (default: ``time.time()``)."""

    def __init__(self, data_dir: Path | str, *, synchronous: str = "FULL"):
        self.data_dir = Path(data_dir)
        self.data_dir.mkdir(parents=True, exist_ok=True)
        self.path = self.data_dir / DB_NAME
        self._lock = threading.RLock()
        self._db = sqlite3.connect(
            self.path, timeout=30.0, isolation_level=None, check_same_thread=False
        )
        self._db.row_factory = sqlite3.Row
        mode = self._db.execute("PRAGMA journal_mode=WAL").fetchone()[0]
        if str(mode).lower() != "wal":
            raise StoreError(f"cannot put {self.path} in WAL mode (got {mode})")
        if synchronous.upper() not in ("FULL", "NORMAL", "EXTRA"):
            raise ValueError(f"synchronous must be FULL, NORMAL or EXTRA, not {synchronous!r}")
        self.synchronous = synchronous.upper()
        self._db.execute(f"PRAGMA synchronous={self.synchronous}")
        self._db.execute("PRAGMA foreign_keys=ON")
        self._lease_runs: dict[str, frozenset[int]] = {}
        self._cell_specs: dict[tuple[int, int], tuple[str, CellSpec]] = {}
        self._closed = False
        self._migrate()

    # ------------------------------------------------------------------------------ plumbing
    def _migrate(self) -> None:
        with self._tx() as db:
            for statement in _SCHEMA.split(";"):
                if statement.strip():
                    db.execute(statement)
            row = db.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone()
            if row is None:
                db.execute(
                    "INSERT INTO meta (key, value) VALUES ('schema_version', ?)",
                    (str(SCHEMA_VERSION),),
                )
                db.executemany(
                    "INSERT OR IGNORE INTO meta (key, value) VALUES (?, '0')",
                    [(f"counter.{c}",) for c in (*_COUNTERS, "lease_turn")],
                )
            elif int(row[0]) != SCHEMA_VERSION:
                raise StoreError(
                    f"{self.path} has store schema version {row[0]}; this code reads "
                    f"version {SCHEMA_VERSION}"
                )

    @contextmanager
    def _tx(self, durable: bool = True) -> Iterator[sqlite3.Connection]:
        """A write transaction (BEGIN IMMEDIATE) holding the lock.

        ``durable=False`` commits without waiting for the disk (``synchronous=NORMAL`` for this
        transaction): it still survives a process kill, and the next durable commit makes it
        durable too (the WAL is written in order), but a power cut may lose it. Leases and
        lease renewals use it: losing them only means runs are leased again (see
        :meth:`lease_many`)."""
        with self._lock:
            if self._closed:
                raise StoreError("store is closed")
            relaxed = not durable and self.synchronous != "NORMAL"
            if relaxed:
                self._db.execute("PRAGMA synchronous=NORMAL")
            try:
                self._db.execute("BEGIN IMMEDIATE")
                try:
                    yield self._db
                except BaseException:
                    self._db.execute("ROLLBACK")
                    raise
                self._db.execute("COMMIT")
            finally:
                if relaxed:
                    self._db.execute(f"PRAGMA synchronous={self.synchronous}")

    @contextmanager
    def _read(self) -> Iterator[sqlite3.Connection]:
        """A consistent read snapshot holding the lock."""
        with self._lock:
            if self._closed:
                raise StoreError("store is closed")
            self._db.execute("BEGIN")
            try:
                yield self._db
            finally:
                self._db.execute("COMMIT")

    def close(self) -> None:
        with self._lock:
            if not self._closed:
                self._closed = True
                self._db.close()

    def __enter__(self) -> Store:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @staticmethod
    def _bump(db: sqlite3.Connection, counter: str, n: int = 1) -> int:
        db.execute(
            "UPDATE meta SET value = CAST(value AS INTEGER) + ? WHERE key = ?",
            (n, f"counter.{counter}"),
        )
        return int(db.execute("SELECT value FROM meta WHERE key = ?", (f"counter.{counter}",))
                   .fetchone()[0])

    def _runs_of(self, lease_id: str, runs_json: str) -> frozenset[int]:
        cached = self._lease_runs.get(lease_id)
        if cached is None:
            if len(self._lease_runs) > 50_000:
                self._lease_runs.clear()
            cached = frozenset(json.loads(runs_json))
            self._lease_runs[lease_id] = cached
        return cached

    @staticmethod
    def _job_row(db: sqlite3.Connection, job_id: str) -> sqlite3.Row | None:
        return db.execute("SELECT * FROM jobs WHERE id = ?", (job_id,)).fetchone()

    # ---------------------------------------------------------------------------------- jobs
    def create_job(
        self, spec: BenchmarkJobSpec | MapJobSpec | dict[str, Any], now: float | None = None
    ) -> str:
        """Store a validated spec and its cells; returns the job id once committed."""
        if isinstance(spec, dict):
            spec = parse_job_spec(spec)
        now = time.time() if now is None else now
        cells = expand_cells(spec)
        total = runs_total(spec)
        with self._tx() as db:
            for _ in range(10):
                job_id = uuid.uuid4().hex[:12]
                if db.execute("SELECT 1 FROM jobs WHERE id = ?", (job_id,)).fetchone() is None:
                    break
            else:  # pragma: no cover - 48 random bits colliding ten times
                raise StoreError("could not allocate a job id")
            cur = db.execute(
                "INSERT INTO jobs (id, kind, spec, state, runs_per_cell, cells_total, runs_total,"
                " created) VALUES (?, ?, ?, 'queued', ?, ?, ?, ?)",
                (job_id, spec.kind, spec.model_dump_json(), spec.runs, len(cells), total, now),
            )
            seq = cur.lastrowid
            db.executemany(
                "INSERT INTO cells (job_seq, idx, key, spec, runs) VALUES (?, ?, ?, ?, ?)",
                (
                    (seq, i, c.key, c.model_dump_json(), spec.runs)
                    for i, c in enumerate(cells)
                ),
            )
        return job_id

    def job_spec(self, job_id: str) -> BenchmarkJobSpec | MapJobSpec | None:
        with self._read() as db:
            row = db.execute("SELECT spec FROM jobs WHERE id = ?", (job_id,)).fetchone()
        return None if row is None else load_job_spec(row["spec"])

    @staticmethod
    def _status(row: sqlite3.Row) -> JobStatus:
        return JobStatus(
            id=row["id"],
            kind=row["kind"],
            state=row["state"],
            runs_total=row["runs_total"],
            runs_done=row["runs_done"],
            runs_failed=row["runs_failed"],
            created=row["created"],
            started=row["started"],
            finished=row["finished"],
        )

    def job_status(self, job_id: str) -> JobStatus | None:
        with self._read() as db:
            row = self._job_row(db, job_id)
        return None if row is None else self._status(row)

    def list_jobs(
        self, state: str | None = None, limit: int = 100, offset: int = 0
    ) -> list[JobStatus]:
        """Jobs, newest first, optionally only those in ``state``."""
        if state is not None and state not in JOB_STATES:
            raise ValueError(f"unknown state {state!r}; valid: {', '.join(JOB_STATES)}")
        sql = "SELECT * FROM jobs"
        args: list[Any] = []
        if state is not None:
            sql += " WHERE state = ?"
            args.append(state)
        sql += " ORDER BY seq DESC LIMIT ? OFFSET ?"
        args += [max(0, int(limit)), max(0, int(offset))]
        with self._read() as db:
            rows = db.execute(sql, args).fetchall()
        return [self._status(r) for r in rows]

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

    # -------------------------------------------------------------------------------- leasing
    def lease(
        self,
        worker: str,
        max_runs: int,
        now: float | None = None,
        lease_seconds: float = 60.0,
        heartbeat_seconds: float | None = None,
        runs_for: RunsFor | None = None,
    ) -> Lease | None:
        """Lease up to ``max_runs`` runs of one cell to ``worker``, or None if nothing is leasable
        (:meth:`lease_many` with one lease)."""
        leases = self.lease_many(worker, max_runs, now, lease_seconds, heartbeat_seconds,
                                 runs_for=runs_for)
        return leases[0] if leases else None

    def lease_many(
        self,
        worker: str,
        max_runs: int,
        now: float | None = None,
        lease_seconds: float = 60.0,
        heartbeat_seconds: float | None = None,
        *,
        max_leases: int = 1,
        runs_for: RunsFor | None = None,
    ) -> list[Lease]:
        """Up to ``max_leases`` leases for ``worker`` in one transaction (a bundle), each of up to
        ``max_runs`` runs of one cell; empty when nothing is leasable.

        Jobs take turns (the job leased least recently goes first; new jobs in submission order);
        within a job, requeued runs go first, then the next unleased runs in cell order.
        ``runs_for(cell_spec, remaining, bundle)``, when given, sizes each lease: how many runs of
        the cell picked (``remaining``: the job's runs not leased yet, requeued ones included;
        ``bundle``: the leases already granted by this call); 0 ends the bundle (never asked for
        the first lease, which has at least one run).

        The transaction is not waited on to reach the disk (``_tx(durable=False)``): after a
        power cut the lease may be gone, its runs are leased again, and the worker's results
        for it are ``stale`` - at least once, never twice."""
        if max_runs < 1:
            raise ValueError("max_runs must be >= 1")
        if max_leases < 1:
            raise ValueError("max_leases must be >= 1")
        now = time.time() if now is None else now
        hb = heartbeat_seconds or max(lease_seconds / 3.0, 0.1)
        out: list[Lease] = []
        with self._tx(durable=False) as db:
            while len(out) < max_leases:
                lease = self._lease_one(db, worker, max_runs, now, lease_seconds, hb, runs_for,
                                        out)
                if lease is None:
                    break
                out.append(lease)
        return out

    def _lease_one(
        self,
        db: sqlite3.Connection,
        worker: str,
        max_runs: int,
        now: float,
        lease_seconds: float,
        heartbeat_seconds: float,
        runs_for: RunsFor | None,
        bundle: list[Lease],
    ) -> Lease | None:
        jobs = db.execute(
            "SELECT seq, id, runs_per_cell, spec FROM jobs "
            "WHERE state IN ('queued', 'running') ORDER BY lease_turn, seq"
        ).fetchall()
        for job in jobs:
            seq = job["seq"]
            picked = self._pick_runs(db, seq, max_runs, runs_for, bundle)
            if picked is _STOP:
                return None
            if picked is None:
                continue
            cell_idx, key, spec, runs = picked
            turn = self._bump(db, "lease_turn")
            self._bump(db, "leases")
            db.execute(
                "UPDATE jobs SET lease_turn = ?, state = 'running', "
                "started = COALESCE(started, ?) WHERE seq = ?",
                (turn, now, seq),
            )
            lease_id = uuid.uuid4().hex
            db.execute(
                "INSERT INTO leases (lease_id, worker, job_seq, cell_idx, runs, pending,"
                " created, deadline, state) VALUES (?, ?, ?, ?, ?, ?, ?, ?, 'active')",
                (lease_id, worker, seq, cell_idx, _dumps(runs), len(runs), now,
                 now + lease_seconds),
            )
            self._lease_runs[lease_id] = frozenset(runs)
            return Lease(
                lease_id=lease_id,
                worker=worker,
                job_id=job["id"],
                cell=key,
                cell_index=cell_idx,
                runs_per_cell=job["runs_per_cell"],
                seed=json.loads(job["spec"])["seed"],
                runs=runs,
                spec=spec,
                deadline=now + lease_seconds,
                lease_seconds=lease_seconds,
                heartbeat_seconds=heartbeat_seconds,
            )
        return None

    def _cell_spec(self, db: sqlite3.Connection, seq: int, cell_idx: int) -> tuple[str, CellSpec]:
        """(key, spec) of a cell; specs never change, so they are parsed once."""
        hit = self._cell_specs.get((seq, cell_idx))
        if hit is None:
            row = db.execute(
                "SELECT key, spec FROM cells WHERE job_seq = ? AND idx = ?", (seq, cell_idx)
            ).fetchone()
            if len(self._cell_specs) > 100_000:
                self._cell_specs.clear()
            hit = self._cell_specs[(seq, cell_idx)] = (
                row["key"], CELL_ADAPTER.validate_json(row["spec"])
            )
        return hit

    @staticmethod
    def _remaining(db: sqlite3.Connection, seq: int) -> int:
        """Runs of the job not leased yet (never leased, or requeued)."""
        fresh = db.execute(
            "SELECT COALESCE(SUM(runs - next_run), 0) FROM cells WHERE job_seq = ? "
            "AND next_run < runs", (seq,)
        ).fetchone()[0]
        again = db.execute("SELECT COUNT(*) FROM requeue WHERE job_seq = ?", (seq,)).fetchone()[0]
        return int(fresh) + int(again)

    def _pick_runs(
        self,
        db: sqlite3.Connection,
        seq: int,
        max_runs: int,
        runs_for: RunsFor | None = None,
        bundle: Sequence[Lease] = (),
    ) -> tuple[int, str, CellSpec, list[int]] | object | None:
        """(cell index, key, spec, runs) to lease from job ``seq``; None when it has nothing
        leasable, ``_STOP`` when ``runs_for`` ends the bundle."""
        first = db.execute(
            "SELECT cell_idx FROM requeue WHERE job_seq = ? ORDER BY cell_idx, run LIMIT 1", (seq,)
        ).fetchone()
        if first is not None:
            cell_idx = first[0]
        else:
            cell = db.execute(
                "SELECT idx FROM cells WHERE job_seq = ? AND next_run < runs ORDER BY idx LIMIT 1",
                (seq,),
            ).fetchone()
            if cell is None:
                return None
            cell_idx = cell[0]
        key, spec = self._cell_spec(db, seq, cell_idx)
        if runs_for is not None:
            n = int(runs_for(spec, self._remaining(db, seq), bundle))
            if n < 1:
                if bundle:
                    return _STOP
                n = 1
            max_runs = min(max_runs, n)
        if first is not None:
            runs = [
                r[0]
                for r in db.execute(
                    "SELECT run FROM requeue WHERE job_seq = ? AND cell_idx = ? "
                    "ORDER BY run LIMIT ?",
                    (seq, cell_idx, max_runs),
                )
            ]
            db.executemany(
                "DELETE FROM requeue WHERE job_seq = ? AND cell_idx = ? AND run = ?",
                [(seq, cell_idx, r) for r in runs],
            )
            return cell_idx, key, spec, runs
        row = db.execute(
            "SELECT next_run, runs FROM cells WHERE job_seq = ? AND idx = ?", (seq, cell_idx)
        ).fetchone()
        start = row["next_run"]
        stop = min(row["runs"], start + max_runs)
        db.execute(
            "UPDATE cells SET next_run = ? WHERE job_seq = ? AND idx = ?", (stop, seq, cell_idx)
        )
        return cell_idx, key, spec, list(range(start, stop))

    def heartbeat(
        self, lease_id: str, worker: str, now: float | None = None, lease_seconds: float = 60.0
    ) -> LeaseState:
        """Renew an active lease of ``worker`` (deadline >= now + lease_seconds). Returns the
        lease's state: anything but 'active' tells the worker to drop it."""
        now = time.time() if now is None else now
        with self._tx(durable=False) as db:  # a lost renewal only means an earlier expiry
            row = db.execute(
                "SELECT worker, state, deadline FROM leases WHERE lease_id = ?", (lease_id,)
            ).fetchone()
            if row is None or row["worker"] != worker:
                return "unknown"
            if row["state"] != "active":
                return row["state"]
            db.execute(
                "UPDATE leases SET deadline = MAX(deadline, ?) WHERE lease_id = ?",
                (now + lease_seconds, lease_id),
            )
            return "active"

    def extend_active_leases(self, now: float | None = None, seconds: float = 60.0) -> int:
        """Give every active lease at least ``seconds`` from ``now``: call once when the
        coordinator restarts, since workers could not renew while it was down."""
        now = time.time() if now is None else now
        with self._tx() as db:
            return db.execute(
                "UPDATE leases SET deadline = MAX(deadline, ?) WHERE state = 'active'",
                (now + seconds,),
            ).rowcount

    def _end_leases(
        self, db: sqlite3.Connection, rows: Sequence[sqlite3.Row], state: str, now: float
    ) -> int:
        """Requeue the unfinished runs of active leases and mark them ``state``."""
        requeued = 0
        for lease in rows:
            seq, cell_idx = lease["job_seq"], lease["cell_idx"]
            runs = sorted(self._runs_of(lease["lease_id"], lease["runs"]))
            done = {
                r[0]
                for r in db.execute(
                    "SELECT run FROM results WHERE job_seq = ? AND cell_idx = ? "
                    "AND run BETWEEN ? AND ?",
                    (seq, cell_idx, runs[0], runs[-1]),
                )
            }
            todo = [r for r in runs if r not in done]
            job_state = db.execute("SELECT state FROM jobs WHERE seq = ?", (seq,)).fetchone()[0]
            if todo and job_state in ("queued", "running"):
                cur = db.executemany(
                    "INSERT OR IGNORE INTO requeue (job_seq, cell_idx, run, since) "
                    "VALUES (?, ?, ?, ?)",
                    [(seq, cell_idx, r, now) for r in todo],
                )
                requeued += max(cur.rowcount, 0)
            db.execute(
                "UPDATE leases SET state = ?, ended = ? WHERE lease_id = ?",
                (state, now, lease["lease_id"]),
            )
        if requeued:
            self._bump(db, "requeued_runs", requeued)
        return requeued

    def requeue_expired(self, now: float | None = None) -> int:
        """Requeue the unfinished runs of leases past their deadline; returns how many runs."""
        now = time.time() if now is None else now
        with self._tx() as db:
            rows = db.execute(
                "SELECT * FROM leases WHERE state = 'active' AND deadline < ?", (now,)
            ).fetchall()
            return self._end_leases(db, rows, "expired", now)

    def requeue_worker(self, worker: str, now: float | None = None) -> int:
        """The worker is gone (liveliness lost): requeue the unfinished runs of its leases."""
        now = time.time() if now is None else now
        with self._tx() as db:
            rows = db.execute(
                "SELECT * FROM leases WHERE state = 'active' AND worker = ?", (worker,)
            ).fetchall()
            return self._end_leases(db, rows, "released", now)

    def release(self, lease_id: str, worker: str, now: float | None = None) -> int:
        """The worker gives a lease back (e.g. shutting down): requeue its unfinished runs."""
        now = time.time() if now is None else now
        with self._tx() as db:
            rows = db.execute(
                "SELECT * FROM leases WHERE state = 'active' AND lease_id = ? AND worker = ?",
                (lease_id, worker),
            ).fetchall()
            return self._end_leases(db, rows, "released", now)

    # -------------------------------------------------------------------------------- results
    def accept_result(self, result: RunResult, now: float | None = None) -> AckStatus:
        """Store one result under the fencing rules (module docstring); never double-counts."""
        return self.accept_results([result], now)[0]

    def accept_results(
        self, results: Iterable[RunResult], now: float | None = None
    ) -> list[AckStatus]:
        """Several results in one transaction (one fsync); statuses in input order."""
        now = time.time() if now is None else now
        with self._tx() as db:
            out = [self._accept(db, r, now) for r in results]
            counts = {s: out.count(s) for s in ("accepted", "duplicate", "stale")}
            for status, counter in (
                ("accepted", "results_accepted"), ("duplicate", "duplicates"), ("stale", "stale")
            ):
                if counts[status]:
                    self._bump(db, counter, counts[status])
        return out

    def _accept(self, db: sqlite3.Connection, r: RunResult, now: float) -> AckStatus:
        lease = db.execute("SELECT * FROM leases WHERE lease_id = ?", (r.lease_id,)).fetchone()
        if lease is None or lease["worker"] != r.worker:
            return "stale"
        job = db.execute(
            "SELECT seq, id, kind, state, runs_total FROM jobs WHERE seq = ?", (lease["job_seq"],)
        ).fetchone()
        if job["id"] != r.job_id or job["state"] == "cancelled" or lease["state"] == "cancelled":
            return "stale"
        cell = db.execute(
            "SELECT idx FROM cells WHERE job_seq = ? AND key = ?", (job["seq"], r.cell)
        ).fetchone()
        if cell is None or cell["idx"] != lease["cell_idx"]:
            return "stale"
        if r.run not in self._runs_of(r.lease_id, lease["runs"]):
            return "stale"
        seq, cell_idx = job["seq"], cell["idx"]
        ok = r.status == "ok"
        raw = r.metrics.get("best_fitness") if job["kind"] == "benchmark" else None
        value = float(raw) if isinstance(raw, int | float) and not isinstance(raw, bool) else None
        series = {"curve": r.curve, "best_position": r.best_position, "path": r.path}
        cur = db.execute(
            "INSERT OR IGNORE INTO results (job_seq, cell_idx, run, lease_id, worker, status,"
            " failure, value, seconds, metrics, series, created)"
            " VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (
                seq, cell_idx, r.run, r.lease_id, r.worker, r.status, r.failure, value,
                r.seconds, _dumps(r.metrics),
                encode_series(series),
                now,
            ),
        )
        if cur.rowcount == 0:
            return "duplicate"
        db.execute(
            "DELETE FROM requeue WHERE job_seq = ? AND cell_idx = ? AND run = ?",
            (seq, cell_idx, r.run),
        )
        column = "done" if ok else "failed"
        db.execute(
            f"UPDATE cells SET {column} = {column} + 1 WHERE job_seq = ? AND idx = ?",
            (seq, cell_idx),
        )
        # every active lease holding this run (its own, or the one it was requeued into)
        for active in db.execute(
            "SELECT lease_id, runs FROM leases WHERE job_seq = ? AND cell_idx = ? "
            "AND state = 'active'",
            (seq, cell_idx),
        ).fetchall():
            if r.run in self._runs_of(active["lease_id"], active["runs"]):
                db.execute(
                    "UPDATE leases SET pending = pending - 1, "
                    "state = CASE WHEN pending <= 1 THEN 'done' ELSE state END, "
                    "ended = CASE WHEN pending <= 1 THEN ? ELSE ended END WHERE lease_id = ?",
                    (now, active["lease_id"]),
                )
        column = "runs_done" if ok else "runs_failed"
        db.execute(f"UPDATE jobs SET {column} = {column} + 1 WHERE seq = ?", (seq,))
        row = db.execute(
            "SELECT runs_done, runs_failed, runs_total, state FROM jobs WHERE seq = ?", (seq,)
        ).fetchone()
        if row["runs_done"] + row["runs_failed"] >= row["runs_total"] and row["state"] not in (
            FINAL_STATES
        ):
            final = "failed" if row["runs_done"] == 0 else "done"
            db.execute(
                "UPDATE jobs SET state = ?, finished = ? WHERE seq = ?", (final, now, seq)
            )
            db.execute(
                "UPDATE leases SET state = 'done', ended = ? WHERE job_seq = ? "
                "AND state = 'active'",
                (now, seq),
            )
        return "accepted"

    # ----------------------------------------------------------------------------- run views
    @staticmethod
    def _identity(kind: str, spec: dict[str, Any]) -> dict[str, Any]:
        if kind == "benchmark":
            return {
                "algorithm": spec["algorithm"], "function": spec["function"], "dim": spec["dim"],
            }
        return {"planner": spec["planner"], "map": spec["map"]}

    def _item(
        self,
        job: sqlite3.Row,
        seed: int,
        cell_idx: int,
        key: str,
        cell_spec: dict[str, Any],
        run: int,
        result: sqlite3.Row | None,
        state: str,
        worker: str | None,
    ) -> dict[str, Any]:
        item: dict[str, Any] = {
            "run_id": cell_idx * job["runs_per_cell"] + run,
            "run": run,
            "cell": key,
            **self._identity(job["kind"], cell_spec),
            "seed": seed,
            "state": state,
            "worker": worker,
        }
        if result is not None:
            metrics = json.loads(result["metrics"])
            item.update({k: v for k, v in metrics.items() if k not in item})
            item["seconds"] = metrics.get("seconds", result["seconds"])
            item["failure"] = result["failure"]
            item["lease_id"] = result["lease_id"]
            item["completed"] = result["created"]
        return _safe(item)

    def runs(self, job_id: str, limit: int = 100, offset: int = 0) -> list[dict[str, Any]] | None:
        """One item per run in run_id order (all runs, finished or not); None for unknown jobs."""
        limit, offset = max(0, int(limit)), max(0, int(offset))
        with self._read() as db:
            job = self._job_row(db, job_id)
            if job is None:
                return None
            seq, rpc = job["seq"], job["runs_per_cell"]
            lo, hi = offset, min(offset + limit, job["runs_total"])
            if lo >= hi:
                return []
            seed = json.loads(job["spec"])["seed"]
            cells = {
                c["idx"]: (c["key"], json.loads(c["spec"]))
                for c in db.execute(
                    "SELECT idx, key, spec FROM cells WHERE job_seq = ? AND idx BETWEEN ? AND ?",
                    (seq, lo // rpc, (hi - 1) // rpc),
                )
            }
            results = {
                (r["cell_idx"], r["run"]): r
                for r in db.execute(
                    "SELECT cell_idx, run, lease_id, worker, status, failure, seconds, metrics,"
                    " created FROM results WHERE job_seq = ? AND (cell_idx, run) >= (?, ?)"
                    " AND (cell_idx, run) <= (?, ?)",
                    (seq, lo // rpc, lo % rpc, (hi - 1) // rpc, (hi - 1) % rpc),
                )
            }
            leased = self._leased_runs(db, seq)
        items = []
        for run_id in range(lo, hi):
            cell_idx, run = divmod(run_id, rpc)
            key, cell_spec = cells[cell_idx]
            res = results.get((cell_idx, run))
            state, worker = self._run_state(job["state"], cell_idx, run, res, leased)
            items.append(self._item(job, seed, cell_idx, key, cell_spec, run, res, state, worker))
        return items

    def _leased_runs(self, db: sqlite3.Connection, seq: int) -> dict[tuple[int, int], str]:
        out: dict[tuple[int, int], str] = {}
        for lease in db.execute(
            "SELECT lease_id, worker, cell_idx, runs FROM leases WHERE job_seq = ? "
            "AND state = 'active'",
            (seq,),
        ):
            for r in self._runs_of(lease["lease_id"], lease["runs"]):
                out[(lease["cell_idx"], r)] = lease["worker"]
        return out

    @staticmethod
    def _run_state(
        job_state: str,
        cell_idx: int,
        run: int,
        result: sqlite3.Row | None,
        leased: dict[tuple[int, int], str],
    ) -> tuple[str, str | None]:
        """done/failed (has a result), cancelled, leased (in an active lease) or queued."""
        if result is not None:
            return ("done" if result["status"] == "ok" else "failed"), result["worker"]
        if job_state == "cancelled":
            return "cancelled", None
        if (cell_idx, run) in leased:
            return "leased", leased[(cell_idx, run)]
        return "queued", None

    def run(self, job_id: str, run_id: int) -> dict[str, Any] | None:
        """One run's item plus its series (curve and best_position, or path); None if unknown."""
        with self._read() as db:
            job = self._job_row(db, job_id)
            if job is None or not 0 <= run_id < job["runs_total"]:
                return None
            seq = job["seq"]
            cell_idx, run = divmod(run_id, job["runs_per_cell"])
            cell = db.execute(
                "SELECT key, spec FROM cells WHERE job_seq = ? AND idx = ?", (seq, cell_idx)
            ).fetchone()
            res = db.execute(
                "SELECT * FROM results WHERE job_seq = ? AND cell_idx = ? AND run = ?",
                (seq, cell_idx, run),
            ).fetchone()
            leased = self._leased_runs(db, seq)
        seed = json.loads(job["spec"])["seed"]
        state, worker = self._run_state(job["state"], cell_idx, run, res, leased)
        item = self._item(
            job, seed, cell_idx, cell["key"], json.loads(cell["spec"]), run, res, state, worker
        )
        if res is not None and res["series"] is not None:
            item.update(decode_series(res["series"]))
        return item

    def iter_run_records(self, job_id: str, batch: int = 500) -> Iterator[dict[str, Any]]:
        """Every stored result of a job, in acceptance order, as recorder records (raw numbers,
        series included). Reads in batches without holding the lock in between."""
        with self._read() as db:
            job = self._job_row(db, job_id)
            if job is None:
                return
            seq, rpc, kind = job["seq"], job["runs_per_cell"], job["kind"]
            seed = json.loads(job["spec"])["seed"]
            cells = {
                c["idx"]: (c["key"], json.loads(c["spec"]))
                for c in db.execute("SELECT idx, key, spec FROM cells WHERE job_seq = ?", (seq,))
            }
        last = 0
        while True:
            with self._read() as db:
                rows = db.execute(
                    "SELECT rowid, * FROM results WHERE job_seq = ? AND rowid > ? "
                    "ORDER BY rowid LIMIT ?",
                    (seq, last, batch),
                ).fetchall()
            if not rows:
                return
            for r in rows:
                key, spec = cells[r["cell_idx"]]
                yield self._record(job_id, kind, seed, rpc, r, key, spec)
            last = rows[-1]["rowid"]

    def run_record(self, job_id: str, run_id: int) -> dict[str, Any] | None:
        """The recorder record of one finished run (None if unknown or not finished)."""
        with self._read() as db:
            job = self._job_row(db, job_id)
            if job is None or not 0 <= run_id < job["runs_total"]:
                return None
            cell_idx, run = divmod(run_id, job["runs_per_cell"])
            r = db.execute(
                "SELECT * FROM results WHERE job_seq = ? AND cell_idx = ? AND run = ?",
                (job["seq"], cell_idx, run),
            ).fetchone()
            cell = db.execute(
                "SELECT key, spec FROM cells WHERE job_seq = ? AND idx = ?",
                (job["seq"], cell_idx),
            ).fetchone()
        if r is None:
            return None
        seed = json.loads(job["spec"])["seed"]
        return self._record(
            job_id, job["kind"], seed, job["runs_per_cell"], r, cell["key"],
            json.loads(cell["spec"]),
        )

    @staticmethod
    def _record(
        job_id: str, kind: str, seed: int, rpc: int, r: sqlite3.Row, key: str, spec: dict[str, Any]
    ) -> dict[str, Any]:
        series = decode_series(r["series"])
        return {
            "job_id": job_id,
            "kind": kind,
            "run_id": r["cell_idx"] * rpc + r["run"],
            "cell_index": r["cell_idx"],
            "cell": key,
            "spec": spec,
            "run": r["run"],
            "seed": seed,
            "worker": r["worker"],
            "lease_id": r["lease_id"],
            "status": r["status"],
            "failure": r["failure"],
            "seconds": r["seconds"],
            "metrics": json.loads(r["metrics"]),
            "created": r["created"],
            **series,
        }

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

    # ------------------------------------------------------------------------------- summary
    def summary(self, job_id: str) -> dict[str, Any] | None:
        """The tables of the CLI for a job (partial while it runs); None for unknown jobs.

        benchmark rows: algorithm, function, dim, runs, failed, min, max, avg, std, median, rank
        (rank of the avg among the algorithms at that function and dim; 1 = best).
        map rows: planner, map, runs, failed, success_rate, collisions, length_mean, length_std,
        error_mean, seconds_mean, gap_mean (length and gap over successful runs)."""
        from swarmpath.stats import describe, rank

        with self._read() as db:
            job = self._job_row(db, job_id)
            if job is None:
                return None
            seq, kind = job["seq"], job["kind"]
            cells = db.execute(
                "SELECT idx, spec, failed FROM cells WHERE job_seq = ? ORDER BY idx", (seq,)
            ).fetchall()
            if kind == "benchmark":
                values: dict[int, list[float]] = {}
                for idx, value in db.execute(
                    "SELECT cell_idx, value FROM results WHERE job_seq = ? AND status = 'ok' "
                    "ORDER BY cell_idx, run",
                    (seq,),
                ):
                    values.setdefault(idx, []).append(math.inf if value is None else value)
            else:
                metrics: dict[int, list[dict[str, Any]]] = {}
                for idx, m in db.execute(
                    "SELECT cell_idx, metrics FROM results WHERE job_seq = ? AND status = 'ok' "
                    "ORDER BY cell_idx, run",
                    (seq,),
                ):
                    metrics.setdefault(idx, []).append(json.loads(m))
        rows: list[dict[str, Any]] = []
        if kind == "benchmark":
            groups: dict[tuple[str, int], dict[str, float]] = {}
            for c in cells:
                spec = json.loads(c["spec"])
                row: dict[str, Any] = {
                    "algorithm": spec["algorithm"], "function": spec["function"],
                    "dim": spec["dim"], "runs": len(values.get(c["idx"], ())),
                    "failed": c["failed"],
                }
                if c["idx"] in values:
                    row.update(describe(values[c["idx"]]))
                    groups.setdefault((row["function"], row["dim"]), {})[row["algorithm"]] = row[
                        "avg"
                    ]
                rows.append(row)
            ranks = {g: rank(avgs) for g, avgs in groups.items()}
            for row in rows:
                if "avg" in row:
                    row["rank"] = ranks[(row["function"], row["dim"])][row["algorithm"]]
                else:
                    row.update(dict.fromkeys(("min", "max", "avg", "std", "median", "rank")))
        else:
            for c in cells:
                spec = json.loads(c["spec"])
                rows.append(
                    {"planner": spec["planner"], "map": spec["map"], "failed": c["failed"],
                     **map_cell_summary(metrics.get(c["idx"], []))}
                )
        return {
            "job_id": job_id,
            "kind": kind,
            "state": job["state"],
            "partial": job["runs_done"] + job["runs_failed"] < job["runs_total"],
            "runs_total": job["runs_total"],
            "runs_done": job["runs_done"],
            "runs_failed": job["runs_failed"],
            "columns": list(BENCHMARK_COLUMNS if kind == "benchmark" else MAP_COLUMNS),
            "rows": [_safe(r) for r in rows],
        }

    def summary_csv(self, job_id: str) -> str | None:
        s = self.summary(job_id)
        if s is None:
            return None
        return summary_to_csv(s)

    # ------------------------------------------------------------------------ workers, metrics
    def active_leases(self, worker: str | None = None) -> list[dict[str, Any]]:
        sql = (
            "SELECT l.lease_id, l.worker, l.cell_idx, l.runs, l.deadline, l.created,"
            " j.id AS job_id, j.runs_per_cell FROM leases l JOIN jobs j ON j.seq = l.job_seq"
            " WHERE l.state = 'active'"
        )
        args: tuple[Any, ...] = ()
        if worker is not None:
            sql += " AND l.worker = ?"
            args = (worker,)
        with self._read() as db:
            rows = db.execute(sql, args).fetchall()
        out = []
        for r in rows:
            runs = sorted(self._runs_of(r["lease_id"], r["runs"]))
            out.append({
                "lease_id": r["lease_id"], "worker": r["worker"], "job_id": r["job_id"],
                "cell_index": r["cell_idx"], "runs": runs,
                "run_ids": [r["cell_idx"] * r["runs_per_cell"] + x for x in runs],
                "deadline": r["deadline"], "created": r["created"],
            })
        return out

    def worker_activity(self) -> dict[str, dict[str, Any]]:
        """Per worker: current runs ('<job>:<run_id>') and runs done (all jobs)."""
        out: dict[str, dict[str, Any]] = {}
        for lease in self.active_leases():
            entry = out.setdefault(lease["worker"], {"current_runs": [], "runs_done": 0})
            entry["current_runs"] += [f"{lease['job_id']}:{i}" for i in lease["run_ids"]]
        with self._read() as db:
            for worker, n in db.execute(
                "SELECT worker, COUNT(*) FROM results GROUP BY worker"
            ):
                out.setdefault(worker, {"current_runs": [], "runs_done": 0})["runs_done"] = n
        return out

    def queue_depth(self) -> int:
        """Runs of queued/running jobs not leased yet (never leased, or requeued)."""
        with self._read() as db:
            fresh = db.execute(
                "SELECT COALESCE(SUM(c.runs - c.next_run), 0) FROM cells c JOIN jobs j "
                "ON j.seq = c.job_seq WHERE j.state IN ('queued', 'running') "
                "AND c.next_run < c.runs"
            ).fetchone()[0]
            again = db.execute(
                "SELECT COUNT(*) FROM requeue q JOIN jobs j ON j.seq = q.job_seq "
                "WHERE j.state IN ('queued', 'running')"
            ).fetchone()[0]
        return int(fresh) + int(again)

    def counters(self) -> dict[str, int]:
        """Monotonic counters since the data dir was created (for Prometheus)."""
        with self._read() as db:
            rows = db.execute("SELECT key, value FROM meta WHERE key LIKE 'counter.%'").fetchall()
        return {r[0].split(".", 1)[1]: int(r[1]) for r in rows if r[0] != "counter.lease_turn"}

    def unfinished_jobs(self) -> list[str]:
        with self._read() as db:
            return [
                r[0] for r in db.execute(
                    "SELECT id FROM jobs WHERE state IN ('queued', 'running') ORDER BY seq"
                )
            ]


BENCHMARK_COLUMNS = (
    "algorithm", "function", "dim", "runs", "failed", "min", "max", "avg", "std", "median", "rank",
)
MAP_COLUMNS = (
    "planner", "map", "runs", "failed", "success_rate", "collisions", "length_mean", "length_std",
    "error_mean", "seconds_mean", "gap_mean",
)


def _mean(xs: Sequence[float]) -> float | None:
    return sum(xs) / len(xs) if xs else None


def _numbers(runs: Sequence[dict[str, Any]], key: str) -> list[float]:
    out = []
    for m in runs:
        v = m.get(key)
        if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v):
            out.append(float(v))
    return out


def map_cell_summary(runs: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Statistics of one planner x map from its runs' metrics (``swarmpath plan --json`` fields).

    success_rate over all finished runs; length mean/std (ddof=1) and gap mean over the successful
    runs; error, seconds and collisions over all runs. Missing values are left out; None when no
    run has the value."""
    from swarmpath.stats import describe

    ok = [m for m in runs if m.get("success") is True]
    lengths = _numbers(ok, "length")
    stats = describe(lengths) if lengths else None
    collisions = _numbers(runs, "collisions")
    return {
        "runs": len(runs),
        "success_rate": len(ok) / len(runs) if runs else None,
        "collisions": int(sum(collisions)) if collisions else (0 if runs else None),
        "length_mean": stats["avg"] if stats else None,
        "length_std": stats["std"] if stats else None,
        "error_mean": _mean(_numbers(runs, "error")),
        "seconds_mean": _mean(_numbers(runs, "seconds")),
        "gap_mean": _mean(_numbers(ok, "gap")),
    }


def summary_to_csv(summary: dict[str, Any]) -> str:
    """A summary's rows as CSV (header = its columns; empty cells for missing values)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    columns = summary["columns"]
    writer.writerow(columns)
    for row in summary["rows"]:
        writer.writerow(["" if row.get(c) is None else row.get(c) for c in columns])
    return buf.getvalue()
