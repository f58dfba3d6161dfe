"""The worker process: a Zenoh client that pulls leases from the coordinator, runs them in its
slots and reports results (schemas/README.md): liveliness token, pull loop with backoff,
heartbeats (RunProgress) for running leases, results put with CongestionControl.BLOCK and re-sent
until acknowledged, ``drop_leases`` and ``Cancel`` honoured, graceful stop on SIGTERM/SIGINT: stop
pulling, let running leases finish for ``grace_seconds`` (then abort them), wait for the acks,
undeclare the token (the coordinator requeues whatever was not reported)."""

from __future__ import annotations

import logging
import os
import signal
import socket
import threading
import time
from collections import deque
from typing import Any

from swarmpath.provenance import numeric_platform
from swarmpath.service.capability import progress_proof
from swarmpath.service.identity import Issuer, id_for
from swarmpath.service.protocol import (
    BenchmarkCell,
    Keys,
    Lease,
    RunProgress,
    encode,
)
from swarmpath.service.scenarios import ByteLRU
from swarmpath.service.worker.execution import benchmark_batches
from swarmpath.service.worker.extensions import Capabilities
from swarmpath.service.worker.pulling import Pulling
from swarmpath.service.worker.reporting import Reporting, _Active, _Pending
from swarmpath.service.worker.settings import WorkerSettings, default_worker_id
from swarmpath.service.worker.slots import ProcessSlot, Slot, ThreadSlot

log = logging.getLogger("swarmpath.worker")


class Worker(Pulling, Reporting):
    """See the module docstring. ``run()`` blocks until ``stop()`` (or a signal)."""

    def __init__(self, settings: WorkerSettings):
        self.settings = settings
        if settings.user:  # an id of the login (service/identity.py)
            self.id = id_for(settings.user, settings.worker_id, default_worker_id())
        else:
            self.id = settings.worker_id or default_worker_id()
        Keys(settings.prefix).worker_token(self.id)  # validates the id
        self._issued = Issuer()
        self.keys = Keys(settings.prefix)
        self.host = socket.gethostname()
        self._platform = numeric_platform()  # the slots run on this host, with this numpy
        self._lock = threading.RLock()
        self._wake = threading.Condition(self._lock)
        self._stop = threading.Event()
        self._abort = threading.Event()
        self._hinted = threading.Event()  # a wake hint since the last lease request
        self._active: dict[str, _Active] = {}  # leases held: running or queued
        self._queue: deque[list[Lease]] = deque()  # groups waiting for a free slot
        self._pending: dict[tuple[str, int], _Pending] = {}
        self._dropped: set[str] = set()
        self.unproven_drops = 0  # drops (acks, cancels) ignored for want of a valid proof
        self._slots: list[Slot] = []
        self._session: Any = None
        self._zenoh: Any = None
        self.runs_done = 0
        self.leases_done = 0
        self._closing = False
        self._seq = 0  # puts of results so far
        self._acked_seq = 0  # highest put with an acknowledged result
        self._last_ack = time.monotonic()
        self._last_busy = 0.0
        self.scenarios = ByteLRU(settings.scenario_cache_bytes)  # fetched scenarios by hash
        self.capabilities = Capabilities()  # what it can run (plugins loaded now)

    # ------------------------------------------------------------------------------ control
    def stop(self) -> None:
        """Graceful stop (idempotent); a second call aborts running leases at once."""
        if self._stop.is_set():
            self._abort.set()
        self._stop.set()
        self._hinted.set()
        with self._wake:
            self._wake.notify_all()

    def install_signal_handlers(self) -> None:
        def handler(signum: int, _frame: Any) -> None:
            name = signal.Signals(signum).name
            if self._stop.is_set():
                log.warning("%s again: aborting running leases", name)
            else:
                log.info("%s: finishing (at most %.0f s), then leaving", name,
                         self.settings.grace_seconds)
            self.stop()

        signal.signal(signal.SIGTERM, handler)
        signal.signal(signal.SIGINT, handler)

    # ---------------------------------------------------------------------------------- run
    def run(self) -> int:
        self._slots = [self.new_slot(i) for i in range(self.settings.slots)]
        for slot in self._slots:
            if isinstance(slot, ProcessSlot):
                slot.on_ready = self._slot_ready
            slot.start()
        if self.settings.exit_with_parent:
            threading.Thread(target=self._watch_parent, daemon=True).start()
        try:
            if not self._open():
                return 1
            self._declare()
            threads = [
                threading.Thread(target=self._heartbeat_loop, name="heartbeat", daemon=True),
                threading.Thread(target=self._resend_loop, name="resend", daemon=True),
            ]
            for t in threads:
                t.start()
            log.info("worker %s ready: %d %s slot(s), pulling from %s", self.id,
                     len(self._slots), self.settings.executor, ", ".join(self.settings.connect))
            self._pull_loop()
            self._drain()
            return 0
        finally:
            self._shutdown()

    def new_slot(self, index: int) -> Slot:
        """Slot ``index`` of this worker (the settings' executor; a subclass may run leases
        elsewhere, e.g. scripts/bench/farm.py's simulated slots)."""
        if self.settings.executor == "process":
            return ProcessSlot(index, self._on_slot_done, self.settings.stacking,
                               warm=self.settings.warm)
        return ThreadSlot(index, self._on_slot_done, self.settings.stacking)

    def _slot_ready(self) -> None:
        with self._wake:
            self._wake.notify_all()

    def _watch_parent(self) -> None:
        while not self._stop.wait(0.5):
            if os.getppid() != self.settings.exit_with_parent:
                log.warning("parent process %s is gone: stopping", self.settings.exit_with_parent)
                self.stop()
                return

    def _open(self) -> bool:
        import zenoh

        from swarmpath.service.zenoh_config import describe, to_zenoh

        self._zenoh = zenoh
        conf = self.settings.zenoh_config()
        complained = False
        while not self._stop.is_set():
            try:
                self._session = zenoh.open(to_zenoh(conf))
                log.info("%s", describe(conf))
                return True
            except Exception as exc:
                if not complained:
                    log.warning("cannot open %s (%s); retrying until it answers",
                                describe(conf), " ".join(str(exc).split())[:200])
                    complained = True
                self._stop.wait(1.0)
        return False

    def _declare(self) -> None:
        s = self._session
        self._token = s.liveliness().declare_token(self.keys.worker_token(self.id))
        self._subs = [
            s.declare_subscriber(self.keys.ack(self.id), self._on_ack),
            s.declare_subscriber(self.keys.cancel, self._on_cancel),
            s.declare_subscriber(self.keys.wake, self._on_wake),
        ]
        self._querier = s.declare_querier(
            self.keys.work, timeout=self.settings.query_timeout,
            target=self._zenoh.QueryTarget.BEST_MATCHING,
        )

    # ---------------------------------------------------------------------------- dispatching
    def _free_slot(self) -> Slot | None:
        for slot in self._slots:
            if not slot.busy and not any(a.slot is slot for a in self._active.values()):
                return slot
        return None

    def _dispatch(self) -> None:
        """Start queued groups on free slots."""
        while True:
            with self._lock:
                if not self._queue or self._stop.is_set():  # stopping: _drain forgets them
                    return
                slot = self._free_slot()
                if slot is None:
                    return
                group = [lease for lease in self._queue.popleft()
                         if lease.lease_id in self._active]
                if not group:
                    continue
                for lease in group:
                    self._active[lease.lease_id].slot = slot
                slot.leases = group  # busy from now on (submit sets it again)
            slot.submit(group)

    # --------------------------------------------------------------------------- heartbeat
    def _heartbeat_loop(self) -> None:
        while not self._closing:
            time.sleep(0.25)
            self.heartbeat_due()

    def heartbeat_due(self, now: float | None = None) -> int:
        """RunProgress for each running lease not reported for half its heartbeat_seconds."""
        now = time.monotonic() if now is None else now
        with self._lock:
            due = [a for a in self._active.values()
                   if now - a.last_progress >= 0.5 * a.lease.heartbeat_seconds]
            for a in due:
                a.last_progress = now
                a.beats += 1
        for a in due:
            lease = a.lease
            spec = lease.spec
            total = spec.iterations * len(
                benchmark_batches(lease.runs, spec.agents, spec.dim)
            ) if isinstance(spec, BenchmarkCell) else 0
            msg = RunProgress(
                lease_id=lease.lease_id, job_id=lease.job_id, worker=self.id,
                cell=lease.cell, runs=list(lease.runs),
                iteration=a.slot.iteration(lease.lease_id) if a.slot is not None else 0,
                iterations=total, seq=a.beats,
                proof=progress_proof(lease.capability, lease.lease_id, a.beats),
            )
            self._put(self.keys.progress(lease.job_id), encode(msg))
        return len(due)

    # ---------------------------------------------------------------------------- stopping
    def _drain(self) -> None:
        """Stop: let running leases finish (grace), abort the rest, wait for the acks."""
        deadline = time.monotonic() + self.settings.grace_seconds
        with self._wake:
            # leases not started yet are left to the coordinator (requeued when we leave)
            for group in self._queue:
                for lease in group:
                    a = self._active.get(lease.lease_id)
                    if a is not None and a.slot is None:
                        self._dropped.add(lease.lease_id)
                        del self._active[lease.lease_id]
            self._queue.clear()
            while self._active and not self._abort.is_set() and time.monotonic() < deadline:
                self._wake.wait(0.25)
            if self._active:
                log.info("aborting %d running leases; the coordinator requeues them",
                         len(self._active))
                for a in list(self._active.values()):
                    self._dropped.add(a.lease.lease_id)
                    self._abandon(a)
            stop_at = time.monotonic() + 3.0
            while self._active and time.monotonic() < stop_at:
                self._wake.wait(0.25)
            ack_deadline = time.monotonic() + self.settings.ack_timeout
            if self._pending:
                self._resend_all()
            while self._pending and not self._abort.is_set() and time.monotonic() < ack_deadline:
                self._wake.wait(0.25)
            if self._pending:
                log.warning("%d results not acknowledged at exit: the coordinator requeues "
                            "their runs", len(self._pending))

    def _shutdown(self) -> None:
        self._closing = True
        for entity in (getattr(self, "_querier", None), *getattr(self, "_subs", []),
                       getattr(self, "_token", None)):
            if entity is None:
                continue
            try:
                entity.undeclare()
            except Exception:  # pragma: no cover
                log.debug("undeclare failed", exc_info=True)
        self._subs = []
        self._token = None
        self._querier = None
        if self._session is not None:
            try:
                self._session.close()
            except Exception:  # pragma: no cover
                log.debug("closing the session failed", exc_info=True)
            self._session = None
        for slot in self._slots:
            slot.close(timeout=3.0)
        log.info("worker %s stopped: %d leases, %d runs", self.id, self.leases_done,
                 self.runs_done)


def run_worker(settings: WorkerSettings, *, signals: bool = True) -> int:
    """Run a worker until SIGTERM/SIGINT (the ``swarmpath worker`` command)."""
    worker = Worker(settings)
    if signals:
        worker.install_signal_handlers()
    return worker.run()
