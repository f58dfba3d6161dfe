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

Layout: :mod:`.base` (schema, connection, transactions), :mod:`.jobs`, :mod:`.leases`,
:mod:`.results` (fencing), :mod:`.runs` (run views and records), :mod:`.summaries` (tables, CSV),
:mod:`.series` (binary run series), :mod:`.maps` (uploaded maps),
:mod:`.scenarios` (a lease's scenario by reference), :mod:`.races` (rounds of raced jobs),
:mod:`.extend` (a finished job extended to more runs), :mod:`.extensions` (which workers
can run which cells: pinned extensions).
:class:`Store` combines them.
"""

from swarmpath.service.store.base import (
    DB_NAME,
    FINAL_STATES,
    JOB_STATES,
    SCHEMA_VERSION,
    CellSpec,
    RunsFor,
    StoreError,
    StoreFull,
)
from swarmpath.service.store.extend import ExtendError, ExtendMixin
from swarmpath.service.store.extensions import ExtensionsMixin
from swarmpath.service.store.jobs import JobsMixin
from swarmpath.service.store.leases import LeasesMixin
from swarmpath.service.store.maps import MapsMixin
from swarmpath.service.store.races import RacesMixin
from swarmpath.service.store.results import ResultsMixin
from swarmpath.service.store.runs import RunViewsMixin
from swarmpath.service.store.scenarios import ScenariosMixin
from swarmpath.service.store.series import SERIES_MAGIC, decode_series, encode_series
from swarmpath.service.store.summaries import (
    BENCHMARK_COLUMNS,
    MAP_COLUMNS,
    SummariesMixin,
    map_cell_summary,
    summary_to_csv,
)


class Store(JobsMixin, ScenariosMixin, LeasesMixin, ResultsMixin, RunViewsMixin, SummariesMixin,
            MapsMixin, RacesMixin, ExtendMixin, ExtensionsMixin):
    """See the module docstring. ``now`` arguments are Unix seconds (default: ``time.time()``)."""


__all__ = [
    "BENCHMARK_COLUMNS",
    "DB_NAME",
    "FINAL_STATES",
    "JOB_STATES",
    "MAP_COLUMNS",
    "SCHEMA_VERSION",
    "SERIES_MAGIC",
    "CellSpec",
    "ExtendError",
    "RunsFor",
    "Store",
    "StoreError",
    "StoreFull",
    "decode_series",
    "encode_series",
    "map_cell_summary",
    "summary_to_csv",
]
