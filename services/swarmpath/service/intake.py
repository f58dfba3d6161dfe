"""What the workers report, as the coordinator takes it: result batches (fenced by the store,
proven by their lease capability, stored in one transaction per group, recorded in the MCAP and
the dashboard, acknowledged) and progress (proven, renewing the lease or answered with a drop).
A mixin of :class:`~swarmpath.service.coordinator.Coordinator`, which owns the state it uses."""

from __future__ import annotations

import logging
import threading
import time
from collections import Counter, OrderedDict, deque
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import orjson

from swarmpath.service.capability import drop_proof, result_ok
from swarmpath.service.frame_head import RecordHead
from swarmpath.service.incoming import Incoming
from swarmpath.service.lease_sizer import LeaseSizer
from swarmpath.service.protocol import (
    Ack,
    AckStatus,
    BenchmarkCell,
    Keys,
    LeaseDrop,
    MapCell,
    ResultBatch,
    RunProgress,
    RunResult,
    decode,
    encode,
)
from swarmpath.service.recorder import Recorders
from swarmpath.service.recorder.process import RecorderProcess
from swarmpath.service.result_frame import decode_frame, is_frame, key_ok, proof_key
from swarmpath.service.settings import CoordinatorSettings
from swarmpath.service.store import FINAL_STATES, Store
from swarmpath.service.store.series import series_prefix
from swarmpath.service.util import short as _short

log = logging.getLogger("swarmpath.coordinator")

SETTLED_LEASES = 20_000  # leases remembered for recognizing re-sent results
CACHED_CAPABILITIES = 50_000  # capabilities of recent leases kept in memory


class ResultIntake:
    """Result batches and progress (see the module docstring)."""

    settings: CoordinatorSettings
    keys: Keys
    store: Store
    recorders: Recorders | RecorderProcess
    dashboard: Any
    sizer: LeaseSizer
    stats: Counter[str]
    _lock: threading.Lock
    _final_lock: threading.RLock
    _accepted: deque[tuple[float, int]]
    _jobs: dict[str, dict[str, Any]]
    _recording: set[str]
    _settled: OrderedDict[str, tuple[str, str, set[int]]]
    _caps: OrderedDict[str, str]
    _seen: Callable[..., None]
    _send: Callable[[str, bytes], None]
    finalize: Callable[[str], Path | None]

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

    def _record(self, job_id: str, results: list[Incoming], now: float) -> None:
        """Write accepted results to the job's MCAP (the store has them already); a recorder
        process is told to read them from the store."""
        info = self._job_info(job_id)
        if info is None:
            return
        with self._final_lock:
            if self.recorders.ready(job_id):  # finalized meanwhile (e.g. cancelled)
                return
            self._recording.add(job_id)
            if isinstance(self.recorders, RecorderProcess):
                self.recorders.poke(job_id, {w: p for w in {r.worker for r in results}
                                             if (p := self.worker_table.platform(w))})
                return
            for r in results:
                idx, spec, _parsed = info["cells"][r.cell]
                record: dict[str, Any] = {
                    "job_id": job_id, "kind": info["kind"],
                    "run_id": idx * info["rpc"] + r.run, "cell_index": idx, "cell": r.cell,
                    "spec": spec, "run": r.run, "seed": info["seed"], "worker": r.worker,
                    "lease_id": r.lease_id, "status": r.status, "failure": r.failure,
                    "seconds": r.seconds, "metrics": r.metrics, "created": now,
                }
                record.update(r.series())
                record["platform"] = self.worker_table.platform(r.worker)
                self.recorders.add(job_id, record)

    def handle_results(self, key: str, payload: bytes, now: float | None = None) -> Ack | None:
        """A ResultBatch on ``results/<job>``: store (one transaction), record, acknowledge.
        Malformed batches are logged and dropped (None)."""
        return self.handle_result_batches([(key, payload)], now)[0]

    def _decode_batch(self, key: str, payload: bytes) -> tuple[str, list[Incoming]] | None:
        """A result message (a result frame, or a JSON ResultBatch) as (worker, its results); a
        result is proven (``capability`` set) when it names this message's job and worker and
        its proof holds. None: malformed, dropped."""
        try:
            if is_frame(payload):
                return self._decode_frame(key, payload)
            return self._decode_json(key, decode(ResultBatch, payload))
        except Exception as exc:
            self.stats["malformed"] += 1
            log.warning("dropped a malformed result batch on %s: %s", key, _short(exc))
            return None

    def _decode_frame(self, key: str, payload: bytes) -> tuple[str, list[Incoming]]:
        job_id = Keys.last_chunk(key)
        worker, records = decode_frame(payload)
        entries: list[Incoming] = []
        keys: dict[str, tuple[str, bytes] | None] = {}  # lease -> (capability, its HMAC key)
        foreign = unproven = 0
        declared: Any = None  # the last record's array declarations and their series prefix
        prefix: bytes | None = None
        for rec in records:
            h = rec.head
            if h.job_id != job_id or h.worker != worker:
                foreign += 1
                entries.append(_identity(h))
                continue
            if h.lease_id in keys:
                found = keys[h.lease_id]
            else:
                cap = self._capability(h.lease_id)
                found = keys[h.lease_id] = None if cap is None else (cap, proof_key(cap))
            # no valid proof, no store round trip (a flood of forged results costs no fsync)
            if found is None or not key_ok(found[1], rec):
                unproven += 1
                entries.append(_identity(h))
                continue
            if h.arrays != declared:  # records of a lease mostly declare the same arrays
                declared, prefix = h.arrays, series_prefix(h.arrays)
            arrays = rec.arrays
            entries.append(Incoming(
                h.lease_id, h.job_id, h.cell, h.run, h.worker, h.status, h.failure, h.seconds,
                h.metrics, arrays.get("curve"), arrays.get("best_position"), arrays.get("path"),
                found[0], None if prefix is None else prefix + rec.raw))
        self._count_foreign(foreign, worker)
        self._count_unproven(unproven)
        return worker, entries

    def _decode_json(self, key: str, batch: ResultBatch) -> tuple[str, list[Incoming]]:
        job_id = Keys.last_chunk(key)
        entries: list[Incoming] = []
        foreign = unproven = 0
        for r in batch.results:
            if r.job_id != job_id or r.worker != batch.worker:
                foreign += 1
                entries.append(_unproven(r))
                continue
            cap = self._capability(r.lease_id)
            if cap is not None and result_ok(cap, r):
                entries.append(Incoming.from_result(r, cap))
            else:
                unproven += 1
                entries.append(_unproven(r))
        self._count_foreign(foreign, batch.worker)
        self._count_unproven(unproven)
        return batch.worker, entries

    @staticmethod
    def _count_foreign(n: int, worker: str) -> None:
        if n:
            log.warning("%d results of %s name another job or worker than their batch: stale",
                        n, worker)

    def _count_unproven(self, n: int) -> None:
        if n:
            self.stats["unproven"] += n
            self.stats["unproven_results"] += n
            if self.stats["unproven_results"] == n:
                log.warning("results without a valid proof of their lease's capability "
                            "(counted in swarmpath_messages_unproven_total): stale")

    def handle_result_batches(
        self, messages: Sequence[tuple[str, bytes]], now: float | None = None,
        parse_acks: bool = True,
    ) -> list[Ack | None]:
        """Several result messages (key, payload) at once - group commit: the results of all
        of them are stored in one transaction (one fsync), then each message is recorded and
        acknowledged to its worker (one Ack, statuses per lease). Returns each message's Ack
        (None: malformed, dropped; all None when ``parse_acks`` is False: the Ack is only put)."""
        now = time.time() if now is None else now
        batches = [self._decode_batch(key, payload) for key, payload in messages]
        status: dict[int, AckStatus] = {}
        todo: list[Incoming] = []
        with self._lock:  # re-sent copies of results stored moments ago: no store round trip
            for item in batches:
                if item is None:
                    continue
                self._seen(item[0], now)
                for r in item[1]:
                    if r.capability is None:
                        continue
                    owner, cap, runs = self._settled.get(r.lease_id, ("", "", ()))
                    if owner == r.worker and r.run in runs and cap == r.capability:
                        status[id(r)] = "duplicate"
                        self.stats["duplicates_fast"] += 1
                    else:
                        todo.append(r)
        statuses = self.store.accept_results(todo, now) if todo else []
        accepted: dict[str, list[Incoming]] = {}
        with self._lock:
            for r, s in zip(todo, statuses, strict=True):
                status[id(r)] = s
                if s == "stale":
                    continue
                # the lease exists, is r.worker's and r proved its capability
                entry = self._settled.get(r.lease_id)
                if entry is None:
                    entry = self._settled[r.lease_id] = (r.worker, r.capability or "", set())
                else:
                    self._settled.move_to_end(r.lease_id)
                entry[2].add(r.run)
                if s == "accepted":
                    accepted.setdefault(r.job_id, []).append(r)
            while len(self._settled) > SETTLED_LEASES:
                self._settled.popitem(last=False)
        for job_id, results in accepted.items():
            self._after_accept(job_id, results, now)
        acks: list[Ack | None] = []
        for item in batches:
            if item is None:
                acks.append(None)
                continue
            worker, entries = item
            per_lease: dict[str, dict[str, list[int]]] = {}
            for r in entries:
                lease = per_lease.get(r.lease_id)
                if lease is None:
                    lease = per_lease[r.lease_id] = {"accepted": [], "duplicate": [], "stale": []}
                lease[status.get(id(r), "stale")].append(r.run)
            payload = orjson.dumps({
                "worker": worker, "results": [],
                "leases": [{"lease_id": lease_id, **runs} for lease_id, runs in per_lease.items()],
                "drop_leases": [],
            })
            self._send(self.keys.ack(worker), payload)
            acks.append(Ack.model_validate_json(payload) if parse_acks else None)
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

    def _after_accept(self, job_id: str, accepted: list[Incoming], now: float) -> None:
        """Learn run costs, write the MCAP, finalize the job when it ended."""
        with self._lock:
            self._accepted.append((now, len(accepted)))
        info = self._job_info(job_id)
        if info is not None:
            by_cell: dict[str, list[float]] = {}
            for r in accepted:
                if r.status == "ok" and r.cell in info["cells"]:
                    by_cell.setdefault(r.cell, []).append(r.seconds)
            for cell, seconds in by_cell.items():
                try:
                    self.sizer.observe_many(info["cells"][cell][2], seconds)
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


def _unproven(r: RunResult) -> Incoming:
    """A result that proved nothing: its identity only (for its ack), never stored."""
    return Incoming(r.lease_id, r.job_id, r.cell, r.run, r.worker, r.status, None, 0.0, {})


def _identity(h: RecordHead) -> Incoming:
    """A frame record that proved nothing: its identity only (for its ack), never stored."""
    return Incoming(h.lease_id, h.job_id, h.cell, h.run, h.worker, h.status, None, 0.0, {})


def _cell(spec: Mapping[str, Any]) -> BenchmarkCell | MapCell:
    return BenchmarkCell(**spec) if spec.get("kind") == "benchmark" else MapCell(**spec)

