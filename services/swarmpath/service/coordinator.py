"""The coordinator: the REST API (FastAPI), the job queue (SQLite), the MCAP recorder and the Zenoh
router, in one process.

Three layers, the lower ones usable without the upper ones:

* :class:`Coordinator` - the protocol logic as plain methods over bytes (no network): lease
  requests, result batches, progress, worker liveliness, the 1 s tick, submit/cancel. It answers
  through ``publish(key, payload)``, a callable the transport provides (a no-op without Zenoh).
  Tests drive it directly.
* :class:`ZenohBridge` - opens the Zenoh session as a router in this process and wires it to the
  Coordinator: the ``work`` queryable, the ``results/*`` and ``progress/*`` subscribers, the
  liveliness subscriber (with history). Zenoh callbacks only copy the payload into a queue; two
  threads do the work (one answers lease queries, one handles results, progress and liveliness in
  arrival order), so a callback never blocks the network.
* :func:`create_app` - the FastAPI application; its lifespan opens the store, recovers after a
  crash, starts the bridge and the 1 s :class:`Ticker`, and undoes all of that on shutdown.

The wire protocol is documented in ``schemas/README.md``; the decisions in docs/service.md
and docs/service.md.
"""

import asyncio
import json
import logging
import math
import os
import queue
import secrets
import threading
import time
from collections import Counter, OrderedDict, deque
from collections.abc import AsyncIterator, Callable, Mapping, Sequence
from contextlib import asynccontextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any, Literal

from fastapi import Body, Depends, FastAPI, HTTPException, Query, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, JSONResponse, PlainTextResponse, Response

from swarmpath import __version__
from swarmpath.service.protocol import (
    DEFAULT_PREFIX,
    MAX_BODY_BYTES,
    PROTOCOL_VERSION,
    Ack,
    BenchmarkCell,
    BenchmarkJobSpec,
    Cancel,
    JobStatus,
    Keys,
    Lease,
    LeaseBundle,
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
from swarmpath.service.store import FINAL_STATES, Store
from swarmpath.service.zenoh_config import DEFAULT_ZENOH, router_config

log = logging.getLogger("swarmpath.coordinator")

DEFAULT_HTTP = "127.0.0.1:8000"


# ----------------------------------------------------------------------------------- settings
@dataclass
class CoordinatorSettings:
    """Everything a coordinator process is configured with (the CLI fills it)."""

    data_dir: Path = field(default_factory=lambda: Path("swarmpath-data"))
    zenoh_listen: list[str] = field(default_factory=lambda: [DEFAULT_ZENOH])
    prefix: str = DEFAULT_PREFIX
    lease_seconds: float = 30.0  # a lease without heartbeat for this long is requeued
    heartbeat_seconds: float | None = None  # default lease_seconds / 3
    target_lease_seconds: float = 10.0  # a lease (or bundle of leases) is about this much work
    min_lease_runs: int = 8  # benchmark leases: at least this many runs (vectorization)
    retry_after: float = 0.5  # NoWork: ask again after this long
    token: str | None = None  # bearer token of mutating endpoints (None: $SWARMPATH_TOKEN)
    shm: bool = False
    dictionary_file: str | None = None  # Zenoh usrpwd authentication of workers
    zenoh_extra: dict[str, Any] | None = None
    synchronous: str = "FULL"  # SQLite durability (FULL: acks survive a power cut)
    tick_seconds: float = 1.0
    require_liveliness: bool = True  # lease only to workers whose liveliness token is seen

    def zenoh_config(self) -> dict[str, Any]:
        return router_config(
            self.zenoh_listen, shm=self.shm, dictionary_file=self.dictionary_file,
            extra=self.zenoh_extra,
        )


def _short(exc: BaseException, limit: int = 300) -> str:
    """One line: a validation error as 'field: message; ...', anything else as its text."""
    errors = getattr(exc, "errors", None)
    if callable(errors):
        try:
            items = errors(include_url=False, include_input=False)
        except TypeError:  # pragma: no cover - not a pydantic error after all
            items = None
        if items:
            parts = [f"{'.'.join(str(p) for p in e['loc']) or '(message)'}: {e['msg']}"
                     for e in items[:3]]
            more = f" (+{len(items) - 3} more)" if len(items) > 3 else ""
            text = "; ".join(parts) + more
            return text if len(text) <= limit else text[: limit - 3] + "..."
    text = " ".join(str(exc).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def json_safe(value: Any) -> Any:
    """Non-finite floats -> 'inf'/'-inf'/'nan' (the store's REST convention), recursively."""
    if isinstance(value, float):
        if math.isfinite(value):
            return value
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v) for v in value]
    return value


# ------------------------------------------------------------------------------- lease sizing
class LeaseSizer:
    """How many runs of a cell make about ``target_seconds`` of work.

    The cost of a run is learned from the results (``RunResult.seconds``, the run's share of its
    vectorized batch), per cell spec, as an exponential moving average; before the first result a
    rough prior is used (benchmark: from agents x iterations x dim; map: 5 s, i.e. one run).
    Benchmark leases get at least ``min_runs`` runs: runs of one cell are computed vectorized and a
    batch of one is several times slower per run than a batch of 30.

    Near the end of a job the target shrinks (guided self-scheduling): a lease takes at most
    ``remaining / (2 * slots)`` of the job's unleased work, ``slots`` being the slots of the live
    workers, so the last leases are small and no worker is left computing a big one alone while
    the others idle. A bundle (several leases in one reply) is filled until its leases' estimated
    seconds reach that target."""

    MAP_PRIOR_SECONDS = 5.0

    def __init__(self, target_seconds: float = 10.0, min_runs: int = 8, alpha: float = 0.3):
        self.target_seconds = float(target_seconds)
        self.min_runs = max(1, int(min_runs))
        self.alpha = alpha
        self.slots = 1  # slots of the live workers (the coordinator keeps it current)
        self._estimates: dict[str, float] = {}
        self._lock = threading.Lock()

    @staticmethod
    def cost_key(spec: BenchmarkCell | MapCell) -> str:
        return spec.model_dump_json()

    @classmethod
    def prior(cls, spec: BenchmarkCell | MapCell) -> float:
        if isinstance(spec, BenchmarkCell):
            return spec.iterations * spec.agents * (2.5e-6 + 5e-7 * spec.dim)
        return cls.MAP_PRIOR_SECONDS

    def estimate(self, spec: BenchmarkCell | MapCell) -> float:
        with self._lock:
            est = self._estimates.get(self.cost_key(spec))
        return self.prior(spec) if est is None else est

    def runs_for(
        self,
        spec: BenchmarkCell | MapCell,
        remaining: int | None = None,
        bundle: Sequence[Lease] = (),
    ) -> int:
        """Runs of a lease of ``spec``; 0 when ``bundle`` (the leases already in this reply)
        holds enough work. ``remaining``: the job's runs not leased yet (None: no tail rule)."""
        est = max(self.estimate(spec), 1e-6)
        budget = self.target_seconds
        if remaining is not None:
            budget = min(budget, remaining * est / (2 * max(1, self.slots)))
        if bundle:
            budget -= sum(len(lease.runs) * max(self.estimate(lease.spec), 1e-6)
                          for lease in bundle)
            if budget <= 0:
                return 0
        low = self.min_runs if isinstance(spec, BenchmarkCell) else 1
        return max(low, int(budget / est))

    def observe(self, spec: BenchmarkCell | MapCell, seconds_per_run: float) -> None:
        if not (seconds_per_run > 0 and math.isfinite(seconds_per_run)):
            return
        key = self.cost_key(spec)
        with self._lock:
            old = self._estimates.get(key)
            self._estimates[key] = (
                seconds_per_run if old is None else old + self.alpha * (seconds_per_run - old)
            )


# -------------------------------------------------------------------------------- coordinator
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
        self.sizer = LeaseSizer(settings.target_lease_seconds, settings.min_lease_runs)
        self.publish: Callable[[str, bytes], None] = publish or (lambda key, payload: None)
        self.heartbeat_seconds = settings.heartbeat_seconds or settings.lease_seconds / 3.0
        self.accepting = True
        self.started = time.time()
        self.stats: Counter[str] = Counter()
        self._lock = threading.Lock()
        self._final_lock = threading.RLock()
        self._workers: dict[str, dict[str, Any]] = {}
        self._alive: set[str] = set()
        self._accepted: deque[tuple[float, int]] = deque()
        self._jobs: dict[str, dict[str, Any]] = {}  # job id -> what records need (cache)
        self._recording: set[str] = set()  # jobs whose MCAP is open
        # lease -> (its worker, runs stored): recognizes re-sent copies without the store
        self._settled: OrderedDict[str, tuple[str, set[int]]] = OrderedDict()

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
        with self._lock:
            entry = self._workers.setdefault(
                worker, {"host": "", "pid": 0, "slots": 1, "alive": worker in self._alive}
            )
            entry["last_seen"] = now
            for key, value in info.items():
                if value:
                    entry[key] = value

    def worker_alive(self, worker: str, now: float | None = None) -> None:
        """A liveliness token appeared (or was there when we started)."""
        now = time.time() if now is None else now
        with self._lock:
            self._alive.add(worker)
        self._seen(worker, now)
        with self._lock:
            self._workers[worker]["alive"] = True
        log.info("worker %s is alive", worker)

    def worker_mark_gone(self, worker: str) -> None:
        """Liveliness lost: first half, instant (no store access; safe in a callback)."""
        with self._lock:
            self._alive.discard(worker)
            if worker in self._workers:
                self._workers[worker]["alive"] = False

    def worker_gone(self, worker: str, now: float | None = None) -> int:
        """Liveliness lost: requeue the worker's unfinished runs at once."""
        self.worker_mark_gone(worker)
        n = self.store.requeue_worker(worker, now)
        log.info("worker %s is gone%s", worker, f"; {n} runs requeued" if n else "")
        return n

    def is_alive(self, worker: str) -> bool:
        with self._lock:
            return worker in self._alive

    def workers(self) -> list[WorkerStatus]:
        activity = self.store.worker_activity()
        with self._lock:
            known = {w: dict(e) for w, e in self._workers.items()}
            alive = set(self._alive)
        out = []
        for worker in sorted(set(known) | alive | set(activity)):
            entry = known.get(worker, {})
            act = activity.get(worker, {})
            current = act.get("current_runs", [])
            if worker not in alive and worker not in known and not current:
                continue  # a worker of a previous coordinator's life with nothing leased
            out.append(WorkerStatus(
                id=worker, host=str(entry.get("host") or ""), pid=int(entry.get("pid") or 0),
                slots=int(entry.get("slots") or 1), current_runs=current,
                runs_done=int(act.get("runs_done", 0)),
                last_seen=float(entry.get("last_seen") or 0.0), alive=worker in alive,
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
        with self._lock:
            self.sizer.slots = max(1, sum(
                int(self._workers.get(w, {}).get("slots") or 1) for w in self._alive))
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
            batches.append((job_id, batch, valid))
        by_id: dict[int, str] = {}
        todo: list[RunResult] = []
        with self._lock:  # re-sent copies of results stored moments ago: no store round trip
            for item in batches:
                for r in item[2] if item is not None else ():
                    owner, runs = self._settled.get(r.lease_id, ("", ()))
                    if owner == r.worker and r.run in runs:
                        by_id[id(r)] = "duplicate"
                        self.stats["duplicates_fast"] += 1
                    else:
                        todo.append(r)
        statuses = self.store.accept_results(todo, now) if todo else []
        by_id.update((id(r), s) for r, s in zip(todo, statuses, strict=True))
        with self._lock:
            for r, s in zip(todo, statuses, strict=True):
                if s != "stale":  # the lease exists and is r.worker's
                    self._settled.setdefault(r.lease_id, (r.worker, set()))[1].add(r.run)
                    self._settled.move_to_end(r.lease_id)
            while len(self._settled) > 20_000:
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
        status = self.store.job_status(job_id)
        if status is not None and status.state in FINAL_STATES:
            self.finalize(job_id)

    def handle_progress(self, key: str, payload: bytes, now: float | None = None) -> Ack | None:
        """A RunProgress: renew the lease; tell the worker to drop it when it is not active."""
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
        self._seen(msg.worker, now)
        state = self.store.heartbeat(msg.lease_id, msg.worker, now, self.settings.lease_seconds)
        if state == "active":
            return None
        ack = Ack(worker=msg.worker, drop_leases=[msg.lease_id])
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
            self._send(self.keys.cancel, encode(Cancel(job_id=job_id)))
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
            for worker in [w for w, e in self._workers.items()
                           if not e.get("alive") and e.get("last_seen", 0) < now - 3600]:
                del self._workers[worker]

    # ------------------------------------------------------------------------------ metrics
    def runs_per_second(self, now: float | None = None, window: float = 60.0) -> float:
        now = time.time() if now is None else now
        with self._lock:
            n = sum(k for t, k in self._accepted if t >= now - window)
        span = min(window, max(now - self.started, 1.0))
        return n / span

    def metrics_text(self, now: float | None = None) -> str:
        now = time.time() if now is None else now
        counters = self.store.counters()
        with self._lock:
            alive = len(self._alive)
        active = self.store.active_leases()
        lines: list[str] = []

        def metric(name: str, kind: str, help_: str, value: float) -> None:
            lines.append(f"# HELP {name} {help_}")
            lines.append(f"# TYPE {name} {kind}")
            lines.append(f"{name} {value:g}" if isinstance(value, float) else f"{name} {value}")

        metric("swarmpath_queue_depth", "gauge",
               "Runs waiting to be leased (never leased, or requeued).", self.store.queue_depth())
        metric("swarmpath_runs_leased", "gauge", "Runs in active leases.",
               sum(len(x["runs"]) for x in active))
        metric("swarmpath_leases_active", "gauge", "Active leases.", len(active))
        metric("swarmpath_runs_per_second", "gauge",
               "Results accepted per second over the last minute.",
               round(self.runs_per_second(now), 3))
        metric("swarmpath_workers", "gauge", "Workers with a live liveliness token.", alive)
        metric("swarmpath_jobs_active", "gauge", "Queued or running jobs.",
               len(self.store.unfinished_jobs()))
        metric("swarmpath_lease_requeues_total", "counter",
               "Runs requeued because their lease expired or their worker vanished.",
               counters.get("requeued_runs", 0))
        metric("swarmpath_leases_total", "counter", "Leases granted.", counters.get("leases", 0))
        metric("swarmpath_results_accepted_total", "counter", "Results stored.",
               counters.get("results_accepted", 0))
        metric("swarmpath_results_duplicate_total", "counter", "Duplicate results ignored.",
               counters.get("duplicates", 0) + self.stats["duplicates_fast"])
        metric("swarmpath_results_stale_total", "counter", "Stale results rejected.",
               counters.get("stale", 0))
        metric("swarmpath_messages_malformed_total", "counter",
               "Malformed messages dropped since this process started.", self.stats["malformed"])
        return "\n".join(lines) + "\n"


def _cell(spec: Mapping[str, Any]) -> BenchmarkCell | MapCell:
    return BenchmarkCell(**spec) if spec.get("kind") == "benchmark" else MapCell(**spec)


# --------------------------------------------------------------------------------- transport
_NOTHING = object()


class ZenohBridge:
    """The coordinator's Zenoh side (see the module docstring)."""

    GROUP_MESSAGES = 64  # result batches stored in one transaction at most ...
    GROUP_BYTES = 8_000_000  # ... and at most this many bytes of them

    def __init__(self, core: Coordinator, config: Mapping[str, Any]):
        self.core = core
        self.config = dict(config)
        self.keys = core.keys
        self.session: Any = None
        self._entities: list[Any] = []
        self._work: queue.SimpleQueue[Any] = queue.SimpleQueue()
        self._events: queue.SimpleQueue[Any] = queue.SimpleQueue()
        self._threads: list[threading.Thread] = []
        self._closed = False

    def start(self) -> None:
        import zenoh

        from swarmpath.service.zenoh_config import describe, to_zenoh

        self.session = zenoh.open(to_zenoh(self.config))
        self._zenoh = zenoh
        log.info("%s", describe(self.config))
        self.core.publish = self.put
        for target, name in ((self._serve_work, "lease"), (self._serve_events, "events")):
            t = threading.Thread(target=target, name=f"coordinator-{name}", daemon=True)
            t.start()
            self._threads.append(t)
        s = self.session
        self._entities = [
            s.declare_queryable(self.keys.work, self._on_query, complete=True),
            s.declare_subscriber(self.keys.all_results, self._on_results),
            s.declare_subscriber(self.keys.all_progress, self._on_progress),
            s.liveliness().declare_subscriber(
                self.keys.all_workers, self._on_liveliness, history=True),
        ]

    def put(self, key: str, payload: bytes) -> None:
        if self._closed or self.session is None:
            return
        self.session.put(
            key, payload, encoding=self._zenoh.Encoding.APPLICATION_JSON,
            congestion_control=self._zenoh.CongestionControl.BLOCK,
        )

    # Zenoh callbacks: copy and queue, nothing else (they run on Zenoh's threads).
    def _on_query(self, query: Any) -> None:
        try:
            self._work.put(query)
        except Exception:  # pragma: no cover
            log.exception("queueing a lease request failed")

    def _on_results(self, sample: Any) -> None:
        self._queue_sample("results", sample)

    def _on_progress(self, sample: Any) -> None:
        self._queue_sample("progress", sample)

    def _queue_sample(self, kind: str, sample: Any) -> None:
        try:
            self._events.put((kind, str(sample.key_expr), sample.payload.to_bytes()))
        except Exception:  # pragma: no cover
            log.exception("queueing a %s message failed", kind)

    def _on_liveliness(self, sample: Any) -> None:
        try:
            worker = Keys.last_chunk(str(sample.key_expr))
            if sample.kind == self._zenoh.SampleKind.DELETE:
                self.core.worker_mark_gone(worker)  # instant: no more leases for it
                self._events.put(("gone", worker, b""))
            else:
                self.core.worker_alive(worker)
        except Exception:  # pragma: no cover
            log.exception("handling a liveliness change failed")

    # worker threads
    def _serve_work(self) -> None:
        while True:
            query = self._work.get()
            if query is None:
                return
            try:
                payload = query.payload.to_bytes() if query.payload is not None else b""
                if len(payload) > MAX_BODY_BYTES:
                    reply = self.core._no_work("lease request too large", 5.0)
                else:
                    reply = self.core.handle_lease_request(payload)
                query.reply(query.key_expr, reply,
                            encoding=self._zenoh.Encoding.APPLICATION_JSON)
            except Exception:
                log.exception("answering a lease request failed")
            finally:
                try:
                    query.drop()
                except Exception:  # pragma: no cover
                    pass

    def _serve_events(self) -> None:
        held: Any = _NOTHING  # an item taken from the queue while grouping results
        while True:
            item = self._events.get() if held is _NOTHING else held
            held = _NOTHING
            if item is None:
                return
            kind, key, payload = item
            try:
                if kind == "results":
                    # group commit: the result batches already queued share one transaction
                    group = [(key, payload)]
                    size = len(payload)
                    while len(group) < self.GROUP_MESSAGES and size < self.GROUP_BYTES:
                        try:
                            nxt = self._events.get_nowait()
                        except queue.Empty:
                            break
                        if nxt is None or nxt[0] != "results":
                            held = nxt
                            break
                        group.append((nxt[1], nxt[2]))
                        size += len(nxt[2])
                    self.core.handle_result_batches(group)
                elif kind == "progress":
                    self.core.handle_progress(key, payload)
                elif kind == "gone" and not self.core.is_alive(key):  # not back meanwhile
                    self.core.worker_gone(key)
            except Exception:
                log.exception("handling a %s message on %s failed", kind, key)

    def close(self) -> None:
        """Stop taking input, finish what was queued, close the session."""
        if self._closed:
            return
        for entity in reversed(self._entities):
            try:
                entity.undeclare()
            except Exception:  # pragma: no cover
                log.debug("undeclare failed", exc_info=True)
        self._entities = []
        self._work.put(None)
        self._events.put(None)
        for t in self._threads:
            t.join(timeout=10.0)
        self._closed = True
        if self.session is not None:
            try:
                self.session.close()
            except Exception:  # pragma: no cover
                log.debug("closing the zenoh session failed", exc_info=True)
        self.core.publish = lambda key, payload: None


class Ticker:
    """Calls ``core.tick()`` every ``seconds`` in a daemon thread; errors are logged."""

    def __init__(self, core: Coordinator, seconds: float = 1.0):
        self.core = core
        self.seconds = seconds
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="coordinator-tick", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(self.seconds):
            try:
                self.core.tick()
            except Exception:
                log.exception("the 1 s tick failed")

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=10.0)


# ------------------------------------------------------------------------------------- REST
_STATE = Literal["queued", "running", "done", "failed", "cancelled"]


class BodyLimit:
    """ASGI middleware: request bodies over ``limit`` bytes get a 422 naming the body (checked
    on Content-Length and on the bytes actually received; the body is buffered, at most
    ``limit`` bytes, and replayed to the application)."""

    def __init__(self, app: Any, limit: int = MAX_BODY_BYTES):
        self.app = app
        self.limit = limit

    async def __call__(self, scope: dict[str, Any], receive: Any, send: Any) -> None:
        if scope["type"] != "http" or scope["method"] not in ("POST", "PUT", "PATCH"):
            await self.app(scope, receive, send)
            return
        length = dict(scope.get("headers") or []).get(b"content-length")
        if length is not None and length.isdigit() and int(length) > self.limit:
            await self._reject(send, int(length))
            return
        chunks: list[bytes] = []
        size = 0
        while True:
            message = await receive()
            if message["type"] == "http.disconnect":
                return
            body = message.get("body", b"")
            size += len(body)
            if size > self.limit:
                await self._reject(send, size)
                return
            chunks.append(body)
            if not message.get("more_body", False):
                break
        replayed = False

        async def replay() -> dict[str, Any]:
            nonlocal replayed
            if not replayed:
                replayed = True
                return {"type": "http.request", "body": b"".join(chunks), "more_body": False}
            return await receive()

        await self.app(scope, replay, send)

    async def _reject(self, send: Any, size: int) -> None:
        body = json.dumps({"detail": [{
            "loc": ["body"], "type": "body_too_large",
            "msg": f"the request body ({size} bytes or more) exceeds {self.limit} bytes",
        }]}).encode()
        await send({"type": "http.response.start", "status": 422, "headers": [
            (b"content-type", b"application/json"), (b"content-length", str(len(body)).encode()),
            (b"connection", b"close"),
        ]})
        await send({"type": "http.response.body", "body": body})


def _validation_detail(errors: list[dict[str, Any]]) -> list[dict[str, Any]]:
    out = []
    for e in errors:
        item = {"loc": list(e.get("loc", ())), "msg": str(e.get("msg", "")),
                "type": str(e.get("type", ""))}
        out.append(item)
    return out


def create_app(
    settings: CoordinatorSettings | None = None,
    *,
    use_zenoh: bool = True,
    on_started: Callable[[], None] | None = None,
    on_stopping: Callable[[], None] | None = None,
) -> FastAPI:
    """The FastAPI application. ``use_zenoh=False`` serves REST only (tests); ``on_started`` runs
    once the router is up (``swarmpath up`` starts its workers there) and ``on_stopping`` before
    it goes down."""

    settings = settings or CoordinatorSettings()
    token = settings.token if settings.token is not None else os.environ.get("SWARMPATH_TOKEN")
    token = token or None

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        core = await asyncio.to_thread(Coordinator, settings)
        bridge: ZenohBridge | None = None
        ticker = Ticker(core, settings.tick_seconds)
        try:
            await asyncio.to_thread(core.startup)
            await asyncio.to_thread(_warm_registries)
            if use_zenoh:
                bridge = ZenohBridge(core, settings.zenoh_config())
                await asyncio.to_thread(bridge.start)
            ticker.start()
            app.state.core = core
            app.state.bridge = bridge
            if on_started is not None:
                await asyncio.to_thread(on_started)
            yield
        finally:
            core.accepting = False
            if on_stopping is not None:
                try:
                    await asyncio.to_thread(on_stopping)
                except Exception:
                    log.exception("stopping the local workers failed")
            ticker.stop()
            if bridge is not None:
                await asyncio.to_thread(bridge.close)
            await asyncio.to_thread(core.close)
            log.info("coordinator stopped")

    app = FastAPI(
        title="swarmpath coordinator",
        version=__version__,
        summary="Benchmark and map studies of swarm optimizers and path planners, run by workers.",
        lifespan=lifespan,
    )
    app.add_middleware(BodyLimit, limit=MAX_BODY_BYTES)

    @app.exception_handler(RequestValidationError)
    async def _invalid(request: Request, exc: RequestValidationError) -> JSONResponse:
        return JSONResponse({"detail": _validation_detail(list(exc.errors()))}, status_code=422)

    def core_of(request: Request) -> Coordinator:
        return request.app.state.core

    def authorized(request: Request) -> None:
        if token is None:
            return
        header = request.headers.get("authorization", "")
        scheme, _, given = header.partition(" ")
        if scheme.lower() != "bearer" or not secrets.compare_digest(given.strip(), token):
            raise HTTPException(
                401, "a valid 'Authorization: Bearer <token>' header is required",
                headers={"WWW-Authenticate": "Bearer"},
            )

    CoreDep = Annotated[Coordinator, Depends(core_of)]

    def status_or_404(core: Coordinator, job_id: str) -> JobStatus:
        status = core.store.job_status(job_id)
        if status is None:
            raise HTTPException(404, f"unknown job {job_id!r}")
        return status

    @app.post("/jobs", status_code=201, dependencies=[Depends(authorized)], tags=["jobs"])
    def submit_job(
        spec: Annotated[BenchmarkJobSpec | MapJobSpec, Body(discriminator="kind")],
        core: CoreDep,
    ) -> dict[str, Any]:
        """Submit a benchmark or map job (a JobSpec). 201 with its id, state and runs_total."""
        status = core.submit(spec)
        return {"id": status.id, "state": status.state, "runs_total": status.runs_total}

    @app.get("/jobs", tags=["jobs"])
    def list_jobs(
        core: CoreDep,
        state: _STATE | None = None,
        limit: Annotated[int, Query(ge=1, le=1000)] = 100,
        offset: Annotated[int, Query(ge=0)] = 0,
    ) -> list[JobStatus]:
        """Jobs, newest first, optionally only those in one state."""
        return core.store.list_jobs(state, limit, offset)

    @app.get("/jobs/{job_id}", tags=["jobs"])
    def job_status(job_id: str, core: CoreDep) -> JobStatus:
        return status_or_404(core, job_id)

    @app.delete("/jobs/{job_id}", dependencies=[Depends(authorized)], tags=["jobs"])
    def cancel_job(job_id: str, core: CoreDep) -> JobStatus:
        """Cancel a queued or running job (a finished job is returned unchanged)."""
        status = core.cancel(job_id)
        if status is None:
            raise HTTPException(404, f"unknown job {job_id!r}")
        return status

    @app.get("/jobs/{job_id}/summary", tags=["results"])
    def job_summary(
        job_id: str, core: CoreDep, format: Literal["json", "csv"] = "json"
    ) -> Any:
        """The statistics tables (partial while the job runs); ``?format=csv`` for CSV."""
        summary = core.store.summary(job_id)
        if summary is None:
            raise HTTPException(404, f"unknown job {job_id!r}")
        if format == "csv":
            from swarmpath.service.store import summary_to_csv

            return PlainTextResponse(summary_to_csv(summary), media_type="text/csv")
        return json_safe(summary)

    @app.get("/jobs/{job_id}/runs", tags=["results"])
    def job_runs(
        job_id: str,
        core: CoreDep,
        limit: Annotated[int, Query(ge=1, le=1000)] = 100,
        offset: Annotated[int, Query(ge=0)] = 0,
    ) -> dict[str, Any]:
        """One item per run (finished or not), in run_id order."""
        status = status_or_404(core, job_id)
        items = core.store.runs(job_id, limit, offset) or []
        return {"job_id": job_id, "total": status.runs_total, "limit": limit, "offset": offset,
                "items": json_safe(items)}

    @app.get("/jobs/{job_id}/runs/{run_id}", tags=["results"])
    def job_run(job_id: str, run_id: int, core: CoreDep) -> dict[str, Any]:
        """One run with its convergence curve (benchmark) or path rows [x, y, t] (map)."""
        status_or_404(core, job_id)
        item = core.store.run(job_id, run_id)
        if item is None:
            raise HTTPException(404, f"job {job_id} has no run {run_id}")
        return json_safe(item)

    @app.get("/jobs/{job_id}/mcap", tags=["results"], response_class=FileResponse,
             responses={409: {"description": "the job has not ended yet"}})
    def job_mcap(job_id: str, core: CoreDep) -> Any:
        """The job's MCAP file, once the job has ended (409 with the reason before)."""
        status_or_404(core, job_id)
        path, reason = core.mcap_path(job_id)
        if path is None:
            raise HTTPException(409, reason)
        return FileResponse(path, media_type="application/octet-stream",
                            filename=f"{job_id}.mcap")

    @app.get("/workers", tags=["service"])
    def workers(core: CoreDep) -> list[WorkerStatus]:
        return core.workers()

    @app.get("/catalog", tags=["service"])
    def catalog() -> dict[str, Any]:
        """Optimizers (with parameters), functions, planners (with parameters) and maps."""
        return build_catalog()

    @app.get("/healthz", tags=["service"])
    def healthz(request: Request) -> dict[str, Any]:
        core = getattr(request.app.state, "core", None)
        bridge = getattr(request.app.state, "bridge", None)
        return {
            "status": "ok" if core is not None and core.accepting else "stopping",
            "version": __version__, "protocol": PROTOCOL_VERSION,
            "zenoh": bridge is not None, "listen": settings.zenoh_listen if bridge else [],
            "prefix": settings.prefix,
            "uptime": round(time.time() - core.started, 3) if core else 0.0,
        }

    @app.get("/metrics", tags=["service"], response_class=PlainTextResponse)
    def metrics(core: CoreDep) -> Response:
        """Prometheus text exposition."""
        return PlainTextResponse(core.metrics_text(),
                                 media_type="text/plain; version=0.0.4; charset=utf-8")

    return app


def _warm_registries() -> None:
    """Import the registries once at startup (validation imports them lazily)."""
    try:
        import swarmpath.planners  # noqa: F401
    except Exception as exc:
        log.warning("planners unavailable: map jobs will be rejected (%s)", _short(exc))


def build_catalog() -> dict[str, Any]:
    from swarmpath.functions import get_function, list_functions
    from swarmpath.optimizers import get_optimizer, list_optimizers

    out: dict[str, Any] = {"optimizers": [], "functions": [], "planners": [], "maps": []}
    for name in list_optimizers():
        cls = get_optimizer(name)
        out["optimizers"].append({
            "name": name, "summary": cls.summary, "reference": cls.reference,
            "min_agents": cls.min_agents, "params": dict(cls.defaults),
            "choices": {k: list(v) for k, v in cls.choices.items()},
        })
    for name in list_functions():
        fn = get_function(name)
        out["functions"].append({
            "name": name, "description": fn.description, "lower": fn.lower, "upper": fn.upper,
            "f_min_per_dim": fn.f_min_per_dim, "f_min_constant": fn.f_min_constant,
            "noisy": fn.noisy,
        })
    try:
        from swarmpath.planners import get_planner, list_planners

        for name in list_planners():
            cls = get_planner(name)
            out["planners"].append({
                "name": name, "kind": cls.kind, "description": cls.description,
                "reference": cls.reference, "params": dict(cls.defaults),
                "choices": {k: list(v) for k, v in cls.choices.items()},
            })
    except Exception as exc:
        out["planners_unavailable"] = _short(exc)
    try:
        from swarmpath.world.presets import get_map, list_maps

        for name in list_maps():
            sc = get_map(name)
            out["maps"].append({
                "name": name, "description": sc.description,
                "size": [float(v) for v in sc.size], "dynamic": bool(sc.is_dynamic),
            })
    except Exception as exc:
        out["maps_unavailable"] = _short(exc)
    return json_safe(out)
