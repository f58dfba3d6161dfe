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
from swarmpath.service.incoming import SERIES, Incoming
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
from swarmpath.service.recorder.common import no_room
from swarmpath.service.recorder.process import RecorderProcess
from swarmpath.service.result_columns import columns_key, columns_ok, decode_message, is_columns
from swarmpath.service.result_frame import (
    RecordHead,
    decode_frame,
    is_frame,
    key_ok,
    proof_key,
)
from swarmpath.service.settings import CoordinatorSettings
from swarmpath.service.store import FINAL_STATES, Store, StoreFull
from swarmpath.service.store.columns import ResultColumns, from_frame, from_incoming, unproven
from swarmpath.service.store.series import raw_series
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
    store_full: Callable[[StoreFull, str], None]

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

    def _record(self, job_id: str, accepted: list[tuple[ResultColumns, list[int]]],
                now: float) -> None:
        """Write accepted results (columns, the indexes accepted) to the job's MCAP (the store
        has them already); a recorder process is told to read them from the store."""
        info = self._job_info(job_id)
        if info is None:
            return
        with self._final_lock:
            if self.recorders.ready(job_id):  # finalized meanwhile (e.g. cancelled)
                return
            self._recording.add(job_id)
            if isinstance(self.recorders, RecorderProcess):
                self.recorders.poke(job_id, {w: p for w in {c.worker for c, _ in accepted}
                                             if (p := self.worker_table.platform(w))})
                return
            for c, indexes in accepted:
                idx, spec, _parsed = info["cells"][c.cell]
                platform = self.worker_table.platform(c.worker)
                for k in indexes:
                    run = c.runs[k]
                    record: dict[str, Any] = {
                        "job_id": job_id, "kind": info["kind"],
                        "run_id": idx * info["rpc"] + run, "cell_index": idx, "cell": c.cell,
                        "spec": spec, "run": run, "seed": info["seed"], "worker": c.worker,
                        "lease_id": c.lease_id, "status": c.status[k],
                        "failure": c.failure[k], "seconds": c.seconds[k],
                        "cpu_seconds": c.cpu(k),
                        "metrics": c.metrics[k], "created": now,
                    }
                    for name in SERIES:
                        value = c.array(name, k)
                        if value is not None:
                            record[name] = value
                    record["platform"] = platform
                    self.recorders.add(job_id, record)

    def handle_results(self, key: str, payload: bytes, now: float | None = None) -> Ack | None:
        """A result message on ``results/<job>``: store (one transaction), record, acknowledge.
        Malformed messages are logged and dropped (None)."""
        return self.handle_result_batches([(key, payload)], now)[0]

    def _decode_batch(self, key: str, payload: bytes) -> tuple[str, list[ResultColumns]] | None:
        """A result message (a columnar frame, a record frame or a JSON ResultBatch) as (worker,
        its results as columns); columns are proven (``capability`` set) when they name this
        message's job and worker and their proof holds. None: malformed, dropped."""
        try:
            if is_columns(payload):
                return self._decode_columns(key, payload)
            if is_frame(payload):
                worker, entries = self._decode_frame(key, payload)
            else:
                worker, entries = self._decode_json(key, decode(ResultBatch, payload))
            return worker, from_incoming(entries)[0]
        except Exception as exc:
            self.stats["malformed"] += 1
            log.warning("dropped a malformed result batch on %s: %s", key, _short(exc))
            return None

    def _decode_columns(self, key: str, payload: bytes) -> tuple[str, list[ResultColumns]]:
        """A message of columnar frames: each frame proven alone, by its lease's capability."""
        frames = decode_message(payload)
        job_id = Keys.last_chunk(key)
        worker = frames[0].head.worker
        out = []
        for frame in frames:
            h = frame.head
            if h.job_id != job_id or h.worker != worker:
                self._count_foreign(len(h.runs), worker)
                out.append(unproven(h))
                continue
            cap = self._capability(h.lease_id)
            # no valid proof, no store round trip (a flood of forged frames costs no fsync)
            if cap is None or not columns_ok(columns_key(cap), frame):
                self._count_unproven(len(h.runs))
                out.append(unproven(h))
                continue
            out.append(from_frame(frame, cap))
        return worker, out

    def _decode_frame(self, key: str, payload: bytes) -> tuple[str, list[Incoming]]:
        job_id = Keys.last_chunk(key)
        worker, records = decode_frame(payload)
        entries: list[Incoming] = []
        keys: dict[str, tuple[str, bytes] | None] = {}  # lease -> (capability, its HMAC key)
        foreign = unproven = 0
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
            if found is None or not key_ok(found[1], rec):
                unproven += 1
                entries.append(_identity(h))
                continue
            arrays = rec.arrays
            entries.append(Incoming(
                h.lease_id, h.job_id, h.cell, h.run, h.worker, h.status, h.failure, h.seconds,
                h.metrics, arrays.get("curve"), arrays.get("best_position"), arrays.get("path"),
                found[0], raw_series(h.arrays, rec.raw), cpu_seconds=h.cpu_seconds))
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
        status: dict[int, list[AckStatus]] = {}  # id(columns) -> statuses run by run
        todo: list[ResultColumns] = []
        with self._lock:  # re-sent copies of results stored moments ago: no store round trip
            for item in batches:
                if item is None:
                    continue
                self._seen(item[0], now)
                for c in item[1]:
                    if c.capability is None:
                        continue
                    owner, cap, runs = self._settled.get(c.lease_id, ("", "", ()))
                    if owner == c.worker and cap == c.capability and runs \
                            and all(run in runs for run in c.runs):
                        status[id(c)] = ["duplicate"] * len(c.runs)
                        self.stats["duplicates_fast"] += len(c.runs)
                    else:
                        todo.append(c)
        try:
            results = self.store.accept_columns(todo, now) if todo else []
        except StoreFull as exc:  # nothing stored, nothing acknowledged: the workers re-send
            self.store_full(exc, "results not stored")
            return [None] * len(messages)
        accepted: dict[str, list[tuple[ResultColumns, list[int]]]] = {}
        with self._lock:
            for c, statuses in zip(todo, results, strict=True):
                status[id(c)] = statuses
                taken = [run for run, s in zip(c.runs, statuses, strict=True) if s != "stale"]
                if not taken:
                    continue
                # the lease exists, is c.worker's and c proved its capability
                entry = self._settled.get(c.lease_id)
                if entry is None:
                    entry = self._settled[c.lease_id] = (c.worker, c.capability or "", set())
                else:
                    self._settled.move_to_end(c.lease_id)
                entry[2].update(taken)
                new = [k for k, s in enumerate(statuses) if s == "accepted"]
                if new:
                    accepted.setdefault(c.job_id, []).append((c, new))
            while len(self._settled) > SETTLED_LEASES:
                self._settled.popitem(last=False)
        for job_id, results_of in accepted.items():
            self._after_accept(job_id, results_of, now)
        acks: list[Ack | None] = []
        for item in batches:
            if item is None:
                acks.append(None)
                continue
            worker, entries = item
            per_lease: dict[str, dict[str, list[int]]] = {}
            for c in entries:
                lease = per_lease.get(c.lease_id)
                if lease is None:
                    lease = per_lease[c.lease_id] = {"accepted": [], "duplicate": [], "stale": []}
                statuses = status.get(id(c))
                if statuses is None:
                    lease["stale"].extend(c.runs)
                    continue
                for run, s in zip(c.runs, statuses, strict=True):
                    lease[s].append(run)
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

    def _after_accept(self, job_id: str, accepted: list[tuple[ResultColumns, list[int]]],
                      now: float) -> None:
        """Learn run costs, write the MCAP, update the dashboard, finalize the job when it
        ended (``accepted``: columns and the indexes of their runs just stored)."""
        with self._lock:
            self._accepted.append((now, sum(len(k) for _c, k in accepted)))
        info = self._job_info(job_id)
        if info is not None:
            for c, indexes in accepted:
                if c.cell not in info["cells"]:
                    continue
                seconds = [c.seconds[k] for k in indexes if c.status[k] == "ok"]
                try:
                    self.sizer.observe_many(info["cells"][c.cell][2], seconds)
                except Exception:  # pragma: no cover - specs come from the store
                    pass
        try:
            self._record(job_id, accepted, now)
        except Exception as exc:
            if not no_room(exc):
                log.exception("recording results of job %s in its MCAP failed", job_id)
            elif isinstance(self.recorders, Recorders):  # rewritten from the store later
                self.recorders.discard(job_id)
        try:
            self.dashboard.observe_runs(job_id, [
                (c.cell, c.runs[k], c.status[k] == "ok", c.metrics[k], c.array("curve", k),
                 c.array("path", k), (c.seconds[k], c.cpu(k)))
                for c, indexes in accepted for k in indexes], now)
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
        try:
            state = self.store.heartbeat(msg.lease_id, msg.worker, now,
                                         self.settings.lease_seconds, seq=msg.seq,
                                         proof=msg.proof)
        except StoreFull as exc:  # the lease is not renewed; the next progress tries again
            self.store_full(exc, "progress not stored")
            return None
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

