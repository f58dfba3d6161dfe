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
