"""The coordinator core: the protocol logic as plain methods over bytes (no network).

:class:`Coordinator` handles lease requests, result batches, progress, worker liveliness, the 1 s
tick, submit/cancel. It answers through ``publish(key, payload)``, a callable the transport
provides (a no-op without Zenoh). Tests drive it directly. The layers around it live in their own
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
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from swarmpath.service.capability import drop_proof, result_ok
from swarmpath.service.catalog import build_catalog
from swarmpath.service.lease_sizer import LeaseSizer
from swarmpath.service.metrics import metrics_text
from swarmpath.service.protocol import (
    CANCEL_LEASES,
    PROTOCOL_VERSION,
    Ack,
    BenchmarkCell,
    BenchmarkJobSpec,
    Cancel,
    JobStatus,
    Keys,
    LeaseBundle,
    LeaseDrop,
    LeaseRequest,
    MapCell,
    MapJobSpec,
    NoWork,
    ResultBatch,
    RunAck,
    RunProgress,
    RunResult,
    WorkerStatus,
    decode,
    encode,
)
from swarmpath.service.recorder import Recorders
from swarmpath.service.settings import DEFAULT_HTTP, CoordinatorSettings
from swarmpath.service.store import FINAL_STATES, Store
from swarmpath.service.util import json_safe
from swarmpath.service.util import short as _short
from swarmpath.service.web.live import Dashboard
from swarmpath.service.worker_table import WorkerTable

if TYPE_CHECKING:
    from swarmpath.service.bridge import ZenohBridge
    from swarmpath.service.http.app import create_app
    from swarmpath.service.http.middleware import BodyLimit
    from swarmpath.service.ticker import Ticker

log = logging.getLogger("swarmpath.coordinator")

SETTLED_LEASES = 20_000  # leases remembered for recognizing re-sent results
CACHED_CAPABILITIES = 50_000  # capabilities of recent leases kept in memory

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


class Coordinator:
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
        self.recorders = Recorders(self.store)
        self.dashboard = Dashboard(self.store, Path(settings.data_dir) / "dashboard")
        self.sizer = LeaseSizer(settings.target_lease_seconds, settings.min_lease_runs)
        self.publish: Callable[[str, bytes], None] = publish or (lambda key, payload: None)
        self.heartbeat_seconds = settings.heartbeat_seconds or settings.lease_seconds / 3.0
        self.accepting = True
        self.started = time.time()
        self.stats: Counter[str] = Counter()
        self._lock = threading.Lock()
        self._final_lock = threading.RLock()
        self.worker_table = WorkerTable(settings.max_workers, settings.forget_workers_seconds)
        self._accepted: deque[tuple[float, int]] = deque()
        self._jobs: dict[str, dict[str, Any]] = {}  # job id -> what records need (cache)
        self._recording: set[str] = set()  # jobs whose MCAP is open
        # lease -> (its worker, its capability, runs stored): recognizes re-sent copies of
        # stored results without a store round trip (at most SETTLED_LEASES leases, oldest out)
        self._settled: OrderedDict[str, tuple[str, str, set[int]]] = OrderedDict()
        # lease -> capability of recent leases (at most CACHED_CAPABILITIES, oldest out)
        self._caps: OrderedDict[str, str] = OrderedDict()

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
            self.recorders.close()
        finally:
            self.store.close()

    # ------------------------------------------------------------------------------ workers
    def _seen(self, worker: str, now: float, **info: Any) -> None:
        self.worker_table.seen(worker, now, **info)

    def worker_alive(self, worker: str, now: float | None = None) -> None:
        """A liveliness token appeared (or was there when we started)."""
        now = time.time() if now is None else now
        if self.worker_table.alive(worker, now):
            log.info("worker %s is alive", worker)
        elif self.worker_table.refused == 1 or self.worker_table.refused % 1000 == 0:
            log.warning("worker table full (%d live workers): %s refused (%d so far)",
                        self.worker_table.max_entries, worker, self.worker_table.refused)

    def worker_mark_gone(self, worker: str) -> None:
        """Liveliness lost: first half, instant (no store access; safe in a callback)."""
        self.worker_table.gone(worker, time.time())

    def worker_gone(self, worker: str, now: float | None = None) -> int:
        """Liveliness lost: requeue the worker's unfinished runs at once."""
        self.worker_mark_gone(worker)
        n = self.store.requeue_worker(worker, now)
        log.info("worker %s is gone%s", worker, f"; {n} runs requeued" if n else "")
        return n

    def is_alive(self, worker: str) -> bool:
        return self.worker_table.is_alive(worker)

    def workers(self) -> list[WorkerStatus]:
        """The workers of the table, and any other worker holding a lease (e.g. one of a previous
        coordinator's life that has not reconnected yet)."""
        activity = self.store.worker_activity()
        known = self.worker_table.snapshot()
        out = []
        for worker in sorted(set(known) | set(activity)):
            entry = known.get(worker)
            act = activity.get(worker, {})
            current = act.get("current_runs", [])
            if entry is None and not current:
                continue  # a worker of the past with nothing leased
            out.append(WorkerStatus(
                id=worker, host=entry.host if entry else "", pid=entry.pid if entry else 0,
                slots=entry.slots if entry else 1, current_runs=current,
                runs_done=int(act.get("runs_done", 0)),
                last_seen=entry.last_seen if entry else 0.0, alive=bool(entry and entry.alive),
            ))
        return out

    # ------------------------------------------------------------------------------ leasing
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
        self._seen(req.worker, now, host=req.host, pid=req.pid, slots=req.slots)
        if req.protocol != PROTOCOL_VERSION:
            return self._no_work(
                f"protocol {req.protocol} not supported; this coordinator speaks "
                f"{PROTOCOL_VERSION}", 30.0)
        if not self.accepting:
            return self._no_work("coordinator shutting down", 2.0)
        if self.settings.require_liveliness and not self.is_alive(req.worker):
            return self._no_work(f"no liveliness token seen for worker {req.worker} yet")
        self.sizer.slots = max(1, self.worker_table.alive_slots())
        try:
            leases = self.store.lease_many(
                req.worker, req.max_runs, now, self.settings.lease_seconds,
                self.heartbeat_seconds, max_leases=req.max_leases, runs_for=self.sizer.runs_for,
            )
        except Exception as exc:  # store closed, disk full, ...: the worker retries
            log.exception("leasing failed")
            return self._no_work(f"coordinator error: {_short(exc, 200)}", 2.0)
        if not leases:
            return self._no_work("empty")
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

    # ------------------------------------------------------------------------------ results
    def _job_info(self, job_id: str) -> dict[str, Any] | None:
        info = self._jobs.get(job_id)
        if info is None:
            status = self.store.job_status(job_id)
            spec = self.store.job_spec(job_id)
            cells = self.store.cells(job_id)
            if status is None or spec is None or cells is None:
                return None
            info = {
                "kind": status.kind, "seed": spec.seed, "rpc": spec.runs,
                "cells": {c["key"]: (c["index"], c["spec"], _cell(c["spec"])) for c in cells},
            }
            if len(self._jobs) > 256:
                self._jobs.clear()
            self._jobs[job_id] = info
        return info

    def _record(self, job_id: str, results: list[RunResult], now: float) -> None:
        """Write accepted results to the job's MCAP (the store has them already)."""
        info = self._job_info(job_id)
        if info is None:
            return
        with self._final_lock:
            if self.recorders.ready(job_id):  # finalized meanwhile (e.g. cancelled)
                return
            self._recording.add(job_id)
            for r in results:
                idx, spec, _parsed = info["cells"][r.cell]
                record: dict[str, Any] = {
                    "job_id": job_id, "kind": info["kind"],
                    "run_id": idx * info["rpc"] + r.run, "cell_index": idx, "cell": r.cell,
                    "spec": spec, "run": r.run, "seed": info["seed"], "worker": r.worker,
                    "lease_id": r.lease_id, "status": r.status, "failure": r.failure,
                    "seconds": r.seconds, "metrics": r.metrics, "created": now,
                }
                for name in ("curve", "best_position", "path"):
                    value = getattr(r, name)
                    if value is not None:
                        record[name] = value
                self.recorders.add(job_id, record)

    def handle_results(self, key: str, payload: bytes, now: float | None = None) -> Ack | None:
        """A ResultBatch on ``results/<job>``: store (one transaction), record, acknowledge.
        Malformed batches are logged and dropped (None)."""
        return self.handle_result_batches([(key, payload)], now)[0]

    def handle_result_batches(
        self, messages: Sequence[tuple[str, bytes]], now: float | None = None
    ) -> list[Ack | None]:
        """Several ResultBatch messages (key, payload) at once - group commit: the results of all
        of them are stored in one transaction (one fsync), then each batch is recorded and
        acknowledged to its worker. Returns each message's Ack (None: malformed, dropped)."""
        now = time.time() if now is None else now
        batches: list[tuple[str, ResultBatch, list[RunResult]] | None] = []
        for key, payload in messages:
            job_id = Keys.last_chunk(key)
            try:
                batch = decode(ResultBatch, payload)
            except Exception as exc:
                self.stats["malformed"] += 1
                log.warning("dropped a malformed result batch on %s: %s", key, _short(exc))
                batches.append(None)
                continue
            self._seen(batch.worker, now)
            valid = [r for r in batch.results if r.job_id == job_id and r.worker == batch.worker]
            if len(valid) < len(batch.results):
                log.warning("%d results of %s name another job or worker than their batch: "
                            "stale", len(batch.results) - len(valid), batch.worker)
            # no valid proof, no store round trip (a flood of forged results costs no fsync)
            proven = [r for r in valid if result_ok(self._capability(r.lease_id), r)]
            if len(proven) < len(valid):
                self.stats["unproven"] += len(valid) - len(proven)
                self.stats["unproven_results"] += len(valid) - len(proven)
                if self.stats["unproven_results"] == len(valid) - len(proven):
                    log.warning("results without a valid proof of their lease's capability "
                                "(counted in swarmpath_messages_unproven_total): stale")
            batches.append((job_id, batch, proven))
        by_id: dict[int, str] = {}
        todo: list[RunResult] = []
        with self._lock:  # re-sent copies of results stored moments ago: no store round trip
            for item in batches:
                for r in item[2] if item is not None else ():
                    owner, cap, runs = self._settled.get(r.lease_id, ("", "", ()))
                    if owner == r.worker and r.run in runs and result_ok(cap, r):
                        by_id[id(r)] = "duplicate"
                        self.stats["duplicates_fast"] += 1
                    else:
                        todo.append(r)
        statuses = self.store.accept_results(todo, now) if todo else []
        by_id.update((id(r), s) for r, s in zip(todo, statuses, strict=True))
        with self._lock:
            fresh = {r.lease_id for r, s in zip(todo, statuses, strict=True)
                     if s != "stale" and r.lease_id not in self._settled}
        caps = {lease_id: self._capability(lease_id) or "" for lease_id in fresh}
        with self._lock:
            for r, s in zip(todo, statuses, strict=True):
                if s != "stale":  # the lease exists, is r.worker's and r proved its capability
                    entry = self._settled.get(r.lease_id)
                    if entry is None:
                        entry = self._settled[r.lease_id] = (r.worker, caps.get(r.lease_id, ""),
                                                             set())
                    entry[2].add(r.run)
                    self._settled.move_to_end(r.lease_id)
            while len(self._settled) > SETTLED_LEASES:
                self._settled.popitem(last=False)
        accepted: dict[str, list[RunResult]] = {}
        for r in todo:
            if by_id[id(r)] == "accepted":
                accepted.setdefault(r.job_id, []).append(r)
        for job_id, results in accepted.items():
            self._after_accept(job_id, results, now)
        acks: list[Ack | None] = []
        for item in batches:
            if item is None:
                acks.append(None)
                continue
            _job_id, batch, _valid = item
            ack = Ack(
                worker=batch.worker,
                results=[
                    RunAck(lease_id=r.lease_id, job_id=r.job_id, cell=r.cell, run=r.run,
                           status=by_id.get(id(r), "stale"))  # type: ignore[arg-type]
                    for r in batch.results
                ],
            )
            self._send(self.keys.ack(batch.worker), encode(ack))
            acks.append(ack)
        return acks

    def _capability(self, lease_id: str) -> str | None:
        """A lease's secret: from the cache of recent leases, else from the store."""
        with self._lock:
            cap = self._caps.get(lease_id)
        if cap is None:
            cap = self.store.capability(lease_id)
            if cap is not None:
                self._remember_caps({lease_id: cap})
        return cap

    def _remember_caps(self, caps: Mapping[str, str]) -> None:
        with self._lock:
            self._caps.update(caps)
            while len(self._caps) > CACHED_CAPABILITIES:
                self._caps.popitem(last=False)

    def _after_accept(self, job_id: str, accepted: list[RunResult], now: float) -> None:
        """Learn run costs, write the MCAP, finalize the job when it ended."""
        with self._lock:
            self._accepted.append((now, len(accepted)))
        info = self._job_info(job_id)
        if info is not None:
            for r in accepted:
                if r.status == "ok" and r.cell in info["cells"]:
                    try:
                        self.sizer.observe(info["cells"][r.cell][2], r.seconds)
                    except Exception:  # pragma: no cover - specs come from the store
                        pass
        try:
            self._record(job_id, accepted, now)
        except Exception:
            log.exception("recording results of job %s in its MCAP failed", job_id)
        try:
            self.dashboard.observe(job_id, accepted, now)
        except Exception:
            log.exception("updating the dashboard's aggregates of job %s failed", job_id)
        status = self.store.job_status(job_id)
        if status is not None and status.state in FINAL_STATES:
            self.finalize(job_id)

    def handle_progress(self, key: str, payload: bytes, now: float | None = None) -> Ack | None:
        """A RunProgress: renew the lease; tell the worker to drop it when it is not active.
        Progress without the lease's proof, or replayed (an old seq), changes nothing and gets
        no answer."""
        now = time.time() if now is None else now
        try:
            msg = decode(RunProgress, payload)
        except Exception as exc:
            self.stats["malformed"] += 1
            log.warning("dropped a malformed progress message on %s: %s", key, _short(exc))
            return None
        if msg.job_id != Keys.last_chunk(key):
            self.stats["malformed"] += 1
            log.warning("dropped progress for job %s published on %s", msg.job_id, key)
            return None
        state = self.store.heartbeat(msg.lease_id, msg.worker, now, self.settings.lease_seconds,
                                     seq=msg.seq, proof=msg.proof)
        if state == "unknown":
            self.stats["unproven"] += 1
            return None
        self._seen(msg.worker, now)
        if state == "active":
            return None
        cap = self.store.capability(msg.lease_id)
        if cap is None:  # pragma: no cover - heartbeat just proved it exists
            return None
        drop = LeaseDrop(lease_id=msg.lease_id, proof=drop_proof(cap, msg.lease_id))
        ack = Ack(worker=msg.worker, drop_leases=[drop])
        self._send(self.keys.ack(msg.worker), encode(ack))
        return ack

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
        return status

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
                try:
                    path = self.recorders.finish(job_id)
                except Exception:
                    log.exception("finalizing the MCAP of job %s failed", job_id)
                    return None
                status = self.store.job_status(job_id)
                log.info("job %s %s; MCAP %s", job_id, status.state if status else "?", path)
                self.dashboard.finished(job_id)
            self._recording.discard(job_id)
            self._jobs.pop(job_id, None)
            return self.recorders.path(job_id)

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
        n = self.store.requeue_expired(now)
        if n:
            log.warning("%d runs requeued: their leases expired without a heartbeat", n)
        self.recorders.tick()
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


def _cell(spec: Mapping[str, Any]) -> BenchmarkCell | MapCell:
    return BenchmarkCell(**spec) if spec.get("kind") == "benchmark" else MapCell(**spec)


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
