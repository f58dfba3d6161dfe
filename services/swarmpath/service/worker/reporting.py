"""The worker's reporting side: results put until acknowledged (with backoff), acks,
``drop_leases`` and ``Cancel`` honoured."""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from swarmpath.service.capability import drop_ok
from swarmpath.service.protocol import (
    Ack,
    Cancel,
    Keys,
    Lease,
    LeaseDrop,
    decode,
)
from swarmpath.service.worker.execution import Cancelled, _result
from swarmpath.service.worker.extensions import unavailable
from swarmpath.service.worker.packing import fit_result, pack_lease_columns
from swarmpath.service.worker.settings import WorkerSettings
from swarmpath.service.worker.slots import NotRun, Outcomes, Slot

log = logging.getLogger("swarmpath.worker")

#: Leases dropped or given up, remembered so their late outcomes are discarded (then forgotten).
DROPPED_LEASES = 10_000


@dataclass
class _Active:
    lease: Lease
    slot: Slot | None  # None while the lease waits in the queue
    received: float
    last_progress: float
    beats: int = 0  # progress messages sent (their seq)


@dataclass
class _Pending:
    job_id: str
    lease_id: str
    data: bytes
    capability: str = ""
    sent: float = 0.0
    seq: int = 0  # of the put that last carried it
    attempts: int = 0


class Reporting:
    """Mixin of :class:`~swarmpath.service.worker.loop.Worker`: what becomes of a lease's
    outcome. The state it uses is created by ``Worker.__init__``."""

    settings: WorkerSettings
    id: str
    keys: Keys
    _lock: threading.RLock
    _wake: threading.Condition
    _stop: threading.Event
    _abort: threading.Event
    _active: dict[str, _Active]
    _queue: deque[list[Lease]]
    _pending: dict[tuple[str, int], _Pending]
    _dropped: set[str]
    capabilities: Any  # worker.extensions.Capabilities
    unproven_drops: int
    _session: Any
    _zenoh: Any
    runs_done: int
    leases_done: int
    _closing: bool
    _seq: int
    _acked_seq: int
    _last_ack: float
    _last_busy: float  # when a lease request was last answered "busy" (0: never)

    def _dispatch(self) -> None:  # the Worker's
        raise NotImplementedError

    def _on_slot_done(self, slot: Slot, outcomes: Outcomes) -> None:
        done: list[tuple[Lease, list[tuple[int, bytes]]]] = []
        again: list[Lease] = []
        with self._lock:
            for lease, outcome in outcomes:
                dropped = lease.lease_id in self._dropped
                held = self._active.get(lease.lease_id)
                if isinstance(outcome, NotRun) and held is not None and not dropped \
                        and not self._stop.is_set():
                    held.slot = None
                    again.append(lease)
                    continue
                self._active.pop(lease.lease_id, None)
                if isinstance(outcome, Cancelled | NotRun) or dropped:
                    log.info("lease %s (%s) dropped", lease.lease_id, lease.cell)
                elif unavailable(outcome):  # no code for it in the slot: not a failed run
                    log.warning("lease %s not run: %s", lease.lease_id, outcome)
                    self.capabilities.refuse(lease.pins, str(outcome))
                elif isinstance(outcome, BaseException):
                    text = f"{type(outcome).__name__}: {outcome}"
                    log.error("lease %s failed as a whole: %s", lease.lease_id, text)
                    done.append((lease, [
                        (r, fit_result(_result(lease, r, 0.0, status="failed",
                                               failure=text[:20_000]),
                                       capability=lease.capability))
                        for r in lease.runs
                    ]))
                else:
                    done.append((lease, outcome))
                    self.leases_done += 1
                    self.runs_done += len(outcome)
            if again:
                self._queue.appendleft(again)
        try:
            self._dispatch()  # the next group first: the slot is free again
            self._publish_many(done)
        except Exception:  # never lose the slot thread silently; the lease expires and requeues
            log.exception("handling the outcome of a group of %d leases failed", len(outcomes))
        finally:
            with self._wake:
                self._wake.notify_all()

    def _publish_results(self, lease: Lease, results: list[tuple[int, bytes]]) -> None:
        self._publish_many([(lease, results)])

    def _publish_many(self, items: Sequence[tuple[Lease, list[tuple[int, bytes]]]]) -> None:
        """Results of finished leases: remembered until acknowledged, put once per job (in
        batches of at most BATCH_BYTES)."""
        by_job: dict[str, list[_Pending]] = {}
        with self._lock:
            for lease, results in items:
                for run, data in results:
                    entry = _Pending(lease.job_id, lease.lease_id, data, lease.capability)
                    self._pending[(lease.lease_id, run)] = entry
                    by_job.setdefault(lease.job_id, []).append(entry)
        for job_id, entries in by_job.items():
            self._send(job_id, entries)

    def _send(self, job_id: str, entries: list[_Pending]) -> None:
        """Put results (in batches) and note when and in which put they went."""
        with self._lock:
            self._seq += 1
            now = time.monotonic()
            for e in entries:
                e.sent, e.seq = now, self._seq
                e.attempts += 1
        key = self.keys.results(job_id)
        for payload in pack_lease_columns(self.id, [(e.lease_id, e.capability, e.data)
                                                    for e in entries]):
            self._put(key, payload)

    def _put(self, key: str, payload: bytes) -> None:
        try:
            self._session.put(
                key, payload, encoding=self._zenoh.Encoding.APPLICATION_JSON,
                congestion_control=self._zenoh.CongestionControl.BLOCK,
            )
        except Exception as exc:
            log.warning("put on %s failed (will retry): %s", key, exc)

    def _on_ack(self, sample: Any) -> None:
        """Zenoh callback: quick bookkeeping only."""
        try:
            ack = decode(Ack, sample.payload.to_bytes())
        except Exception as exc:
            log.warning("ignored a malformed ack: %s", " ".join(str(exc).split())[:200])
            return
        settled = ack.statuses()
        with self._wake:
            if settled:
                self._last_ack = time.monotonic()
            for lease_id, run, status in settled:
                entry = self._pending.pop((lease_id, run), None)
                if entry is not None:
                    self._acked_seq = max(self._acked_seq, entry.seq)
                if status == "stale":
                    log.info("result of run %d was stale (%s)", run, lease_id)
            for drop in ack.drop_leases:
                self._drop_proven(drop, "coordinator dropped")
            self._wake.notify_all()

    def _on_cancel(self, sample: Any) -> None:
        try:
            msg = decode(Cancel, sample.payload.to_bytes())
        except Exception as exc:
            log.warning("ignored a malformed cancel: %s", " ".join(str(exc).split())[:200])
            return
        with self._wake:
            for drop in msg.leases:
                self._drop_proven(drop, f"job {msg.job_id} cancelled: dropping")
            self._wake.notify_all()

    def _capability(self, lease_id: str) -> str | None:
        active = self._active.get(lease_id)
        if active is not None:
            return active.lease.capability
        for p in self._pending.values():
            if p.lease_id == lease_id:
                return p.capability
        return None

    def _drop_proven(self, drop: LeaseDrop, why: str) -> bool:
        """Drop a lease we hold when the order proves it comes from the coordinator (the HMAC of
        the lease id with its capability, which only the coordinator and we know)."""
        cap = self._capability(drop.lease_id)
        if cap is None:
            return False  # not ours (any more): nothing to do
        if not drop_ok(cap, drop.lease_id, drop.proof):
            self.unproven_drops += 1
            log.warning("ignored a drop of lease %s without a valid proof (not from the "
                        "coordinator)", drop.lease_id)
            return False
        log.info("%s lease %s", why, drop.lease_id)
        self._drop(drop.lease_id)
        return True

    def _drop(self, lease_id: str) -> None:
        self._dropped.add(lease_id)
        if len(self._dropped) > DROPPED_LEASES:
            self._dropped = {lease_id}
        active = self._active.get(lease_id)
        if active is not None:
            self._abandon(active)
        for key in [k for k, p in self._pending.items() if p.lease_id == lease_id]:
            del self._pending[key]

    def _abandon(self, active: _Active) -> None:
        """Stop a held lease: cancel it in its slot, or forget it if it has not started."""
        if active.slot is not None:
            active.slot.cancel(active.lease.lease_id)
        else:
            self._active.pop(active.lease.lease_id, None)  # _dispatch skips it

    def _resend_all(self) -> None:
        with self._lock:
            for p in self._pending.values():
                p.sent = 0.0

    def _resend_loop(self) -> None:
        while self._session is not None and not self._abort.is_set():
            time.sleep(0.25)
            self.resend_due()
            if self._closing:
                return

    def resend_due(self, now: float | None = None) -> int:
        """Put again what was not acknowledged within ack_timeout (doubling, at most 30 s) -
        unless acks keep coming for earlier puts, or lease requests are answered ``busy``
        (back-pressure): the coordinator handles each worker's messages in order, so it is busy,
        not deaf, and re-sending would only add duplicates to its queue.
        A result is re-sent at once when a later put was acknowledged before it (it was lost)
        or after an outage (``_resend_all``). Returns how many results were put again."""
        now = time.monotonic() if now is None else now
        due: dict[str, list[_Pending]] = {}
        with self._lock:
            silent = now - max(self._last_ack, self._last_busy) >= self.settings.ack_timeout
            for p in self._pending.values():
                wait = min(30.0, self.settings.ack_timeout * 2 ** max(0, p.attempts - 1))
                overtaken = p.seq < self._acked_seq
                if p.sent == 0.0 or (now - p.sent >= wait and (silent or overtaken)):
                    due.setdefault(p.job_id, []).append(p)
        for job_id, entries in due.items():
            log.info("re-sending %d unacknowledged results of job %s", len(entries), job_id)
            self._send(job_id, entries)
        return sum(len(v) for v in due.values())
