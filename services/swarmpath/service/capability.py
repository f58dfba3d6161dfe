"""Lease capabilities: who may report on a lease, and who may end it.

Every lease gets a random secret (:func:`new_capability`, 256 bits) when it is granted. The
coordinator sends it only in the reply to the worker's own lease query (a Zenoh query reply goes
to the querier alone) and keeps it in the store; it is never put on a key expression, so no
subscriber ever sees it. Both ends then prove knowledge of it with HMAC-SHA256 tags, each bound to
its purpose (a domain string) so a tag of one kind is useless as another:

* a result carries :func:`result_proof` over its own JSON (all fields but ``proof``): a result
  copied from the bus cannot be altered, and one without the secret is ``stale``;
* a progress message carries :func:`progress_proof` over (lease, sequence number); the coordinator
  renews the lease only for a sequence number above the last one it took, so a replayed progress
  message renews nothing;
* a drop (the coordinator ending a lease: in an Ack, or in a Cancel) carries :func:`drop_proof`;
  workers drop a lease only with a valid one, so a forged cancel or ack ends nothing.

Pure functions, no I/O.
"""

from __future__ import annotations

import hashlib
import hmac
import secrets

from swarmpath.service.protocol import RunResult

CAPABILITY_BYTES = 32


def new_capability() -> str:
    """A fresh lease secret: 64 hex digits from the OS's CSPRNG."""
    return secrets.token_hex(CAPABILITY_BYTES)


def _tag(capability: str, domain: str, text: str) -> str:
    return hmac.new(capability.encode(), f"{domain}\n{text}".encode(), hashlib.sha256).hexdigest()


def _same(expected: str, given: str | None) -> bool:
    return bool(given) and hmac.compare_digest(expected, str(given))


def result_body(result: RunResult) -> str:
    """The text a result's proof covers: its wire JSON without the proof (and without
    ``cpu_seconds`` when it is null: the JSON of a result from before that field, unchanged)."""
    unmeasured = {"cpu_seconds"} if result.cpu_seconds is None else set()
    return result.model_dump_json(exclude={"proof", *unmeasured})


def result_proof(capability: str, result: RunResult) -> str:
    return _tag(capability, "result", result_body(result))


def result_ok(capability: str | None, result: RunResult) -> bool:
    """True when ``result.proof`` was made with ``capability`` (never for an empty one)."""
    return bool(capability) and _same(result_proof(str(capability), result), result.proof)


def progress_proof(capability: str, lease_id: str, seq: int) -> str:
    return _tag(capability, "progress", f"{lease_id}\n{int(seq)}")


def progress_ok(capability: str | None, lease_id: str, seq: int, proof: str | None) -> bool:
    return bool(capability) and _same(progress_proof(str(capability), lease_id, seq), proof)


def drop_proof(capability: str, lease_id: str) -> str:
    return _tag(capability, "drop", lease_id)


def drop_ok(capability: str | None, lease_id: str, proof: str | None) -> bool:
    return bool(capability) and _same(drop_proof(str(capability), lease_id), proof)
