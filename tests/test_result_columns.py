"""The columnar result frame (protocol 5): exact round trips, one proof over the frame's bytes
bound to the lease's capability, hostile frames refused with the reason, and the coordinator
storing, deduplicating and refusing whole frames."""

from __future__ import annotations

import json

import numpy as np
import pytest

from swarmpath.service.coordinator import Coordinator, CoordinatorSettings
from swarmpath.service.protocol import (
    PROTOCOL_VERSION,
    Ack,
    BenchmarkJobSpec,
    Lease,
    LeaseRequest,
    NoWork,
    decode,
    decode_work_reply,
    encode,
)
from swarmpath.service.result_columns import (
    ARRAY_ORDER,
    COLUMNS_MAGIC,
    LONGEST,
    ColumnsHead,
    columns_key,
    columns_ok,
    columns_proof,
    decode_columns,
    decode_message,
    encode_columns,
)
from swarmpath.service.result_frame import FrameError, RunResultHead, encode_record
from swarmpath.service.store.columns import from_frame
from swarmpath.service.store.series import decode_series, encode_series
from swarmpath.service.worker import execute_lease, pack_lease_columns

CAP = "c0de" * 16
OTHER = "beef" * 16


def record(run: int, arrays: dict[str, np.ndarray], **changes) -> bytes:
    fields = {"lease_id": "L1", "job_id": "j1", "cell": "GWO/F1/2", "run": run, "worker": "w1",
              "seconds": 0.25, "metrics": {"best_fitness": 1.5 + run, "evaluations": 40}}
    return encode_record(RunResultHead(**{**fields, **changes}), arrays, CAP)


def uniform_records(n: int = 6) -> tuple[list[bytes], list[dict[str, np.ndarray]]]:
    rng = np.random.default_rng(3)
    arrays = [{"curve": rng.random(50), "best_position": rng.random(2)} for _ in range(n)]
    arrays[1]["curve"][0] = np.inf  # non-finite values travel exactly
    return [record(i, a) for i, a in enumerate(arrays)], arrays


def ragged_records() -> tuple[list[bytes], list[dict[str, np.ndarray]]]:
    arrays: list[dict[str, np.ndarray]] = [
        {"path": np.arange(12.0).reshape(4, 3)},
        {},  # a failed run: no series
        {"path": np.zeros((0, 3))},  # an empty path
        {"path": np.arange(6.0).reshape(2, 3) / 7, "best_position": np.ones(3)},
    ]
    recs = [record(i, a, status="failed" if not a else "ok",
                   failure="boom" if not a else None) for i, a in enumerate(arrays)]
    return recs, arrays


def single(records: list[bytes], capability: str | None = CAP) -> bytes:
    frames = pack_lease_columns("w1", [("L1", capability or "", r) for r in records])
    assert len(frames) == 1
    return frames[0]


@pytest.mark.parametrize("make", [uniform_records, ragged_records])
def test_round_trip_is_exact_and_stored_series_equal_encode_series(make):
    records, arrays = make()
    frame = decode_columns(single(records))
    assert frame.head.runs == list(range(len(records)))
    assert columns_ok(columns_key(CAP), frame)
    cols = from_frame(frame, CAP)
    for k, want in enumerate(arrays):
        for name in ("curve", "best_position", "path"):
            got = cols.array(name, k)
            if name in want:
                assert got is not None and got.shape == want[name].shape
                assert got.tobytes() == want[name].astype("<f8").tobytes()
            else:
                assert got is None
        in_order = {name: want[name] for name in ARRAY_ORDER if name in want}
        assert (None if cols.series[k] is None else bytes(cols.series[k])) == \
            encode_series(in_order)
        if cols.series[k] is not None:
            back = decode_series(bytes(cols.series[k]))
            assert set(back) == set(want)
    assert cols.status[1] == ("failed" if make is ragged_records else "ok")
    assert cols.metrics[2] == {"best_fitness": 3.5, "evaluations": 40}


def test_one_proof_covers_every_byte_and_needs_the_lease_capability():
    records, _ = uniform_records(3)
    data = single(records)
    frame = decode_columns(data)
    assert not columns_ok(columns_key(OTHER), frame) and not columns_ok(b"", frame)
    assert not columns_ok(columns_key(CAP), decode_columns(single(records, None)))
    changed = 0
    for pos in range(len(data)):
        altered = bytearray(data)
        altered[pos] ^= 0x01
        try:
            got = decode_columns(bytes(altered))
        except FrameError:
            continue
        assert not columns_ok(columns_key(CAP), got), pos
        changed += 1
    assert changed > len(data) // 2  # most flips decode (in the floats), then fail the proof


def test_messages_are_cut_to_their_limit_with_one_lease_per_frame():
    records, _ = uniform_records(40)
    others = [record(i, {"curve": np.ones(50)}, lease_id="L2") for i in range(3)]
    limit = 4096 + 2000
    messages = pack_lease_columns(
        "w1", [("L1", CAP, r) for r in records] + [("L2", OTHER, r) for r in others], limit)
    frames = [f for m in messages for f in decode_message(m)]
    assert len(messages) > 2 and all(len(m) <= limit for m in messages)
    assert [r for f in frames if f.head.lease_id == "L1" for r in f.head.runs] == list(range(40))
    assert [r for f in frames if f.head.lease_id == "L2" for r in f.head.runs] == [0, 1, 2]
    assert frames[-1].head.lease_id == "L2"
    assert all(columns_ok(columns_key(CAP if f.head.lease_id == "L1" else OTHER), f)
               for f in frames)
    whole = pack_lease_columns("w1", [("L1", CAP, r) for r in records[:2]] +
                               [("L2", OTHER, r) for r in others])
    assert len(whole) == 1 and [f.head.lease_id for f in decode_message(whole[0])] == ["L1", "L2"]


def hand_made(head: dict, block: bytes = b"", cap: str = CAP) -> bytes:
    text = json.dumps(head).encode()
    signed = COLUMNS_MAGIC + len(text).to_bytes(4, "little") + text + block
    return signed + columns_proof(columns_key(cap), signed)


def good_head(**changes) -> dict:
    head = {"worker": "w1", "lease_id": "L1", "job_id": "j1", "cell": "GWO/F1/2",
            "runs": [0, 1], "status": ["ok", "ok"], "failure": [None, None],
            "seconds": [0.5, 0.5], "metrics": [{}, {}],
            "arrays": [{"name": "curve", "dtype": "<f8", "rows": [2, 2]}]}
    head.update(changes)
    return head


@pytest.mark.parametrize(("payload", "reason"), [
    (b"SPR1" + bytes(40), "frame 0: not a columnar result frame"),
    (b"SPC1" + b"\x10", "length missing"),
    (b"SPC1" + (10**6).to_bytes(4, "little") + b"{}", "no room for the proof"),
    (COLUMNS_MAGIC + bytes(1_000_001), "exceeds"),
    (hand_made(good_head(lease_id="a/b"), bytes(32)), "lease_id"),
    (hand_made(good_head(runs=[0, -1]), bytes(32)), "runs.1"),
    (hand_made(good_head(extra=1), bytes(32)), "extra"),
    (hand_made(good_head(status=["ok"]), bytes(32)), "status has 1 entries"),
    (hand_made(good_head(seconds=[0.5, -1.0]), bytes(32)), "seconds.1"),
    (hand_made(good_head(arrays=[{"name": "curve", "dtype": "<f4", "rows": [2, 2]}]),
               bytes(32)), "dtype"),
    (hand_made(good_head(arrays=[{"name": "curve", "dtype": "<f8", "rows": [2]}]),
               bytes(32)), "rows entries"),
    (hand_made(good_head(arrays=[{"name": "curve", "dtype": "<f8", "rows": [2, 2]}] * 2),
               bytes(64)), "declared twice"),
    (hand_made(good_head(arrays=[{"name": "best_position", "dtype": "<f8",
                                  "rows": [LONGEST["best_position"] + 1, 0]}]),
               bytes(8 * (LONGEST["best_position"] + 1))), "at most"),
    (hand_made(good_head(), bytes(24)), "block of 24 bytes"),
    (hand_made(good_head(), bytes(40)), "frame 1: not a columnar result frame"),
    (hand_made(good_head(), bytes(32)) * 2 + b"SPC1", "frame 2: columns head: length missing"),
])
def test_hostile_frames_are_refused_with_the_reason(payload, reason):
    with pytest.raises(FrameError, match=reason):
        decode_columns(payload)


def test_encode_fills_the_declarations():
    head = ColumnsHead(worker="w1", lease_id="L1", job_id="j1", cell="c", runs=[4, 5],
                       status=["ok", "failed"], failure=[None, "x"], seconds=[0.1, 0.0],
                       metrics=[{"a": 1}, {}])
    frame = decode_columns(encode_columns(head, [{"curve": np.arange(3.0)}, {}], CAP))
    assert [(a.name, a.rows) for a in frame.head.arrays] == [("curve", [3, -1])]
    assert frame.block.tolist() == [0.0, 1.0, 2.0]


# ------------------------------------------------------------------------------ coordinator
@pytest.fixture
def core(tmp_path):
    core = Coordinator(CoordinatorSettings(data_dir=tmp_path / "store"))
    sent: list[tuple[str, bytes]] = []
    core.publish = lambda key, payload: sent.append((key, payload))
    core.sent = sent  # type: ignore[attr-defined]
    yield core
    core.close()


def lease_of(core: Coordinator) -> Lease:
    spec = BenchmarkJobSpec(kind="benchmark", algorithms=["GWO"], functions=["F1"], dims=[2],
                            runs=6, agents=3, iterations=8, seed=2)
    core.submit(spec)
    core.worker_alive("w1")
    reply = decode_work_reply(core.handle_lease_request(encode(LeaseRequest(worker="w1",
                                                                            max_runs=100))))
    assert isinstance(reply, Lease)
    return reply


def statuses(ack: Ack | None) -> set[str]:
    assert ack is not None
    return {status for _lease, _run, status in ack.statuses()}


def test_the_coordinator_stores_a_frame_once_and_refuses_forgeries(core):
    lease = lease_of(core)
    records = [data for _run, data in execute_lease(lease)]
    frame = pack_lease_columns("w1", [(lease.lease_id, lease.capability, r) for r in records])[0]
    key = core.keys.results(lease.job_id)
    forged = pack_lease_columns("w1", [(lease.lease_id, OTHER, r) for r in records])[0]
    flipped = bytearray(frame)
    flipped[-100] ^= 0x01  # a bit of the last curve
    for bad, where in ((forged, key), (bytes(flipped), key), (frame, "swarmpath/results/x")):
        ack = core.handle_results(where, bad)
        assert statuses(ack) == {"stale"}
        assert sorted(run for _l, run, _s in ack.statuses()) == lease.runs
    assert core.store.job_status(lease.job_id).runs_done == 0
    assert core.stats["unproven"] == 2 * len(lease.runs)
    assert statuses(core.handle_results(key, frame)) == {"accepted"}
    assert statuses(core.handle_results(key, frame)) == {"duplicate"}  # re-sent
    assert core.store.job_status(lease.job_id).state == "done"
    acks = [decode(Ack, p) for k, p in core.sent if "/ack/" in k]
    assert len(acks) == 5 and acks[-2].leases[0].accepted == lease.runs
    for (_run, data), run in zip(execute_lease(lease), lease.runs, strict=True):
        stored = core.store.run(lease.job_id, lease.cell_index * 6 + run)
        sent = decode_columns(pack_lease_columns("w1", [(lease.lease_id, CAP, data)])[0])
        assert stored["curve"] == sent.block[:len(stored["curve"])].tolist()


def test_runs_outside_the_lease_are_stale_and_the_others_accepted(core):
    lease = lease_of(core)
    records = [data for _run, data in execute_lease(lease)]
    outside = record(99, {"curve": np.ones(8)}, lease_id=lease.lease_id, job_id=lease.job_id,
                     cell=lease.cell)
    frame = pack_lease_columns("w1", [(lease.lease_id, lease.capability, r)
                                      for r in [*records, outside]])[0]
    ack = core.handle_results(core.keys.results(lease.job_id), frame)
    assert ack is not None and ack.leases[0].accepted == lease.runs
    assert ack.leases[0].stale == [99]


def test_each_frame_of_a_message_is_proven_by_its_own_lease(core):
    lease = lease_of(core)
    records = [data for _run, data in execute_lease(lease)]
    half = len(records) // 2
    payload, = pack_lease_columns("w1", [(lease.lease_id, OTHER, r) for r in records[:half]] +
                                  [("L9", lease.capability, r) for r in records[half:]])
    assert [f.head.lease_id for f in decode_message(payload)] == [lease.lease_id] * 2
    ack = core.handle_results(core.keys.results(lease.job_id), payload)
    assert ack is not None and ack.leases[0].stale == lease.runs[:half]
    assert ack.leases[0].accepted == lease.runs[half:]


def test_a_worker_of_an_older_protocol_is_told_to_upgrade(core):
    lease_of(core)  # a job with work left
    reply = decode_work_reply(core.handle_lease_request(encode(LeaseRequest(
        worker="w1", max_runs=100, protocol=PROTOCOL_VERSION - 1))))
    assert isinstance(reply, NoWork)
    assert f"protocol {PROTOCOL_VERSION - 1} not supported" in reply.reason
