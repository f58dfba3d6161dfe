"""The binary result frame (protocol 4): exact round trips, proofs over the received bytes, and
hostile frames rejected with the reason."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from swarmpath.service.capability import new_capability
from swarmpath.service.model import MAX_BODY_BYTES, MAX_ITERATIONS
from swarmpath.service.result_frame import (
    FRAME_MAGIC,
    PROOF_BYTES,
    FrameError,
    RunResultHead,
    as_dict,
    decode_frame,
    decode_record,
    encode_record,
    pack_frames,
    record_ok,
)
from swarmpath.service.store.series import decode_series, encode_series, raw_series

CAP = new_capability()


def head(run: int = 0, **changes) -> RunResultHead:
    fields = {"lease_id": "L1", "job_id": "j1", "cell": "GWO/F1/2", "run": run, "worker": "w1",
              "seconds": 0.25, "metrics": {"best_fitness": 1e-30, "evaluations": 1000}}
    return RunResultHead(**{**fields, **changes})


def frame(records: list[bytes], worker: str = "w1") -> bytes:
    (out,) = pack_frames(worker, records, MAX_BODY_BYTES)
    return out


def raw_frame(head_json: dict, records: list[tuple[dict, bytes]]) -> bytes:
    """A frame built by hand (for layouts encode_record never makes)."""
    def chunk(b: bytes) -> bytes:
        return len(b).to_bytes(4, "little") + b

    body = b"".join(chunk(json.dumps(h).encode()) + arrays + bytes(PROOF_BYTES)
                    for h, arrays in records)
    return FRAME_MAGIC + chunk(json.dumps(head_json).encode()) + body


def test_round_trip_is_exact_and_zero_copy():
    curve = np.array([3.0, math.inf, 1e-300, 0.1, -math.inf])
    path = np.array([[0.0, 1.0, 2.0], [3.5, 4.25, 5.0]])
    records = [encode_record(head(0), {"curve": curve, "best_position": np.array([0.5, -2.0])},
                             CAP),
               encode_record(head(1, status="failed", failure="boom"), {}, CAP),
               encode_record(head(2), {"path": path}, CAP),
               encode_record(head(3), {"path": np.zeros((0, 3))}, CAP)]
    worker, got = decode_frame(frame(records))
    assert worker == "w1" and [r.head.run for r in got] == [0, 1, 2, 3]
    assert got[0].arrays["curve"].tobytes() == curve.tobytes()  # bit for bit, inf included
    assert got[0].arrays["best_position"].tolist() == [0.5, -2.0]
    assert got[1].arrays == {} and got[1].head.failure == "boom"
    assert got[2].arrays["path"].tolist() == path.tolist()
    assert got[3].arrays["path"].shape == (0, 3)
    assert not got[0].arrays["curve"].flags.writeable  # a view of the payload
    assert as_dict(got[0])["metrics"] == {"best_fitness": 1e-30, "evaluations": 1000}
    assert decode_record(records[2]).arrays["path"].tolist() == path.tolist()


def test_proof_covers_every_byte_and_needs_the_capability():
    data = encode_record(head(), {"curve": np.linspace(1.0, 0.0, 50)}, CAP)
    rec = decode_record(data)
    assert record_ok(CAP, rec)
    assert not record_ok(new_capability(), rec) and not record_ok("", rec)
    assert not record_ok(None, rec)
    tampered = bytearray(data)
    tampered[len(data) - PROOF_BYTES - 3] ^= 0x01  # one bit of the curve's last value
    assert not record_ok(CAP, decode_record(bytes(tampered)))
    unsigned = decode_record(encode_record(head(), {}, None))
    assert unsigned.proof == bytes(PROOF_BYTES) and not record_ok(CAP, unsigned)


def test_frames_are_cut_to_the_limit():
    records = [encode_record(head(i), {"curve": np.ones(100)}, CAP) for i in range(20)]
    frames = pack_frames("w1", records, 4000)
    assert len(frames) > 1 and all(len(f) <= 4000 for f in frames)
    runs = [r.head.run for f in frames for r in decode_frame(f)[1]]
    assert runs == list(range(20))


def ok_head(**changes) -> dict:
    h = head().model_dump()
    h.update(changes)
    return h


@pytest.mark.parametrize(("payload", "reason"), [
    (b"", "magic"),
    (b"{}", "magic"),
    (FRAME_MAGIC, "frame head: length missing"),
    (FRAME_MAGIC + (10**9).to_bytes(4, "little"), "frame head: length"),
    (raw_frame({"worker": "w1", "count": 0}, []), "count"),
    (raw_frame({"worker": "bad worker", "count": 1}, [(ok_head(), b"")]), "worker"),
    (raw_frame({"worker": "w1", "count": 2}, [(ok_head(), b"")]), "record 1 head"),
    (raw_frame({"worker": "w1", "count": 1}, [(ok_head(), b"")]) + b"x", "after the last"),
    (raw_frame({"worker": "w1", "count": 1}, [(ok_head(extra=1), b"")]), "extra"),
    (raw_frame({"worker": "w1", "count": 1}, [(ok_head(run=-1), b"")]), "run"),
    (raw_frame({"worker": "w1", "count": 1},
               [(ok_head(arrays=[["curve", "<f4", [2]]]), bytes(8))]), "arrays"),
    (raw_frame({"worker": "w1", "count": 1},
               [(ok_head(arrays=[["secret", "<f8", [1]]]), bytes(8))]), "arrays"),
    (raw_frame({"worker": "w1", "count": 1},
               [(ok_head(arrays=[["path", "<f8", [1, 2]]]), bytes(16))]), "shape"),
    (raw_frame({"worker": "w1", "count": 1},
               [(ok_head(arrays=[["curve", "<f8", [1, 1]]]), bytes(8))]), "shape"),
    (raw_frame({"worker": "w1", "count": 1},
               [(ok_head(arrays=[["curve", "<f8", [MAX_ITERATIONS + 1]]]), b"")]), "rows"),
    (raw_frame({"worker": "w1", "count": 1},
               [(ok_head(arrays=[["curve", "<f8", [-1]]]), b"")]), "rows"),
    (raw_frame({"worker": "w1", "count": 1},
               [(ok_head(arrays=[["curve", "<f8", [1]], ["curve", "<f8", [1]]]), bytes(16))]),
     "twice"),
    (raw_frame({"worker": "w1", "count": 1},
               [(ok_head(arrays=[["curve", "<f8", [1000]]]), bytes(80))]), "past the frame"),
    (raw_frame({"worker": "w1", "count": 1}, [(ok_head(), b"")])[:-1], "proof"),
    (FRAME_MAGIC + bytes(MAX_BODY_BYTES), "exceeds"),
])
def test_hostile_frames_are_rejected_with_the_reason(payload, reason):
    with pytest.raises(FrameError, match=reason):
        decode_frame(payload)


@pytest.mark.parametrize("changes", [
    {}, {"status": "failed", "failure": "boom"}, {"seconds": 2}, {"seconds": -0.0},
    {"metrics": {"best_fitness": float("nan"), "hit": True, "note": "x", "none": None}},
    {"metrics": {"deep": [1]}}, {"metrics": []}, {"run": "5"}, {"run": 5.0}, {"run": True},
    {"seconds": "1.5"}, {"seconds": True}, {"seconds": float("nan")}, {"status": "OK"},
    {"failure": 3}, {"cell": "c" * 256}, {"cell": "c" * 257}, {"failure": "f" * 20_001},
    {"lease_id": "L1\n"}, {"job_id": ""}, {"worker": "w" * 129}, {"extra": None},
    {"arrays": [["curve", "<f8", [2.0]]]}, {"arrays": [["curve", "<f8", ["2"]]]},
    {"arrays": [("curve", "<f8", [2])] * 4}, {"arrays": [["curve", "<f8"]]},
    {"arrays": {"curve": 1}}, {"metrics": {"big": 2**70}}, {"metrics": {"big": 2**64 - 1}},
    {"metrics": {"small": 1e300, "neg": -(2**63)}}, {"lease_id": ["L1"]}, {"cell": {"a": 1}},
    {"worker": 7},
])
def test_record_heads_are_read_as_the_model_reads_them(changes):
    """A record's head gives the model's values (exact JSON types, the metrics as sent), and
    every head the model rejects is rejected with the model's reason (the field named)."""
    fields = ok_head(**changes)
    text = json.dumps(fields).encode()
    payload = raw_frame({"worker": "w1", "count": 1},
                        [(fields, bytes(16) if "arrays" in changes else b"")])
    try:
        want = RunResultHead.model_validate_json(text)
    except Exception as exc:
        field = str(exc).splitlines()[1].split(".")[0]
        with pytest.raises(FrameError, match=f"record 0: {field}"):
            decode_frame(payload)
        return
    try:
        (rec,) = decode_frame(payload)[1]
    except FrameError as exc:  # the layout (array bytes) can still be wrong; never the head
        assert "record 0: array" in str(exc)
        return
    got = rec.head.fields()
    expected = want.model_dump(exclude={"arrays"})
    assert json.dumps(got, sort_keys=True) == json.dumps(expected, sort_keys=True)
    assert [type(v) for v in got.values()] == [type(v) for v in expected.values()]


def test_received_arrays_are_stored_as_they_came():
    """The store's series column made from a record's received bytes is what encoding its
    arrays gives, and reads back to the same arrays whatever order they were declared in."""
    curve, best, path = np.linspace(2.0, 0.0, 7), np.array([0.5, -1.0]), np.ones((3, 3))
    rec = decode_record(encode_record(head(), {"curve": curve, "best_position": best,
                                               "path": path}, CAP))
    assert raw_series(rec.head.arrays, rec.raw) == encode_series(dict(rec.arrays))
    assert raw_series([], b"") is None
    swapped = raw_frame({"worker": "w1", "count": 1}, [(
        ok_head(arrays=[["best_position", "<f8", [2]], ["curve", "<f8", [7]]]),
        best.tobytes() + curve.tobytes())])
    (rec,) = decode_frame(swapped)[1]
    back = decode_series(raw_series(rec.head.arrays, rec.raw))
    assert back == {"best_position": best.tolist(), "curve": curve.tolist()}
