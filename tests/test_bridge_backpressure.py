"""The coordinator's back-pressure: while result batches wait to be stored beyond about a second
of work, lease requests are answered no_work "busy" (no network: the bridge's lease thread is
fed fake queries)."""

from __future__ import annotations

import threading
from types import SimpleNamespace

from swarmpath.service.bridge import ZenohBridge
from swarmpath.service.coordinator import Coordinator, CoordinatorSettings
from swarmpath.service.protocol import (
    BenchmarkJobSpec,
    LeaseRequest,
    NoWork,
    decode_work_reply,
    encode,
)


class FakeQuery:
    def __init__(self, payload: bytes) -> None:
        self.payload = SimpleNamespace(to_bytes=lambda: payload)
        self.key_expr = "swarmpath/work"
        self.replies: list[bytes] = []
        self.answered = threading.Event()

    def reply(self, _key: str, payload: bytes, **_kw: object) -> None:
        self.replies.append(payload)

    def drop(self) -> None:
        self.answered.set()


def ask(bridge: ZenohBridge) -> object:
    query = FakeQuery(encode(LeaseRequest(worker="w1", max_runs=5)))
    bridge._work.put(query)
    assert query.answered.wait(10)
    return decode_work_reply(query.replies[0])


def test_lease_requests_get_busy_while_results_wait(tmp_path):
    core = Coordinator(CoordinatorSettings(data_dir=tmp_path, synchronous="NORMAL"))
    bridge = ZenohBridge(core, {})
    bridge._zenoh = SimpleNamespace(Encoding=SimpleNamespace(APPLICATION_JSON=None))
    thread = threading.Thread(target=bridge._serve_work, daemon=True)
    thread.start()
    try:
        core.submit(BenchmarkJobSpec(kind="benchmark", algorithms=["GWO"], functions=["F1"],
                                     dims=[2], runs=20, agents=2, iterations=5))
        core.worker_alive("w1")
        assert bridge.busy_bytes() == bridge.BUSY_MIN_BYTES  # nothing measured yet
        with bridge._queued_lock:
            bridge._queued[:] = [3, bridge.BUSY_MIN_BYTES + 1]
        reply = ask(bridge)
        assert isinstance(reply, NoWork) and reply.reason.startswith("busy")
        assert reply.retry_after == bridge.BUSY_RETRY and core.stats["busy"] == 1
        assert "swarmpath_lease_requests_busy_total 1" in core.metrics_text()
        bridge._drain_rate = 10 * bridge.BUSY_MIN_BYTES / bridge.BUSY_SECONDS  # a fast drain
        assert bridge.busy_bytes() == 10 * bridge.BUSY_MIN_BYTES
        assert not isinstance(ask(bridge), NoWork)  # the same backlog is now < 1 s of work
        bridge._drain_rate = 1e12
        assert bridge.busy_bytes() == bridge.BUSY_MAX_BYTES
    finally:
        bridge._work.put(None)
        thread.join(10)
        core.close()


def test_a_worker_told_busy_does_not_resend_its_unacknowledged_results():
    import time

    from swarmpath.service.protocol import BenchmarkCell
    from swarmpath.service.worker import execute_lease
    from test_service_api import make_lease, offline_worker

    w = offline_worker(ack_timeout=5.0)
    spec = BenchmarkCell(algorithm="PSO", function="F1", dim=2, agents=5, iterations=3)
    lease = make_lease(spec, [0, 1])
    w._publish_results(lease, execute_lease(lease))
    t = time.monotonic()
    w._last_ack = t - 100.0  # no ack for a long time ...
    w._last_busy = t + 8.0  # ... but the coordinator said "busy" 1.5 s ago: it is behind
    assert w.resend_due(t + 9.5) == 0
    assert w.resend_due(t + 13.5) == 2  # silent and not busy for ack_timeout: put again


def test_idle_workers_are_told_to_wait_longer_the_more_of_them_there_are(tmp_path):
    core = Coordinator(CoordinatorSettings(data_dir=tmp_path, synchronous="NORMAL"))
    try:
        request = encode(LeaseRequest(worker="w0"))
        core.worker_alive("w0")
        reply = decode_work_reply(core.handle_lease_request(request))
        assert isinstance(reply, NoWork) and reply.reason == "empty"
        assert reply.retry_after == core.settings.retry_after  # a small farm: as before
        for i in range(1, 600):
            core.worker_alive(f"w{i}")
        reply = decode_work_reply(core.handle_lease_request(request))
        assert isinstance(reply, NoWork)
        assert reply.retry_after == 600 / core.EMPTY_POLLS_PER_SECOND  # 30 s: 20 polls/s
    finally:
        core.close()


def test_new_work_wakes_the_workers_told_empty_and_nothing_else_does(tmp_path):
    """A submitted job puts a wake hint at once; runs requeued while a worker waits after an
    empty reply put one at the next tick; a requeue nobody waits for, or a tick without new
    work, puts none."""
    sent: list[str] = []
    core = Coordinator(CoordinatorSettings(data_dir=tmp_path, synchronous="NORMAL",
                                           lease_seconds=30.0),
                       publish=lambda key, _payload: sent.append(key))
    spec = BenchmarkJobSpec(kind="benchmark", algorithms=["GWO"], functions=["F1"], dims=[2],
                            runs=20, agents=2, iterations=5)
    wakes = lambda: sent.count("swarmpath/wake")  # noqa: E731
    try:
        core.worker_alive("w1")
        t = 1000.0
        core.submit(spec)
        assert wakes() == 1
        request = encode(LeaseRequest(worker="w1", max_runs=100, max_leases=32))
        assert not isinstance(decode_work_reply(core.handle_lease_request(request, t)), NoWork)
        core.tick(t)
        core.tick(t + 31.0)  # the lease expired: its runs are requeued, but nobody waits
        assert wakes() == 1
        assert not isinstance(decode_work_reply(core.handle_lease_request(request, t + 32)),
                              NoWork)
        empty = decode_work_reply(core.handle_lease_request(request, t + 33))
        assert isinstance(empty, NoWork) and empty.reason == "empty"
        core.tick(t + 34)  # nothing new
        assert wakes() == 1
        core.tick(t + 64.0)  # expired again, and w1 waits: woken
        assert wakes() == 2
        core.tick(t + 65.0)
        assert wakes() == 2  # once
    finally:
        core.close()


class Replies:
    """A querier answering every lease request ``empty``, ask again in 600 s."""

    def __init__(self, on_ask) -> None:
        self.asked: list[float] = []
        self.on_ask = on_ask

    def get(self, payload: bytes) -> list[object]:
        import time

        self.asked.append(time.monotonic())
        self.on_ask(len(self.asked))
        empty = encode(NoWork(retry_after=600.0, reason="empty"))
        return [SimpleNamespace(ok=SimpleNamespace(payload=SimpleNamespace(
            to_bytes=lambda: empty)))]


def test_a_worker_told_empty_asks_again_when_woken_and_not_before_the_hint_min_wait():
    from swarmpath.service.worker.pulling import HINT_MIN_WAIT
    from test_service_api import offline_worker

    for hint_in_flight in (False, True):
        w = offline_worker(executor="thread")
        w._slots = [w.new_slot(0)]

        def on_ask(n: int, w=w, in_flight=hint_in_flight) -> None:
            if n == 1 and in_flight:
                w._on_wake(None)  # the hint overtook the "empty" reply: it counts
            if n == 2:
                w.stop()

        w._querier = Replies(on_ask)
        loop = threading.Thread(target=w._pull_loop, daemon=True)
        loop.start()
        if not hint_in_flight:
            while not w._querier.asked:
                loop.join(0.05)
            w._on_wake(None)
        loop.join(60)  # without the hint: 600 s
        assert not loop.is_alive()
        first, second = w._querier.asked
        assert second - first >= HINT_MIN_WAIT
