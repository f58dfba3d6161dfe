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
        assert reply.retry_after == 600 / core.EMPTY_POLLS_PER_SECOND  # 3 s: 200 polls/s in all
    finally:
        core.close()
