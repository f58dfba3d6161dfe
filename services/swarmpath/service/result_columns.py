"""The columnar result frame (protocol 5): results of one lease as columns, proven once.

A worker puts the finished runs of a lease as one or more of these frames, and one message (a
put on ``results/<job>``, at most 1 MB) holds one or more frames back to back, of one lease or
of several (all integers uint32 little-endian)::

    frame: b"SPC1" | H | ColumnsHead JSON (H bytes) | float64 block | proof (32 bytes)

:class:`ColumnsHead` names the lease, its job, cell and worker once and holds each run's small
fields as columns (``runs``, ``status``, ``failure``, ``seconds``, ``cpu_seconds``,
``metrics``: one entry per run, in the same order; ``cpu_seconds`` may be absent, as from
workers older than it: then no run's CPU time is known). ``arrays`` declares the series: for
each name (``curve``, ``best_position``, ``path``, each at most once, in that order) the rows
of every run (-1: the run has no such array; a path row is [x, y, t], three values, the others
one). The block holds the arrays' raw little-endian float64 values, array by array and,
within one, run by run. The proof is the raw HMAC-SHA256 digest, keyed with the lease's
capability (its text, UTF-8), of ``b"result-columns\\n"`` followed by every byte of the frame
before the proof: one HMAC per frame, over the bytes received (nothing re-serialized), and a
frame proves nothing for any other lease.

Decoding checks everything before anything is used: the size, the magic, the head against its
schema (``schemas/result_columns_head.schema.json``: one pydantic validation per frame; the
error names the field), every column as long as ``runs``, the rows against their bounds, and the
block's length against the rows declared, and that the frames fill the message exactly; any
violation rejects the message with a :class:`~swarmpath.service.result_frame.FrameError`.
Pure functions, no I/O.
"""

from __future__ import annotations

import hashlib
import hmac
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field, ValidationError

from swarmpath.service.model import (
    MAX_BODY_BYTES,
    MAX_DIM,
    MAX_ITERATIONS,
    MAX_LEASE_RUNS,
    Identifier,
    Model,
    Scalar,
)
from swarmpath.service.result_frame import (
    PROOF_BYTES,
    FrameError,
    FrameRecord,
    RecordHead,
    _first,
    decode_record,
)

COLUMNS_MAGIC = b"SPC1"
MAX_FRAMES = 1024  # frames in one message at most
COLUMNS_DOMAIN = b"result-columns\n"
ARRAY_ORDER = ("curve", "best_position", "path")
#: values per row, and the most rows one run's array may have
WIDTHS = {"curve": 1, "best_position": 1, "path": 3}
LONGEST = {"curve": MAX_ITERATIONS, "best_position": MAX_DIM, "path": MAX_BODY_BYTES // 24}
_U32 = 4
_STATUS = Literal["ok", "failed"]


class ColumnArray(Model):
    """One series of every run of a columnar frame."""

    name: Literal["curve", "best_position", "path"]
    dtype: Literal["<f8"]
    rows: list[Annotated[int, Field(ge=-1)]] = Field(
        max_length=MAX_LEASE_RUNS,
        description="rows of each run's array (-1: none); a path row holds x, y, t")


class ColumnsHead(Model):
    """The JSON after a columnar result frame's magic: one lease's results as columns."""

    worker: Identifier
    lease_id: Identifier
    job_id: Identifier
    cell: str = Field(max_length=256)
    runs: list[Annotated[int, Field(ge=0)]] = Field(min_length=1, max_length=MAX_LEASE_RUNS)
    status: list[_STATUS] = Field(max_length=MAX_LEASE_RUNS)
    failure: list[Annotated[str, Field(max_length=20_000)] | None] = Field(
        max_length=MAX_LEASE_RUNS)
    seconds: list[Annotated[float, Field(ge=0)]] = Field(
        max_length=MAX_LEASE_RUNS, description="wall seconds of each run (its share of a batch)")
    cpu_seconds: list[Annotated[float, Field(ge=0)] | None] | None = Field(
        default=None, max_length=MAX_LEASE_RUNS,
        description="CPU seconds of each run (its share of a batch; null: not measured); "
        "absent: none measured (a worker from before it was sent)")
    metrics: list[dict[str, Scalar]] = Field(max_length=MAX_LEASE_RUNS)
    arrays: list[ColumnArray] = Field(default_factory=list, max_length=3)


@dataclass(slots=True, eq=False)
class ColumnsFrame:
    """A decoded columnar frame: its head, the float64 block (a read-only view of the payload),
    and the bytes its proof covers."""

    head: ColumnsHead
    block: np.ndarray
    signed: memoryview
    proof: bytes


def columns_key(capability: str) -> bytes:
    """The HMAC key of a lease's capability (its text, UTF-8)."""
    return capability.encode()


def columns_proof(key: bytes, signed: bytes | memoryview) -> bytes:
    """The proof of a frame whose bytes before the proof are ``signed``."""
    mac = hmac.new(key, COLUMNS_DOMAIN, hashlib.sha256)
    mac.update(signed)
    return mac.digest()


def columns_ok(key: bytes, frame: ColumnsFrame) -> bool:
    """True when the frame's proof was made with ``key`` (never for an empty key)."""
    return bool(key) and hmac.compare_digest(columns_proof(key, frame.signed), frame.proof)


# --------------------------------------------------------------------------------- encoding
def encode_columns(head: ColumnsHead, arrays: Sequence[dict[str, np.ndarray]],
                   capability: str | None) -> bytes:
    """One frame; ``head.arrays`` is filled from ``arrays`` (each run's arrays by name). Without
    a capability the proof is zeros (the coordinator finds the frame stale)."""
    declared = []
    parts: list[bytes] = []
    for name in ARRAY_ORDER:
        if not any(name in a for a in arrays):
            continue
        rows = []
        for a in arrays:
            value = a.get(name)
            if value is None:
                rows.append(-1)
                continue
            arr = np.ascontiguousarray(value, dtype="<f8")
            rows.append(int(arr.shape[0]) if arr.ndim else 1)
            parts.append(arr.tobytes())
        declared.append(ColumnArray(name=name, dtype="<f8", rows=rows))  # type: ignore[arg-type]
    text = head.model_copy(update={"arrays": declared}).model_dump_json().encode()
    signed = b"".join([COLUMNS_MAGIC, len(text).to_bytes(_U32, "little"), text, *parts])
    proof = columns_proof(columns_key(capability), signed) if capability else bytes(PROOF_BYTES)
    return signed + proof


def pack_columns(worker: str, capability: str | None, records: Sequence[bytes],
                 limit: int) -> list[bytes]:
    """Columnar frames of the result records (:func:`~swarmpath.service.result_frame.encode_record`
    form, what a worker's slots return) of ONE lease, each at most about ``limit`` bytes (a
    record larger than that travels alone), proven with the lease's ``capability``; put them
    with :func:`pack_message`."""
    out: list[bytes] = []
    chunk: list[Any] = []
    size = 0
    for data in records:
        rec = decode_record(data)
        if chunk and size + len(data) > limit - 4096:
            out.append(_columns_frame(worker, capability, chunk))
            chunk, size = [], 0
        chunk.append(rec)
        size += len(data) + 64
    if chunk:
        out.append(_columns_frame(worker, capability, chunk))
    return out


def pack_message(frames: Sequence[bytes], limit: int) -> list[bytes]:
    """Messages of frames put back to back, each at most ``limit`` bytes when the frames allow
    it (a frame larger than that travels alone)."""
    out: list[bytes] = []
    chunk: list[bytes] = []
    size = 0
    for frame in frames:
        if chunk and (size + len(frame) > limit or len(chunk) == MAX_FRAMES):
            out.append(b"".join(chunk))
            chunk, size = [], 0
        chunk.append(frame)
        size += len(frame)
    if chunk:
        out.append(b"".join(chunk))
    return out


def _columns_frame(worker: str, capability: str | None, recs: list[Any]) -> bytes:
    first = recs[0].head
    head = ColumnsHead(
        worker=worker, lease_id=first.lease_id, job_id=first.job_id, cell=first.cell,
        runs=[r.head.run for r in recs], status=[r.head.status for r in recs],
        failure=[r.head.failure for r in recs], seconds=[r.head.seconds for r in recs],
        cpu_seconds=[r.head.cpu_seconds for r in recs], metrics=[r.head.metrics for r in recs])
    return encode_columns(head, [r.arrays for r in recs], capability)


# --------------------------------------------------------------------------------- decoding
def is_columns(payload: bytes) -> bool:
    return payload[:4] == COLUMNS_MAGIC


def decode_columns(payload: bytes) -> ColumnsFrame:
    """The one frame in ``payload``; raises FrameError naming what is wrong (module docstring)."""
    frames = decode_message(payload)
    if len(frames) != 1:
        raise FrameError(f"{len(frames)} frames where one was expected")
    return frames[0]


def decode_message(payload: bytes) -> list[ColumnsFrame]:
    """The frames of a message: one or more, back to back, filling it exactly (at most
    MAX_FRAMES); raises FrameError naming what is wrong (module docstring)."""
    if len(payload) > MAX_BODY_BYTES:
        raise FrameError(f"message of {len(payload)} bytes exceeds {MAX_BODY_BYTES}")
    frames = []
    pos = 0
    view = memoryview(payload)
    while pos < len(payload):
        if len(frames) == MAX_FRAMES:
            raise FrameError(f"more than {MAX_FRAMES} frames in one message")
        frame, pos = _frame_at(payload, view, pos, len(frames))
        frames.append(frame)
    if not frames:
        raise FrameError("empty message")
    return frames


def _frame_at(payload: bytes, view: memoryview, pos: int, i: int) -> tuple[ColumnsFrame, int]:
    first = pos
    if payload[pos:pos + 4] != COLUMNS_MAGIC:
        raise FrameError(f"frame {i}: not a columnar result frame (magic)")
    pos += len(COLUMNS_MAGIC)
    if pos + _U32 > len(payload):
        raise FrameError(f"frame {i}: columns head: length missing")
    n = int.from_bytes(payload[pos:pos + _U32], "little")
    pos += _U32
    if pos + n + PROOF_BYTES > len(payload):
        raise FrameError(f"frame {i}: columns head: length {n} leaves no room for the proof")
    try:
        head = ColumnsHead.model_validate_json(payload[pos:pos + n])
    except ValidationError as exc:
        raise FrameError(f"frame {i}: columns head: {_first(exc)}") from None
    values = _declared_values(head, i)
    start = pos + n
    end = start + 8 * values
    if end + PROOF_BYTES > len(payload):
        raise FrameError(f"frame {i}: block of {len(payload) - PROOF_BYTES - start} bytes; "
                         f"the arrays declare {8 * values}")
    block = np.frombuffer(payload, dtype="<f8", count=values, offset=start)
    proof = bytes(view[end:end + PROOF_BYTES])
    return ColumnsFrame(head, block, view[first:end], proof), end + PROOF_BYTES


def _declared_values(head: ColumnsHead, i: int) -> int:
    """How many float64 values the head's arrays declare, after checking the columns."""
    count = len(head.runs)
    for name in ("status", "failure", "seconds", "metrics", "cpu_seconds"):
        if getattr(head, name) is not None and len(getattr(head, name)) != count:
            raise FrameError(f"frame {i}: columns head: {name} has "
                             f"{len(getattr(head, name))} entries; runs has {count}")
    values = 0
    seen = set()
    for arr in head.arrays:
        if arr.name in seen:
            raise FrameError(f"frame {i}: columns head: array {arr.name} declared twice")
        seen.add(arr.name)
        if len(arr.rows) != count:
            raise FrameError(f"frame {i}: columns head: array {arr.name} has {len(arr.rows)} "
                             f"rows entries; runs has {count}")
        longest = max(arr.rows)
        if longest > LONGEST[arr.name]:
            raise FrameError(f"frame {i}: columns head: array {arr.name} has {longest} rows in "
                             f"a run (at most {LONGEST[arr.name]})")
        values += WIDTHS[arr.name] * (sum(arr.rows) + arr.rows.count(-1))
    return values


def column_records(payload: bytes) -> tuple[str, list[FrameRecord]]:
    """A message of columnar frames as (worker of its first frame, one record per run), the
    arrays views of the payload; the records have no proof of their own (``signed`` and
    ``proof`` empty)."""
    frames = decode_message(payload)
    records = []
    for frame in frames:
        records += _records(frame)
    return frames[0].head.worker, records


def column_arrays(frame: ColumnsFrame) -> dict[str, list[np.ndarray | None]]:
    """Each declared array's value per run (None where a run has none; a path has rows of 3),
    read-only views of the frame's block."""
    out: dict[str, list[np.ndarray | None]] = {}
    offset = 0
    for a in frame.head.arrays:
        width = WIDTHS[a.name]
        per_run: list[np.ndarray | None] = []
        for rows in a.rows:
            if rows < 0:
                per_run.append(None)
                continue
            values = frame.block[offset:offset + rows * width]
            per_run.append(values.reshape(rows, width) if width > 1 else values)
            offset += rows * width
        out[a.name] = per_run
    return out


def _records(frame: ColumnsFrame) -> list[FrameRecord]:
    h = frame.head
    by_name = column_arrays(frame)
    cpu = h.cpu_seconds or [None] * len(h.runs)
    records = []
    for k, run in enumerate(h.runs):
        arrays = {name: v[k] for name, v in by_name.items() if v[k] is not None}
        shapes = [(name, "<f8", list(v.shape)) for name, v in arrays.items()]
        head = RecordHead(h.lease_id, h.job_id, h.cell, run, h.worker, h.status[k],
                          h.failure[k], h.seconds[k], h.metrics[k], shapes,
                          cpu_seconds=cpu[k])
        records.append(FrameRecord(head, arrays, b"", b""))
    return records

