"""The store's plumbing: schema, connection, transactions, counters."""

from __future__ import annotations

import json
import math
import sqlite3
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Self

from swarmpath.evidence.race_tests import LookMemo
from swarmpath.service.protocol import (
    BenchmarkCell,
    JobState,
    Lease,
    MapCell,
)

#: 2: leases.capability, leases.beat; 3: jobs.pins; 4: results.cpu_seconds; 5: a raced job's
#: closing look written into its stored spec (the default changed: _keep_closing_looks); 6: its
#: planned looks and shares of alpha written too (the default became looks every round); 7: its
#: futility threshold and recycling written too (the defaults became 0.05 and true)
SCHEMA_VERSION = 7
DB_NAME = "swarmpath.sqlite3"
CACHE_KIB = 2048  # SQLite page cache of the connection, KiB (bounded; its default is 2,000)
#: Page size of a new store file. A result row (a 500-point curve: ~4.3 KB) overflows a 4 KiB
#: page into a second one, and SQLite writes the WAL page by page: with 32 KiB pages seven rows
#: share a page and storing a run costs about half the CPU (docs/benchmarks.md, coordinator hot
#: path); a lease transaction writes its ~10 touched pages whole, so it costs more (ibid.). An
#: existing file keeps the page size it was made with.
PAGE_BYTES = 32768
LEASE_RUNS_CACHE = 50_000  # leases whose run sets are kept in memory (beyond: read again)
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
    finished      REAL,
    pins          TEXT NOT NULL DEFAULT '{}'            -- extensions pinned at submission
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
    ended    REAL,
    capability TEXT NOT NULL DEFAULT '',                -- the lease's secret ('' never matches)
    beat     INTEGER NOT NULL DEFAULT 0                -- highest progress seq taken
);
CREATE INDEX IF NOT EXISTS leases_active ON leases (deadline) WHERE state = 'active';
CREATE INDEX IF NOT EXISTS leases_active_worker ON leases (worker) WHERE state = 'active';
CREATE INDEX IF NOT EXISTS leases_active_cell ON leases (job_seq, cell_idx)
    WHERE state = 'active';
CREATE INDEX IF NOT EXISTS leases_by_job ON leases (job_seq);  -- an ended job's caches out
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
    cpu_seconds REAL,                   -- NULL: not measured (stored before schema version 4)
    UNIQUE (job_seq, cell_idx, run)                    -- a run has at most one result
);
CREATE TABLE IF NOT EXISTS races (                     -- raced jobs: one row per block
    job_seq  INTEGER NOT NULL,
    block    TEXT NOT NULL,                            -- the cells' shared spec (JSON)
    state    TEXT NOT NULL,                            -- rounds, cells, comparisons (JSON)
    finished INTEGER NOT NULL,                         -- 1: no cell of the block races on
    updated  REAL NOT NULL,
    PRIMARY KEY (job_seq, block)
) WITHOUT ROWID;
CREATE TABLE IF NOT EXISTS maps (                      -- uploaded with POST /maps
    id       TEXT PRIMARY KEY,
    name     TEXT NOT NULL,
    format   TEXT NOT NULL,                            -- 'nav2' or 'movingai'
    source   TEXT NOT NULL,                            -- the upload (JSON), kept as sent
    scenario TEXT NOT NULL,                            -- the imported scenario (JSON)
    created  REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS map_scen (                  -- the .scen uploaded with a MovingAI map
    map_id   TEXT PRIMARY KEY,
    pairs    TEXT NOT NULL,                            -- service.map_pairs.scen_rows (JSON)
    info     TEXT NOT NULL                             -- pairs per bucket (map_pairs.scen_info)
);
"""

_COUNTERS = ("leases", "requeued_runs", "results_accepted", "duplicates", "stale")

CellSpec = BenchmarkCell | MapCell
#: Lease sizing: ``runs_for(cell_spec, job_runs_not_leased, leases_already_in_bundle) -> runs``.
RunsFor = Callable[[CellSpec, int, Sequence[Lease]], int]


class StoreError(RuntimeError):
    pass


class StoreFull(StoreError):
    """A write the store could not make because its disk (or SQLite's page limit) is full.
    Nothing was changed; the same write succeeds once there is room."""


#: SQLite's primary result code for "database or disk is full" (an ENOSPC on the database or
#: its WAL is reported as this code too).
SQLITE_FULL = 13


def _is_full(exc: sqlite3.Error) -> bool:
    code = getattr(exc, "sqlite_errorcode", None)
    return (code is not None and code & 0xFF == SQLITE_FULL) or \
        "database or disk is full" in str(exc)


def _dumps(obj: Any) -> str:
    return json.dumps(obj, separators=(",", ":"), allow_nan=True)


def _json_number(v: Any) -> Any:
    """JSON-safe numbers for REST: non-finite floats become the strings 'inf', '-inf', 'nan'."""
    if isinstance(v, float) and not math.isfinite(v):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")
    return v


def _safe(d: dict[str, Any]) -> dict[str, Any]:
    return {k: _json_number(v) for k, v in d.items()}


#: What a raced job stored before version 6 was raced with where its spec is silent: no planned
#: looks, the confidence sequence at half of alpha beside the rank-sum closing look.
_UNLOOKED_RACE = {"looks": [], "look_share": 0.0, "sequence_share": 0.5,
                  "spending": "obrien-fleming"}
#: ... and one stored before version 7: no comparison stopped for futility, no share recycled.
_NO_FUTILITY = {"futility": 0.0, "recycle": False}


def _keep_closing_looks(db: sqlite3.Connection) -> None:
    """Raced jobs stored before version 7 replay as they were decided. A spec without
    ``racing.final_test`` was raced without a closing look, the default of the code that stored
    it (new jobs default to the rank-sum look); one with a boolean, by the sign look (true) or
    none (false). One without the planned looks' fields (stored before they existed) was raced
    without looks (:data:`_UNLOOKED_RACE`; new jobs default to a look every round), and one
    without ``futility`` and ``recycle`` (stored before version 7) without futility stops or
    recycled shares (new jobs default to 0.05 and true). All are written into the spec by
    name: stored specs are read without validation (``jobspec.load_job_spec``), so they must
    hold what the model holds."""
    for row in db.execute("SELECT seq, spec FROM jobs WHERE kind = 'benchmark'").fetchall():
        spec = json.loads(row["spec"])
        racing = spec.get("racing")
        if not isinstance(racing, dict):
            continue
        look = racing.get("final_test")
        written = {k: v for k, v in {**_UNLOOKED_RACE, **_NO_FUTILITY}.items()
                   if racing.get(k) is None}
        if look not in ("rank-sum", "sign", "none"):
            written["final_test"] = "sign" if look is True else "none"
        if written:
            racing.update(written)
            db.execute("UPDATE jobs SET spec = ? WHERE seq = ?",
                       (json.dumps(spec, separators=(",", ":")), row["seq"]))


class StoreBase:
    """The connection, its lock and transactions, the schema and small shared lookups; the
    mixins of :class:`~swarmpath.service.store.Store` build on it."""

    def __init__(self, data_dir: Path | str, *, synchronous: str = "FULL"):
        self.data_dir = Path(data_dir)
        self.data_dir.mkdir(parents=True, exist_ok=True)
        self.path = self.data_dir / DB_NAME
        self._lock = threading.RLock()
        self._db = sqlite3.connect(
            self.path, timeout=30.0, isolation_level=None, check_same_thread=False
        )
        self._db.row_factory = sqlite3.Row
        self._db.execute(f"PRAGMA page_size={PAGE_BYTES}")  # a new file only (WAL keeps it)
        mode = self._db.execute("PRAGMA journal_mode=WAL").fetchone()[0]
        if str(mode).lower() != "wal":
            raise StoreError(f"cannot put {self.path} in WAL mode (got {mode})")
        if synchronous.upper() not in ("FULL", "NORMAL", "EXTRA"):
            raise ValueError(f"synchronous must be FULL, NORMAL or EXTRA, not {synchronous!r}")
        self.synchronous = synchronous.upper()
        self._db.execute(f"PRAGMA synchronous={self.synchronous}")
        self._db.execute("PRAGMA foreign_keys=ON")
        self._db.execute(f"PRAGMA cache_size=-{CACHE_KIB}")  # page cache: bounded, in KiB
        self._lease_runs: dict[str, frozenset[int]] = {}
        self._cell_specs: dict[tuple[int, int], tuple[str, CellSpec]] = {}
        # job id -> (seq, runs per cell, kind, seed, cells): see RunViewsMixin.iter_run_records
        self._record_contexts: dict[str, tuple[int, int, str, int, dict[int, Any]]] = {}
        # job seq -> its race settings and blocks, or None (RacesMixin)
        self._race_contexts: dict[int, Any] = {}
        # the planned looks' tests by the samples tested, kept across a race's replays
        self._look_memo = LookMemo()
        self._closed = False
        #: () -> {live worker: what it advertised, or None}; set by the coordinator: a job's
        #: status then says when no live worker can run it (store.extensions)
        self.live_extensions: Callable[[], Mapping[str, Mapping[str, str] | None]] | None = None
        # (since, message) while writes fail for want of room; None once one succeeds again
        self.write_problem: tuple[float, str] | None = None
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
            elif int(row[0]) in (1, 2, 3, 4, 5, 6):
                version = int(row[0])
                if version == 1:  # leases granted before capabilities can prove nothing
                    db.execute("ALTER TABLE leases ADD COLUMN capability TEXT NOT NULL "
                               "DEFAULT ''")
                    db.execute("ALTER TABLE leases ADD COLUMN beat INTEGER NOT NULL DEFAULT 0")
                if version <= 2:  # jobs from before pins pinned nothing: any worker runs them
                    db.execute("ALTER TABLE jobs ADD COLUMN pins TEXT NOT NULL DEFAULT '{}'")
                if version <= 3:  # results from before CPU times: NULL (missing), never 0
                    db.execute("ALTER TABLE results ADD COLUMN cpu_seconds REAL")
                _keep_closing_looks(db)
                db.execute("UPDATE meta SET value = ? WHERE key = 'schema_version'",
                           (str(SCHEMA_VERSION),))
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
            changes = self._db.total_changes
            try:
                self._db.execute("BEGIN IMMEDIATE")
                try:
                    yield self._db
                    self._db.execute("COMMIT")
                except BaseException:
                    if self._db.in_transaction:  # also after a COMMIT that failed
                        try:
                            self._db.execute("ROLLBACK")
                        except sqlite3.Error:  # pragma: no cover - SQLite rolled back itself
                            pass
                    raise
            except sqlite3.Error as exc:
                if not _is_full(exc):
                    raise
                self._full(exc)
            else:  # a transaction that wrote something: there is room again
                if self.write_problem is not None and self._db.total_changes != changes:
                    self.write_problem = None
            finally:
                if relaxed:
                    self._db.execute(f"PRAGMA synchronous={self.synchronous}")

    def _full(self, exc: sqlite3.Error) -> None:
        """Note that writes fail for want of room (``write_problem``) and raise StoreFull."""
        import shutil

        try:
            free = f"{shutil.disk_usage(self.data_dir).free:,} bytes free"
        except OSError:  # pragma: no cover
            free = "free space unknown"
        message = f"the store cannot write to {self.path} ({exc}; {free} on its disk)"
        since = self.write_problem[0] if self.write_problem else time.time()
        self.write_problem = (since, message)
        raise StoreFull(message) from None

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

    def __enter__(self) -> Self:
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

    def forget_job(self, job_id: str) -> list[str]:
        """Drop the caches of an ended job (its leases' run sets and its cell specs); returns
        its lease ids, for the caller's own per-lease caches. The database keeps everything."""
        with self._read() as db:
            row = db.execute("SELECT seq FROM jobs WHERE id = ?", (job_id,)).fetchone()
            if row is None:
                return []
            seq = int(row[0])
            leases = [r[0] for r in db.execute(
                "SELECT lease_id FROM leases WHERE job_seq = ?", (seq,))]
            for lease_id in leases:
                self._lease_runs.pop(lease_id, None)
            for key in [k for k in self._cell_specs if k[0] == seq]:
                del self._cell_specs[key]
            self._race_contexts.pop(seq, None)
        return leases

    def _runs_of(self, lease_id: str, runs_json: str) -> frozenset[int]:
        cached = self._lease_runs.get(lease_id)
        if cached is None:
            cached = self._remember_runs(lease_id, json.loads(runs_json))
        return cached

    def _remember_runs(self, lease_id: str, runs: Iterable[int]) -> frozenset[int]:
        """Cache a lease's run set; at most LEASE_RUNS_CACHE leases (then it starts over: a
        run set not cached is read from its lease row). A job's end drops its leases' sets
        (forget_job); the bound holds within one job of many leases too."""
        if len(self._lease_runs) >= LEASE_RUNS_CACHE:
            self._lease_runs.clear()
        cached = self._lease_runs[lease_id] = frozenset(runs)
        return cached

    def _race_step(self, db: sqlite3.Connection, seq: int, cell_idx: int, now: float) -> None:
        """Raced jobs decide their next round here (RacesMixin); a no-op for the others."""

    @staticmethod
    def _job_row(db: sqlite3.Connection, job_id: str) -> sqlite3.Row | None:
        return db.execute("SELECT * FROM jobs WHERE id = ?", (job_id,)).fetchone()

    def counters(self) -> dict[str, int]:
        """Monotonic counters since the data dir was created (for Prometheus)."""
        with self._read() as db:
            rows = db.execute("SELECT key, value FROM meta WHERE key LIKE 'counter.%'").fetchall()
        return {r[0].split(".", 1)[1]: int(r[1]) for r in rows if r[0] != "counter.lease_turn"}
