"""The binary result frame (protocol 4): a worker's results, their small fields as JSON and their
series (curve, best position, path) as raw little-endian float64 buffers of a declared shape.

A frame (all integers uint32 little-endian)::

    b"SPR1" | H | FrameHead JSON (H bytes) | record 1 | ... | record N     (N = FrameHead.count)
    record: h | RunResultHead JSON (h bytes) | array bytes | proof (32 bytes)

``RunResultHead.arrays`` declares the arrays that follow its JSON, in order, as
``[name, dtype, shape]``: ``"curve"`` ``"<f8"`` ``[n]`` (n <= MAX_ITERATIONS),
``"best_position"`` ``"<f8"`` ``[d]`` (d <= MAX_DIM), ``"path"`` ``"<f8"`` ``[n, 3]`` (rows
[x, y, t]); each takes ``8 * prod(shape)`` bytes, each name at most once. ``proof`` is the raw
HMAC-SHA256 digest, keyed with the lease's capability (its text, UTF-8), of
``b"result-frame\\n"`` followed by the record's bytes before the proof (``h``, the head JSON and
the arrays): the coordinator checks the bytes it received, nothing is re-serialized.

Decoding checks everything before anything is used: the magic, every length against what is
left of the payload, every head against its schema (``schemas/run_result_head.schema.json``:
the pydantic model, which names what it rejects), dtypes and shapes, and that the last record
ends exactly at the payload's end; any violation rejects the whole frame with a
:class:`FrameError` naming what is wrong. The arrays returned are read-only views of the
payload (no copy). Pure functions, no I/O.
"""

from __future__ import annotations

import hashlib
import hmac
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

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

FRAME_MAGIC = b"SPR1"
PROOF_DOMAIN = b"result-frame\n"
PROOF_BYTES = 32
MAX_FRAME_HEAD = 1024  # bytes of FrameHead JSON at most
MAX_RESULT_HEAD = 64 * 1024  # bytes of one RunResultHead JSON at most
ArrayName = Literal["curve", "best_position", "path"]
#: the longest dimension each array may have, and its row width (None: a vector)
_SHAPES: dict[str, tuple[int, int | None]] = {
    "curve": (MAX_ITERATIONS, None),
    "best_position": (MAX_DIM, None),
    "path": (MAX_BODY_BYTES // 24, 3),
}
_U32 = 4


class FrameHead(Model):
    """The JSON after a result frame's magic: who sends, how many records follow."""

    worker: Identifier
    count: int = Field(ge=1, le=MAX_LEASE_RUNS)


class RunResultHead(Model):
    """A result's small fields in a result frame (a :class:`~swarmpath.service.protocol.RunResult`
    without its series and proof) and the declaration of the arrays that follow it."""

    lease_id: Identifier
    job_id: Identifier
    cell: str = Field(max_length=256)
    run: int = Field(ge=0)
    worker: Identifier
    status: Literal["ok", "failed"] = "ok"
    failure: str | None = Field(default=None, max_length=20_000)
    seconds: float = Field(ge=0, description="wall seconds of this run (its share of a batch)")
    cpu_seconds: float | None = Field(
        default=None, ge=0, description="CPU seconds of this run (its share of a batch); null: "
        "not measured")
    metrics: dict[str, Scalar] = Field(default_factory=dict)
    arrays: list[tuple[ArrayName, Literal["<f8"], list[int]]] = Field(
        default_factory=list, max_length=3,
        description="[name, dtype, shape] of each array after this JSON, in order",
    )


@dataclass(slots=True, eq=False)
class RunFields:
    """The small fields of one reported run, shared by a record head and an
    :class:`~swarmpath.service.incoming.Incoming` (same order: both are built positionally)."""

    lease_id: str
    job_id: str
    cell: str
    run: int
    worker: str
    status: str
    failure: str | None
    seconds: float
    metrics: dict[str, Any]
    #: the run's CPU seconds (None: not measured); keyword-only, so it follows every field
    cpu_seconds: float | None = field(default=None, kw_only=True)


@dataclass(slots=True, eq=False)
class RecordHead(RunFields):
    """A checked record head: the fields of a ``RunResultHead`` as plain attributes."""

    arrays: list[tuple[str, str, list[int]]]

    def fields(self) -> dict[str, Any]:
        """The small fields (without ``arrays``), as ``RunResultHead.model_dump`` gives them."""
        return {"lease_id": self.lease_id, "job_id": self.job_id, "cell": self.cell,
                "run": self.run, "worker": self.worker, "status": self.status,
                "failure": self.failure, "seconds": self.seconds,
                "cpu_seconds": self.cpu_seconds, "metrics": dict(self.metrics)}


class FrameError(ValueError):
    """A result frame that breaks the layout (the message says where)."""


@dataclass(slots=True)
class FrameRecord:
    """One decoded record: its head, its arrays (read-only views), the signed bytes and proof."""

    head: RecordHead
    arrays: dict[str, np.ndarray]
    signed: bytes
    proof: bytes
    #: the arrays' bytes as received (in ``head.arrays`` order), for storing them as they are
    raw: bytes = b""


def record_proof(capability: str, signed: bytes) -> bytes:
    """The proof of a record whose bytes before the proof are ``signed``."""
    return hmac.digest(capability.encode(), PROOF_DOMAIN + signed, hashlib.sha256)


def record_ok(capability: str | None, record: FrameRecord) -> bool:
    """True when the record's proof was made with ``capability`` (never for an empty one)."""
    return bool(capability) and hmac.compare_digest(
        record_proof(str(capability), record.signed), record.proof)


def proof_key(capability: str) -> bytes:
    """The HMAC key of a capability (its text, UTF-8): made once per lease on the hot path."""
    return capability.encode()


def key_ok(key: bytes, record: FrameRecord) -> bool:
    """:func:`record_ok` with the capability's :func:`proof_key` (never true for an empty key)."""
    return bool(key) and hmac.compare_digest(
        hmac.digest(key, PROOF_DOMAIN + record.signed, "sha256"), record.proof)


# --------------------------------------------------------------------------------- encoding
def encode_record(
    head: RunResultHead, arrays: dict[str, np.ndarray], capability: str | None
) -> bytes:
    """One record; ``head.arrays`` is filled from ``arrays`` (curve, best_position, path in that
    order). Without a capability the proof is zeros (the coordinator finds it stale)."""
    parts = []
    declared: list[tuple[ArrayName, Literal["<f8"], list[int]]] = []
    for name in ("curve", "best_position", "path"):
        value = arrays.get(name)
        if value is None:
            continue
        arr = np.ascontiguousarray(value, dtype="<f8")
        declared.append((name, "<f8", list(arr.shape)))  # type: ignore[arg-type]
        parts.append(arr.tobytes())
    text = head.model_copy(update={"arrays": declared}).model_dump_json().encode()
    signed = len(text).to_bytes(_U32, "little") + text + b"".join(parts)
    proof = record_proof(capability, signed) if capability else bytes(PROOF_BYTES)
    return signed + proof


def pack_frames(worker: str, records: Sequence[bytes], limit: int) -> list[bytes]:
    """Frames of ``records`` (from :func:`encode_record`), each at most ``limit`` bytes when
    the records allow it (a record larger than that travels alone)."""
    out: list[bytes] = []
    chunk: list[bytes] = []
    size = 0
    for rec in records:
        if chunk and size + len(rec) > limit - MAX_FRAME_HEAD:
            out.append(_frame(worker, chunk))
            chunk, size = [], 0
        chunk.append(rec)
        size += len(rec)
    if chunk:
        out.append(_frame(worker, chunk))
    return out


def _frame(worker: str, records: list[bytes]) -> bytes:
    head = FrameHead(worker=worker, count=len(records)).model_dump_json().encode()
    return b"".join([FRAME_MAGIC, len(head).to_bytes(_U32, "little"), head, *records])


# --------------------------------------------------------------------------------- decoding
def is_frame(payload: bytes) -> bool:
    return payload[:4] == FRAME_MAGIC


def decode_frame(payload: bytes) -> tuple[str, list[FrameRecord]]:
    """(worker, records) of a frame; raises :class:`FrameError` (see the module docstring).
    A columnar frame (protocol 5, :mod:`~swarmpath.service.result_columns`) reads as its runs'
    records too, for tools and tests that read what a worker sends; those records carry no proof
    of their own (:func:`key_ok` is never true for them)."""
    if payload[:4] == b"SPC1":
        from swarmpath.service.result_columns import column_records

        return column_records(payload)
    if len(payload) > MAX_BODY_BYTES:
        raise FrameError(f"frame of {len(payload)} bytes exceeds {MAX_BODY_BYTES}")
    if not is_frame(payload):
        raise FrameError("not a result frame (magic)")
    pos = len(FRAME_MAGIC)
    text, pos = _chunk(payload, pos, MAX_FRAME_HEAD, "frame head")
    try:
        frame = FrameHead.model_validate_json(text)
    except ValidationError as exc:
        raise FrameError(f"frame head: {_first(exc)}") from None
    worker, count = frame.worker, frame.count
    records = []
    for i in range(count):
        rec, pos = _record(payload, pos, i)
        records.append(rec)
    if pos != len(payload):
        raise FrameError(f"{len(payload) - pos} bytes after the last record")
    return worker, records


def decode_record(data: bytes) -> FrameRecord:
    """One record alone (what :func:`encode_record` made), checked like a frame's."""
    rec, pos = _record(data, 0, 0)
    if pos != len(data):
        raise FrameError(f"{len(data) - pos} bytes after the record")
    return rec


def _record(payload: bytes, pos: int, i: int) -> tuple[FrameRecord, int]:
    start = pos
    text, pos = _chunk(payload, pos, MAX_RESULT_HEAD, f"record {i} head")
    try:
        model = RunResultHead.model_validate_json(text)
    except ValidationError as exc:
        raise FrameError(f"record {i}: {_first(exc)}") from None
    head = RecordHead(model.lease_id, model.job_id, model.cell, model.run, model.worker,
                      model.status, model.failure, model.seconds, dict(model.metrics),
                      [(n, d, list(s)) for n, d, s in model.arrays],
                      cpu_seconds=model.cpu_seconds)
    arrays: dict[str, np.ndarray] = {}
    first = pos
    for name, _dtype, shape in head.arrays:
        if name in arrays:
            raise FrameError(f"record {i}: array {name} declared twice")
        count = _check_shape(i, name, shape)
        end = pos + 8 * count
        if end > len(payload):
            raise FrameError(f"record {i}: array {name} runs past the frame's end")
        arrays[name] = np.frombuffer(payload, dtype="<f8", count=count,
                                     offset=pos).reshape(shape)
        pos = end
    if pos + PROOF_BYTES > len(payload):
        raise FrameError(f"record {i}: no room for its proof")
    rec = FrameRecord(head, arrays, payload[start:pos], payload[pos:pos + PROOF_BYTES],
                      payload[first:pos])
    return rec, pos + PROOF_BYTES


def as_dict(record: FrameRecord) -> dict[str, Any]:
    """A record as the fields of a RunResult without its proof (lists for the arrays): for tools
    and tests that read what a worker sends."""
    out: dict[str, Any] = record.head.fields()
    out.update({"curve": None, "best_position": None, "path": None})
    out.update({name: arr.tolist() for name, arr in record.arrays.items()})
    return out


def _chunk(payload: bytes, pos: int, limit: int, what: str) -> tuple[bytes, int]:
    if pos + _U32 > len(payload):
        raise FrameError(f"{what}: length missing")
    n = int.from_bytes(payload[pos:pos + _U32], "little")
    pos += _U32
    if n > limit or pos + n > len(payload):
        raise FrameError(f"{what}: length {n} exceeds {min(limit, len(payload) - pos)}")
    return payload[pos:pos + n], pos + n


def _check_shape(i: int, name: str, shape: list[int]) -> int:
    longest, width = _SHAPES[name]
    want = 1 if width is None else 2
    if len(shape) != want or (width is not None and shape[1] != width):
        raise FrameError(f"record {i}: array {name} has shape {shape}; expected "
                         f"{'[n]' if width is None else f'[n, {width}]'}")
    if not 0 <= shape[0] <= longest:
        raise FrameError(f"record {i}: array {name} has {shape[0]} rows (at most {longest})")
    return math.prod(shape)


def _first(exc: ValidationError) -> str:
    err = exc.errors()[0]
    loc = ".".join(str(p) for p in err["loc"])
    return f"{loc}: {err['msg']}" if loc else str(err["msg"])
