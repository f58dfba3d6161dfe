"""Shared by the job specs and the wire messages: the size limits, the identifier pattern,
the value types and :class:`Model`, the base of every message (unknown fields rejected)."""

from __future__ import annotations

import re
from typing import Annotated, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
)

# ----------------------------------------------------------------------------------------- limits
MAX_DIM = 1000
MAX_AGENTS = 1000
MAX_ITERATIONS = 100_000
MAX_RUNS_PER_CELL = 10_000
MAX_RUNS_PER_JOB = 1_000_000
MAX_BODY_BYTES = 1_000_000  # REST bodies and Zenoh payloads a coordinator accepts
MAX_SEED = 2**63 - 1
MAX_LEASE_RUNS = MAX_RUNS_PER_CELL
MAX_BUNDLE_LEASES = 64  # leases in one reply to a LeaseRequest
CANCEL_LEASES = 2000  # lease drops in one Cancel message
#: a map cell's scenario travels in its lease up to this many bytes of canonical JSON; a larger
#: one travels as a ScenarioRef and the worker fetches it (ScenarioRequest on Keys.scenario)
INLINE_SCENARIO_BYTES = 16_000
MAX_SCENARIO_BYTES = 64 * 1024 * 1024  # a fetched scenario (canonical JSON) at most
MAX_OPTIMUM_BUDGET = 3600.0  # s: the largest time budget a map job may give the exact optimum

PROTOCOL_VERSION = 5  # 2: lease capabilities (swarmpath.service.capability); 3: ScenarioRef;
# 4: results travel as binary result frames (swarmpath.service.result_frame); 5: a lease's
# results travel as columnar frames, proven once per frame (swarmpath.service.result_columns)
DEFAULT_PREFIX = "swarmpath"

# Identifiers that appear inside key expressions: one chunk, none of the reserved characters.
ID_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,127}$"
_ID_RE = re.compile(ID_PATTERN)

ParamValue = bool | int | float | str
Scalar = bool | int | float | str | None
#: "waiting" is never stored: a queued or running job that no live worker can run now (its
#: status says why; swarmpath.service.store.extensions)
JobState = Literal["queued", "running", "done", "failed", "cancelled", "waiting"]
RunState = Literal["queued", "leased", "done", "failed", "cancelled"]
AckStatus = Literal["accepted", "duplicate", "stale"]
LeaseState = Literal["active", "done", "expired", "released", "cancelled", "unknown"]

Identifier = Annotated[str, Field(pattern=ID_PATTERN)]
#: A capability (64 hex digits) or an HMAC-SHA256 tag made with one (64 hex digits).
Secret = Annotated[str, Field(pattern=r"^[0-9a-f]{64}$")]


class Model(BaseModel):
    """Base of every message: unknown fields are an error; NaN and infinities travel as the JSON
    extensions ``NaN``, ``Infinity`` and ``-Infinity`` (Python's json and pydantic read them)."""

    model_config = ConfigDict(
        extra="forbid",
        ser_json_inf_nan="constants",
        json_schema_serialization_defaults_required=True,
    )

