"""The coordinator core: the protocol logic as plain methods over bytes (no network).

:class:`Coordinator` handles lease requests, worker liveliness, the 1 s tick, submit/cancel, and
(through its mixin :class:`~swarmpath.service.intake.ResultIntake`) result batches and progress.
It answers through ``publish(key, payload)``, a callable the transport provides (a no-op without
Zenoh). Tests drive it directly. The layers around it live in their own
modules: :mod:`~swarmpath.service.bridge` (Zenoh), :mod:`~swarmpath.service.ticker` (the 1 s tick),
:mod:`~swarmpath.service.http` (the FastAPI application, ``create_app``),
:mod:`~swarmpath.service.lease_sizer`, :mod:`~swarmpath.service.settings`. The names they had
when they all lived here are still importable from this module.

The wire protocol is documented in ``schemas/README.md``; the decisions in docs/service.md.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import Counter, OrderedDict, deque
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from swarmpath.service import memdebug
from swarmpath.service.bounded import BoundedRunner
from swarmpath.service.capability import drop_proof
from swarmpath.service.catalog import build_catalog
from swarmpath.service.intake import ResultIntake
from swarmpath.service.lease_sizer import LeaseSizer
from swarmpath.service.maps import warm_importer
from swarmpath.service.metrics import metrics_text
from swarmpath.service.protocol import (
    CANCEL_LEASES,
    PROTOCOL_VERSION,
    BenchmarkJobSpec,
    Cancel,
    JobStatus,
    Keys,
    LeaseBundle,
    LeaseDrop,
    LeaseRequest,
    MapJobSpec,
    NoWork,
    decode,
    encode,
)
from swarmpath.service.recorder import Recorders
from swarmpath.service.recorder.common import no_room
from swarmpath.service.recorder.process import RecorderProcess
from swarmpath.service.settings import DEFAULT_HTTP, CoordinatorSettings
from swarmpath.service.store import FINAL_STATES, Store, StoreError, StoreFull
from swarmpath.service.util import json_safe
from swarmpath.service.util import short as _short
from swarmpath.service.web.live import Dashboard
from swarmpath.service.worker_admission import WorkerAdmission

if TYPE_CHECKING:
    from swarmpath.service.bridge import ZenohBridge
    from swarmpath.service.http.app import create_app
    from swarmpath.service.http.middleware import BodyLimit
    from swarmpath.service.ticker import Ticker

log = logging.getLogger("swarmpath.coordinator")


__all__ = [
    "DEFAULT_HTTP",
    "BodyLimit",
    "Coordinator",
    "CoordinatorSettings",
    "LeaseSizer",
    "Ticker",
    "ZenohBridge",
    "build_catalog",
    "create_app",
    "json_safe",
]


class Coordinator(WorkerAdmission, ResultIntake):
    """The protocol logic (see the module docstring). Thread-safe: the store serializes its
    transactions; the registries here have their own lock."""

    def __init__(
        self,
        settings: CoordinatorSettings,
        publish: Callable[[str, bytes], None] | None = None,
    ):
        self.settings = settings
        self.keys = Keys(settings.prefix)
        self.store = Store(settings.data_dir, synchronous=settings.synchronous)
        self.recorders: Recorders | RecorderProcess = (
            RecorderProcess(settings.data_dir, settings.synchronous)
            if settings.recorder_process else Recorders(self.store))
        self.dashboard = Dashboard(self.store, Path(settings.data_dir) / "dashboard")
        self.sizer = LeaseSizer(settings.target_lease_seconds, settings.min_lease_runs,
                                max_lease_rate=settings.max_lease_rate)
        self.publish: Callable[[str, bytes], None] = publish or (lambda key, payload: None)
        self.heartbeat_seconds = settings.heartbeat_seconds or settings.lease_seconds / 3.0
        self.accepting = True
        self.started = time.time()
        self.stats: Counter[str] = Counter()
        self._lock = threading.Lock()
        self._final_lock = threading.RLock()
        self._init_admission(settings)
        # a job no live worker can run says so (state waiting; swarmpath.plugins.pins)
        self.store.live_extensions = self.worker_table.alive_extensions
        self._lease_probe = 0.0  # last lease attempt while the store could not write
        self._full_logged = -1e9  # monotonic time of the last "cannot write" log line
        self._finish_after: dict[str, float] = {}  # job -> when its MCAP may be tried again
        # uploads are parsed here, never in this process (started at the first upload)
        self.map_importer = BoundedRunner(settings.max_map_import_bytes,
                                          settings.max_map_import_seconds,
                                          name="swarmpath-map-import", warm=warm_importer)
        self._accepted: deque[tuple[float, int]] = deque()
        self._told_empty = False  # a worker was told "empty" since the last wake hint
        self._depth: int | None = None  # the queue's unleased runs at the last tick
        self._jobs: dict[str, dict[str, Any]] = {}  # job id -> what records need (cache)
        self._recording: set[str] = set()  # jobs whose MCAP is open
        # lease -> (its worker, its capability, runs stored): recognizes re-sent copies of
        # stored results without a store round trip (at most SETTLED_LEASES leases, oldest out)
        self._settled: OrderedDict[str, tuple[str, str, set[int]]] = OrderedDict()
        # lease -> capability of recent leases (at most CACHED_CAPABILITIES, oldest out)
        self._caps: OrderedDict[str, str] = OrderedDict()
        memdebug.start()  # SWARMPATH_TRACEMALLOC=DIR: allocation snapshots at each job's end

    # ---------------------------------------------------------------------------- lifecycle
    def startup(self, now: float | None = None) -> list[str]:
        """After a (re)start: give outstanding leases a fresh deadline (their workers could not
        renew while we were down), rebuild unfinished jobs' MCAP files and finalize missing ones.

        The fresh deadline is 1.5 heartbeat periods (at least 10 s, at most a lease): a worker
        still running a lease renews it within one period of reconnecting, and a lease whose
        grant never reached its worker (the reply was lost in the crash) is requeued sooner."""
        now = time.time() if now is None else now
        grace = min(self.settings.lease_seconds, max(1.5 * self.heartbeat_seconds, 10.0))
        extended = self.store.extend_active_leases(now, grace)
        if extended:
            log.info("restart: %d active leases get %.0f s to report", extended, grace)
        touched = self.recorders.recover()
        self._recording.update(self.store.unfinished_jobs())
        self.dashboard.warm(self.store.unfinished_jobs())
        if touched:
            log.info("restart: MCAP files rebuilt from the store for %d jobs", len(touched))
        return touched

    def close(self) -> None:
        self.accepting = False
        try:
            self.map_importer.close()
            self.dashboard.close()  # its build threads read the store
            self.recorders.close()
        finally:
            self.store.close()

    # ------------------------------------------------------------------------------ leasing
    #: Idle workers together ask for work about this often at most: an empty reply tells each
    #: to wait max(retry_after, live workers / this) seconds. A lease query costs the coordinator
    #: about 0.3-0.5 ms of CPU (Zenoh included): 500 idle workers polling every 0.5 s took 0.28 of
    #: a core, and at 200 polls/s the idle workers of a 200-worker farm were most of its CPU per
    #: run (scripts/bench/farm.py, docs/benchmarks.md). New work does not wait for these polls:
    #: the coordinator puts a hint on ``wake`` (:meth:`wake`) and the workers told ``empty`` ask
    #: again at once; the polls only catch a hint that was missed.
    EMPTY_POLLS_PER_SECOND = 20.0

    def empty_retry(self) -> float:
        """How long a worker told "empty" waits before asking again (unless woken)."""
        self._told_empty = True
        return max(self.settings.retry_after,
                   self.worker_table.alive_count() / self.EMPTY_POLLS_PER_SECOND)

    def wake(self) -> None:
        """Tell the workers waiting after an ``empty`` reply that work appeared (a hint on
        ``wake``, no payload: they ask again at once; only the coordinator may put there)."""
        self._told_empty = False
        self._send(self.keys.wake, b"")

    def _wake_for_new_work(self) -> None:
        """From the tick: wake the workers told ``empty`` when the job queue's unleased runs
        grew since the last tick (runs requeued, a race's next round, ...; a submitted job wakes
        them at once)."""
        depth = self.store.queue_depth()
        if self._told_empty and self._depth is not None and depth > self._depth:
            self.wake()
        self._depth = depth

    def _no_work(self, reason: str, retry_after: float | None = None) -> bytes:
        return encode(NoWork(
            retry_after=self.settings.retry_after if retry_after is None else retry_after,
            reason=reason,
        ))

    def handle_lease_request(self, payload: bytes | None, now: float | None = None) -> bytes:
        """A query on ``work``: the reply payload (a Lease or a NoWork), never an exception."""
        now = time.time() if now is None else now
        try:
            req = decode(LeaseRequest, payload or b"")
        except Exception as exc:
            self.stats["malformed"] += 1
            log.warning("dropped a malformed lease request: %s", _short(exc))
            return self._no_work(f"malformed lease request: {_short(exc, 200)}", 5.0)
        if req.protocol != PROTOCOL_VERSION:
            return self._no_work(
                f"protocol {req.protocol} not supported; this coordinator speaks "
                f"{PROTOCOL_VERSION}", 30.0)
        refused = self._request_refusal(req)  # may it speak for this worker id?
        if refused is not None:
            return self._no_work(f"refused: {refused}", 5.0)
        self._seen(req.worker, now, host=req.host, pid=req.pid, slots=req.slots,
                   platform=req.platform, proven=True, extensions=req.extensions)
        if not self.accepting:
            return self._no_work("coordinator shutting down", 2.0)
        if self.settings.require_liveliness and not self.is_alive(req.worker):
            self._check_token(req.worker, now)
            return self._no_work(f"no liveliness token seen for worker {req.worker} yet")
        self.sizer.slots = max(1, self.worker_table.alive_slots())
        problem = self.store.write_problem
        if problem is not None and now - self._lease_probe < self.FULL_RETRY:
            # no work while results could not be stored; one lease attempt per FULL_RETRY s
            # finds out when the disk has room again
            return self._no_work(f"the coordinator cannot store results now: {problem[1]}",
                                 self.FULL_RETRY)
        self._lease_probe = now
        try:
            leases = self.store.lease_many(
                req.worker, req.max_runs, now, self.settings.lease_seconds,
                self.heartbeat_seconds, max_leases=req.max_leases, runs_for=self.sizer.runs_for,
                extensions=req.extensions,
            )
        except StoreFull as exc:
            self.store_full(exc, "no leases")
            return self._no_work(f"the coordinator cannot store results now: {exc}",
                                 self.FULL_RETRY)
        except Exception as exc:  # store closed, ...: the worker retries
            log.exception("leasing failed")
            return self._no_work(f"coordinator error: {_short(exc, 200)}", 2.0)
        if not leases:
            return self._no_work("empty", self.empty_retry())
        if self.settings.require_liveliness and not self.is_alive(req.worker):
            # the worker vanished while we leased: its requeue may have run before our commit
            for lease in leases:
                self.store.release(lease.lease_id, req.worker)
            return self._no_work(f"worker {req.worker} lost its liveliness token")
        self.stats["leases"] += len(leases)
        self._remember_caps({lease.lease_id: lease.capability for lease in leases})
        if req.max_leases == 1:
            return encode(leases[0])
        return encode(LeaseBundle(leases=leases))

    #: While the store cannot write (disk full), lease requests get no work and ask again
    #: after this many seconds; one request in that time tries to lease (and so finds out).
    FULL_RETRY = 5.0

    def store_full(self, exc: StoreFull, what: str) -> None:
        """A write refused for want of room: one ERROR line a minute, no traceback (the
        condition is in /healthz and on the dashboard; everything is retried)."""
        now = time.monotonic()
        if now - self._full_logged >= 60.0:
            self._full_logged = now
            log.error("%s: %s (leasing paused; results are stored when they are sent again)",
                      what, exc)

    def _send(self, key: str, payload: bytes) -> None:
        try:
            self.publish(key, payload)
        except Exception:
            log.exception("publishing on %s failed", key)

    # --------------------------------------------------------------------------------- jobs
    def submit(self, spec: BenchmarkJobSpec | MapJobSpec) -> JobStatus:
        job_id = self.store.create_job(spec)
        status = self.store.job_status(job_id)
        assert status is not None
        log.info("job %s submitted: %s, %d runs", job_id, spec.kind, status.runs_total)
        self.wake()
        return status

    def extend(self, job_id: str, runs: int) -> tuple[JobStatus, int]:
        """A new job extending ``job_id`` to ``runs`` runs per cell, reusing its results
        (:meth:`Store.extend_job`); finalized at once when it has nothing left to run."""
        new_id, reused = self.store.extend_job(job_id, runs)
        status = self.store.job_status(new_id)
        assert status is not None
        log.info("job %s extends job %s to %d runs per cell: %d results reused, %d runs",
                 new_id, job_id, runs, reused, status.runs_total)
        if status.state in FINAL_STATES:
            self.finalize(new_id)
        else:
            self.wake()
        return status, reused

    def cancel(self, job_id: str) -> JobStatus | None:
        before = self.store.job_status(job_id)
        if before is None:
            return None
        state = self.store.cancel(job_id)
        if before.state not in FINAL_STATES and state == "cancelled":
            drops = [LeaseDrop(lease_id=lease_id, proof=drop_proof(cap, lease_id))
                     for lease_id, _worker, cap in self.store.cancelled_leases(job_id)]
            for i in range(0, max(1, len(drops)), CANCEL_LEASES):
                msg = Cancel(job_id=job_id, leases=drops[i:i + CANCEL_LEASES])
                self._send(self.keys.cancel, encode(msg))
            log.info("job %s cancelled", job_id)
            self.finalize(job_id)
        return self.store.job_status(job_id)

    def finalize(self, job_id: str) -> Path | None:
        """Finish the job's MCAP (once). Returns its path."""
        with self._final_lock:
            if not self.recorders.ready(job_id):
                if self._finish_after.get(job_id, 0.0) > time.monotonic():
                    return None  # the disk was full a moment ago
                try:
                    path = self.recorders.finish(job_id)
                except Exception as exc:
                    if not no_room(exc):
                        log.exception("finalizing the MCAP of job %s failed", job_id)
                        return None
                    self._finish_after[job_id] = time.monotonic() + self.FULL_RETRY
                    if time.monotonic() - self._full_logged >= 60.0:
                        self._full_logged = time.monotonic()
                        log.error("the MCAP of job %s waits: the disk is full (%s)", job_id, exc)
                    return None
                self._finish_after.pop(job_id, None)
                status = self.store.job_status(job_id)
                log.info("job %s %s; MCAP %s", job_id, status.state if status else "?", path)
                self.dashboard.finished(job_id)
            self._recording.discard(job_id)
            self._jobs.pop(job_id, None)
            self._forget(job_id)
            memdebug.dump(job_id)
            return self.recorders.path(job_id)

    def _forget(self, job_id: str) -> None:
        """An ended job's per-lease caches out (the store keeps what re-sent results need)."""
        try:
            leases = self.store.forget_job(job_id)
        except StoreError:  # closing
            return
        with self._lock:
            for lease_id in leases:
                self._settled.pop(lease_id, None)
                self._caps.pop(lease_id, None)

    def mcap_path(self, job_id: str) -> tuple[Path | None, str]:
        """(path, '') when the job's MCAP can be downloaded, else (None, reason)."""
        status = self.store.job_status(job_id)
        if status is None:
            return None, f"unknown job {job_id!r}"
        if status.state not in FINAL_STATES:
            finished = status.runs_done + status.runs_failed
            return None, (
                f"job {job_id} is {status.state} ({finished}/{status.runs_total} runs finished); "
                "its MCAP file is finalized when the job ends"
            )
        if not self.recorders.ready(job_id):
            self.finalize(job_id)
        if not self.recorders.ready(job_id):
            return None, f"the MCAP file of job {job_id} could not be finalized (see the log)"
        return self.recorders.path(job_id), ""

    # --------------------------------------------------------------------------------- tick
    def tick(self, now: float | None = None) -> None:
        """Every second: requeue expired leases, flush MCAP files, finalize finished jobs."""
        now = time.time() if now is None else now
        try:
            n = self.store.requeue_expired(now)
        except StoreFull as exc:
            self.store_full(exc, "expired leases not requeued")
            n = 0
        if n:
            log.warning("%d runs requeued: their leases expired without a heartbeat", n)
        try:
            self._wake_for_new_work()
        except StoreError:  # closing
            pass
        try:
            self.recorders.tick()
        except OSError as exc:  # in-process recorders on a full disk: rebuilt when there is room
            if not no_room(exc):
                raise
            if time.monotonic() - self._full_logged >= 60.0:
                self._full_logged = time.monotonic()
                log.error("MCAP files wait: the disk is full (%s)", exc)
        with self._final_lock:
            recording = list(self._recording)
        for job_id in recording:
            status = self.store.job_status(job_id)
            if status is None or status.state in FINAL_STATES:
                self.finalize(job_id)
        with self._lock:
            while self._accepted and self._accepted[0][0] < now - 60.0:
                self._accepted.popleft()
        self.worker_table.prune(now)

    # ------------------------------------------------------------------------------ metrics
    def runs_per_second(self, now: float | None = None, window: float = 60.0) -> float:
        now = time.time() if now is None else now
        with self._lock:
            n = sum(k for t, k in self._accepted if t >= now - window)
        span = min(window, max(now - self.started, 1.0))
        return n / span

    def metrics_text(self, now: float | None = None) -> str:
        """Prometheus text exposition of the queue, leases, workers and counters."""
        return metrics_text(self, now)



def __getattr__(name: str) -> Any:
    """The transport layers import this module, so they are re-exported lazily."""
    if name == "create_app":
        from swarmpath.service.http.app import create_app

        return create_app
    if name == "ZenohBridge":
        from swarmpath.service.bridge import ZenohBridge

        return ZenohBridge
    if name == "BodyLimit":
        from swarmpath.service.http.middleware import BodyLimit

        return BodyLimit
    if name == "Ticker":
        from swarmpath.service.ticker import Ticker

        return Ticker
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
