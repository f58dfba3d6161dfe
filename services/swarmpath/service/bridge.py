"""The coordinator's Zenoh side: opens the session as a router in this process and wires it to the
:class:`~swarmpath.service.coordinator.Coordinator`: the ``work`` queryable, the ``results/*`` and
``progress/*`` subscribers, the liveliness subscriber (with history), the ``scenarios/*``
queryable (a lease's scenario by hash, :mod:`swarmpath.service.scenarios`). Zenoh callbacks only
copy the payload into a queue; three threads do the work (one answers lease queries, one
scenario queries, one handles results, progress and liveliness in arrival order), so a callback
never blocks the network."""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Mapping
from typing import Any

from swarmpath.service.coordinator import Coordinator
from swarmpath.service.protocol import MAX_BODY_BYTES, Keys
from swarmpath.service.scenarios import ByteLRU, ScenarioRefused, answer

log = logging.getLogger("swarmpath.coordinator")

_NOTHING = object()  # nothing held back while grouping results


class ZenohBridge:
    """The coordinator's Zenoh side (see the module docstring)."""

    GROUP_MESSAGES = 64  # result batches stored in one transaction at most ...
    GROUP_BYTES = 8_000_000  # ... and at most this many bytes of them
    #: Bounds of the two queues between Zenoh's callbacks and our threads. Beyond them input is
    #: dropped and counted (``swarmpath_messages_overload_total``): an unanswered lease query is
    #: asked again, an unacknowledged result batch is put again by its worker, the next progress
    #: message renews the lease.
    MAX_QUERIES = 1024
    MAX_EVENTS = 100_000
    MAX_EVENT_BYTES = 256_000_000
    #: Back-pressure: while the result batches waiting to be stored would take more than
    #: BUSY_SECONDS to handle at the rate the events thread has been handling them (bounded by
    #: BUSY_MIN_BYTES and BUSY_MAX_BYTES), lease requests are answered ``no_work`` ("busy", ask
    #: again after BUSY_RETRY s): the workers stop adding work until the backlog drains. Without
    #: it a farm faster than the coordinator fills the queue to MAX_EVENT_BYTES: acks come tens of
    #: seconds late (so results are re-sent), progress waits behind results until leases expire
    #: and are requeued, and input is dropped (scripts/bench/farm.py, docs/scale.md).
    BUSY_SECONDS = 1.0
    BUSY_MIN_BYTES = 1_000_000
    BUSY_MAX_BYTES = 32_000_000
    BUSY_RETRY = 1.0
    #: scenario queries waiting for their thread at most, and the canonical JSON kept for them
    MAX_SCENARIO_QUERIES = 64
    SCENARIO_CACHE_BYTES = 128 * 1024 * 1024

    def __init__(self, core: Coordinator, config: Mapping[str, Any]):
        self.core = core
        self.config = dict(config)
        self.keys = core.keys
        self.session: Any = None
        self._entities: list[Any] = []
        self._work: queue.Queue[Any] = queue.Queue(self.MAX_QUERIES)
        self._scenario_queries: queue.Queue[Any] = queue.Queue(self.MAX_SCENARIO_QUERIES)
        self.scenarios = ByteLRU(self.SCENARIO_CACHE_BYTES)
        self._events: queue.SimpleQueue[Any] = queue.SimpleQueue()
        self._queued = [0, 0]  # events and their payload bytes waiting in _events
        self._queued_lock = threading.Lock()
        self._drain_rate = 0.0  # bytes/s the events thread handles results at (moving average)
        self._threads: list[threading.Thread] = []
        self._closed = False

    def start(self) -> None:
        import zenoh

        from swarmpath.service.zenoh_config import describe, to_zenoh

        self.session = zenoh.open(to_zenoh(self.config))
        self._zenoh = zenoh
        log.info("%s", describe(self.config))
        self.core.publish = self.put
        self.core.check_token = self.check_token
        for target, name in ((self._serve_work, "lease"), (self._serve_events, "events"),
                             (self._serve_scenarios, "scenarios")):
            t = threading.Thread(target=target, name=f"coordinator-{name}", daemon=True)
            t.start()
            self._threads.append(t)
        s = self.session
        self._entities = [
            s.declare_queryable(self.keys.work, self._on_query, complete=True),
            s.declare_queryable(self.keys.all_scenarios, self._on_scenario_query),
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
            self._work.put_nowait(query)
        except queue.Full:
            self.core.stats["overload"] += 1
            query.drop()  # no reply: the worker asks again after its backoff
        except Exception:  # pragma: no cover
            log.exception("queueing a lease request failed")

    def _on_scenario_query(self, query: Any) -> None:
        try:
            self._scenario_queries.put_nowait(query)
        except queue.Full:
            self.core.stats["overload"] += 1
            query.drop()  # no reply: the worker's runs fail with "no reply" and are reported
        except Exception:  # pragma: no cover
            log.exception("queueing a scenario request failed")

    def _on_results(self, sample: Any) -> None:
        self._queue_sample("results", sample)

    def _on_progress(self, sample: Any) -> None:
        self._queue_sample("progress", sample)

    def _queue_sample(self, kind: str, sample: Any) -> None:
        try:
            payload = sample.payload.to_bytes()
            with self._queued_lock:
                if self._queued[0] >= self.MAX_EVENTS or \
                        self._queued[1] + len(payload) > self.MAX_EVENT_BYTES:
                    self.core.stats["overload"] += 1
                    return
                self._queued[0] += 1
                self._queued[1] += len(payload)
            self._events.put((kind, str(sample.key_expr), payload))
        except Exception:  # pragma: no cover
            log.exception("queueing a %s message failed", kind)

    def _taken(self, item: Any) -> Any:
        """Bookkeeping of an item taken from _events."""
        if item is not None and item[0] in ("results", "progress"):
            with self._queued_lock:
                self._queued[0] -= 1
                self._queued[1] -= len(item[2])
        return item

    def busy_bytes(self) -> float:
        """The backlog (bytes) beyond which lease requests are answered busy."""
        return min(self.BUSY_MAX_BYTES, max(self.BUSY_MIN_BYTES,
                                            self._drain_rate * self.BUSY_SECONDS))

    def backlog(self) -> int:
        """Bytes of result and progress messages waiting for the events thread."""
        with self._queued_lock:
            return self._queued[1]

    def check_token(self, worker: str) -> None:
        """Look a worker's liveliness token up (without waiting): if it is there, the worker is
        admitted as when its token appeared (Coordinator._check_token rate-limits the calls)."""
        if self._closed or self.session is None:
            return

        def found(reply: Any) -> None:
            try:
                if reply.ok is not None:
                    self.core.worker_alive(Keys.last_chunk(str(reply.ok.key_expr)))
            except Exception:  # pragma: no cover
                log.exception("handling a liveliness reply failed")

        self.session.liveliness().get(self.keys.worker_token(worker), found, timeout=5.0)

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
                busy = self.backlog()
                if len(payload) > MAX_BODY_BYTES:
                    reply = self.core._no_work("lease request too large", 5.0)
                elif busy > self.busy_bytes():
                    self.core.stats["busy"] += 1
                    reply = self.core._no_work(
                        f"busy: {busy / 1e6:.0f} MB of results waiting", self.BUSY_RETRY)
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

    def _serve_scenarios(self) -> None:
        """Answer ``scenarios/<sha256>`` queries (:func:`swarmpath.service.scenarios.answer`)."""
        store = self.core.store
        while True:
            query = self._scenario_queries.get()
            if query is None:
                return
            try:
                payload = query.payload.to_bytes() if query.payload is not None else b""
                try:
                    if len(payload) > MAX_BODY_BYTES:
                        raise ScenarioRefused("scenario request too large")
                    data = answer(str(query.key_expr), payload, store.lease_scenario_ref,
                                  store.lease_scenario, self.scenarios)
                except ScenarioRefused as exc:
                    self.core.stats["malformed"] += 1
                    log.warning("refused a scenario request: %s", exc)
                    query.reply_err(str(exc).encode())
                else:
                    query.reply(query.key_expr, data,
                                encoding=self._zenoh.Encoding.APPLICATION_JSON)
            except Exception:
                log.exception("answering a scenario request failed")
            finally:
                try:
                    query.drop()
                except Exception:  # pragma: no cover
                    pass

    def _serve_events(self) -> None:
        held: Any = _NOTHING  # an item taken from the queue while grouping results
        while True:
            item = self._taken(self._events.get()) if held is _NOTHING else held
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
                            nxt = self._taken(self._events.get_nowait())
                        except queue.Empty:
                            break
                        if nxt is None or nxt[0] != "results":
                            held = nxt
                            break
                        group.append((nxt[1], nxt[2]))
                        size += len(nxt[2])
                    started = time.perf_counter()
                    self.core.handle_result_batches(group, parse_acks=False)
                    rate = size / max(time.perf_counter() - started, 1e-6)
                    self._drain_rate += 0.2 * (rate - self._drain_rate)
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
        self._scenario_queries.put(None)
        for t in self._threads:
            t.join(timeout=10.0)
        self._closed = True
        if self.session is not None:
            try:
                self.session.close()
            except Exception:  # pragma: no cover
                log.debug("closing the zenoh session failed", exc_info=True)
        self.core.publish = lambda key, payload: None
        self.core.check_token = lambda worker: None
