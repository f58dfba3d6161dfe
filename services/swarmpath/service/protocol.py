"""The messages of the swarmpath service (the Zenoh key expressions they travel on are in
:mod:`.keys`; :class:`Keys` is importable from here too).

Every message is UTF-8 JSON of one of the pydantic models below (unknown fields are rejected). The
protocol itself - who sends what on which key, leases, fencing, acknowledgements, cancellation - is
documented for implementers in other languages in ``schemas/README.md``; the JSON Schemas exported
from these models by :mod:`swarmpath.service.schemas` are next to it.

Job specs are validated completely (:mod:`.jobspec`, its checks in :mod:`.spec_checks`; their
names are importable from here too): unknown algorithm / function / planner / map names,
unknown or out-of-range algorithm parameters, and the size limits all fail with a
:class:`pydantic.ValidationError` whose error location names the field (FastAPI turns that into a
422 with the same location). Use :func:`parse_job_spec` (or :data:`JOB_SPEC_ADAPTER`).

A job expands into *cells* (benchmark: algorithm x function x dim; map: planner x map), each with
``runs`` runs numbered 0..runs-1. Run ``r`` of cell ``c`` has the job-wide ``run_id = c * runs +
r``. A run is fully determined by (cell spec, job seed, run index): whichever worker executes it,
it gives the same numbers.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, TypeVar

from pydantic import (
    AfterValidator,
    BaseModel,
    Field,
    TypeAdapter,
)

from swarmpath.plugins.pins import clean_extensions
from swarmpath.provenance import clean_platform
from swarmpath.service.cell_notes import CellNotes
from swarmpath.service.jobspec import (
    CELL_ADAPTER,
    JOB_SPEC_ADAPTER,
    BenchmarkCell,
    BenchmarkJobSpec,
    CellSpec,
    JobSpec,
    MapCell,
    MapEntry,
    MapJobSpec,
    MapRef,
    ScenarioRef,
    expand_cells,
    first_runs,
    load_job_spec,
    map_name,
    parse_job_spec,
    run_key,
    runs_total,
)
from swarmpath.service.keys import Keys
from swarmpath.service.model import (
    CANCEL_LEASES,
    DEFAULT_PREFIX,
    ID_PATTERN,
    INLINE_SCENARIO_BYTES,
    MAX_AGENTS,
    MAX_BODY_BYTES,
    MAX_BUNDLE_LEASES,
    MAX_DIM,
    MAX_ITERATIONS,
    MAX_LEASE_RUNS,
    MAX_RUNS_PER_CELL,
    MAX_RUNS_PER_JOB,
    MAX_SCENARIO_BYTES,
    MAX_SEED,
    PROTOCOL_VERSION,
    AckStatus,
    Identifier,
    JobState,
    LeaseState,
    Model,
    ParamValue,
    RunState,
    Scalar,
    Secret,
)
from swarmpath.service.result_columns import ColumnsHead
from swarmpath.service.result_frame import FrameHead, RunResultHead
from swarmpath.service.spec_checks import (
    INT64,
    FieldProblems,
    Loc,
)
from swarmpath.service.status_views import JobStatus, WorkerStatus, iso_time

#: Every name of the protocol, those defined in model, spec_checks and jobspec included.
__all__ = [
    "CANCEL_LEASES",
    "CELL_ADAPTER",
    "DEFAULT_PREFIX",
    "ID_PATTERN",
    "INLINE_SCENARIO_BYTES",
    "INT64",
    "JOB_SPEC_ADAPTER",
    "MAX_AGENTS",
    "MAX_BODY_BYTES",
    "MAX_BUNDLE_LEASES",
    "MAX_DIM",
    "MAX_ITERATIONS",
    "MAX_LEASE_RUNS",
    "MAX_RUNS_PER_CELL",
    "MAX_RUNS_PER_JOB",
    "MAX_SCENARIO_BYTES",
    "MAX_SEED",
    "PROTOCOL_VERSION",
    "WORK_REPLY_ADAPTER",
    "Ack",
    "AckStatus",
    "BenchmarkCell",
    "BenchmarkJobSpec",
    "Cancel",
    "CellNotes",
    "CellSpec",
    "ColumnsHead",
    "FieldProblems",
    "FrameHead",
    "Identifier",
    "JobSpec",
    "JobState",
    "JobStatus",
    "Keys",
    "Lease",
    "LeaseAck",
    "LeaseBundle",
    "LeaseDrop",
    "LeaseRequest",
    "LeaseState",
    "Loc",
    "M",
    "MapCell",
    "MapEntry",
    "MapJobSpec",
    "MapRef",
    "Model",
    "NoWork",
    "ParamValue",
    "ResultBatch",
    "RunAck",
    "RunProgress",
    "RunRequest",
    "RunResult",
    "RunResultHead",
    "RunState",
    "Scalar",
    "ScenarioRef",
    "ScenarioRequest",
    "Secret",
    "WorkReply",
    "WorkerStatus",
    "decode",
    "decode_work_reply",
    "encode",
    "error_fields",
    "expand_cells",
    "first_runs",
    "iso_time",
    "load_job_spec",
    "map_name",
    "parse_job_spec",
    "run_key",
    "runs_total",
]


# ------------------------------------------------------------------------------------ messages
class RunRequest(Model):
    """One run: what a lease expands into."""

    job_id: Identifier
    cell: str = Field(description="cell key, e.g. 'GWO/F1/30' or 'ICOOT/mfb-static'")
    cell_index: int = Field(ge=0)
    run: int = Field(ge=0, description="run index within the cell")
    run_id: int = Field(ge=0, description="cell_index * runs_per_cell + run")
    seed: int = Field(ge=0, le=MAX_SEED, description="the job seed")
    spec: CellSpec


Platform = Annotated[dict[str, Any], AfterValidator(clean_platform)]
Extensions = Annotated[dict[str, str], AfterValidator(clean_extensions)]


class LeaseRequest(Model):
    """Payload of a query on ``<prefix>/work``: a worker asks for up to ``max_runs`` runs."""

    worker: Identifier
    max_runs: int = Field(default=1, ge=1, le=MAX_LEASE_RUNS)
    max_leases: int = Field(
        default=1, ge=1, le=MAX_BUNDLE_LEASES,
        description="more than 1: the reply is a LeaseBundle of up to this many leases",
    )
    host: str = ""
    pid: int = 0
    slots: int = Field(default=1, ge=1)
    version: str = ""
    protocol: int = PROTOCOL_VERSION
    platform: Platform | None = Field(
        default=None, description="the worker's numeric platform (swarmpath.provenance), "
        "bounded; shown in GET /workers, never trusted for anything else")
    extensions: Extensions | None = Field(
        default=None, description="what the worker can run: '<kind>:<name>' (optimizer, "
        "function, suite, planner) -> the first 16 hex digits of its code's sha256 "
        "(swarmpath.plugins.pins); it is leased only cells whose pinned extensions it has. "
        "null: it advertises nothing and is leased only cells of built-ins")
    login: str = Field(default="", max_length=128,
                       description="the Zenoh login that owns `worker` (service/identity.py)")
    issued: int = Field(default=0, ge=0, le=2**63 - 1,
                        description="the worker's clock in ns, increasing request by request")
    proof: str = Field(default="", max_length=64, description="HMAC-SHA256 of the login's "
                       "password over the worker, login and issued (hex)")


class Lease(Model):
    """Reply to a LeaseRequest: several runs of one cell, owned by ``worker`` until ``deadline``.

    ``deadline`` is the coordinator's Unix time; workers on other clocks use ``lease_seconds``
    (measured from receipt) and renew with RunProgress at least every ``heartbeat_seconds``."""

    kind: Literal["lease"] = "lease"
    lease_id: Identifier
    worker: Identifier
    job_id: Identifier
    cell: str
    cell_index: int = Field(ge=0)
    runs_per_cell: int = Field(ge=1)
    seed: int = Field(ge=0, le=MAX_SEED)
    runs: list[int] = Field(min_length=1, description="run indices within the cell")
    spec: CellSpec
    deadline: float
    lease_seconds: float = Field(gt=0)
    heartbeat_seconds: float = Field(gt=0)
    capability: Secret = Field(
        description="the lease's secret: sent only in this reply, never put on the bus; results "
        "and progress of the lease prove it (HMAC), and so does the coordinator when it ends it",
    )

    pins: dict[str, str] = Field(
        default_factory=dict, description="the cell's extensions ('<kind>:<name>') and the "
        "sha256 of their code the job was pinned to: a worker whose code differs does not run "
        "the lease (it is not a failure; the runs go to another worker)")

    def run_ids(self) -> list[int]:
        return [self.cell_index * self.runs_per_cell + r for r in self.runs]

    def requests(self) -> list[RunRequest]:
        return [
            RunRequest(
                job_id=self.job_id,
                cell=self.cell,
                cell_index=self.cell_index,
                run=r,
                run_id=self.cell_index * self.runs_per_cell + r,
                seed=self.seed,
                spec=self.spec,
            )
            for r in self.runs
        ]


class ScenarioRequest(Model):
    """Payload of a query on ``<prefix>/scenarios/<sha256>``: the scenario of a lease the worker
    holds. ``proof`` is :func:`swarmpath.service.scenarios.request_proof` (HMAC with the lease's
    capability), so only the holder of a live lease on that scenario is answered. The reply is
    the canonical JSON itself (a reply error with the reason otherwise)."""

    worker: Identifier
    lease_id: Identifier
    proof: str = Field(max_length=128)


class NoWork(Model):
    """Reply to a LeaseRequest when nothing is leasable; ask again after ``retry_after`` s."""

    kind: Literal["no_work"] = "no_work"
    retry_after: float = Field(default=1.0, ge=0)
    reason: str = "empty"


class LeaseBundle(Model):
    """Reply to a LeaseRequest with ``max_leases`` > 1: one or more leases (of any cells and jobs)
    that together make about the coordinator's target of work. Each lease is independent (own
    id, deadline, heartbeats, results); a worker may run them one after the other in one slot,
    or together where that gives the same numbers (the Python worker stacks the benchmark leases
    that differ only in their function into one batch), and report their results in one
    ResultBatch."""

    kind: Literal["leases"] = "leases"
    leases: list[Lease] = Field(min_length=1, max_length=MAX_BUNDLE_LEASES)


WorkReply = Annotated[Lease | LeaseBundle | NoWork, Field(discriminator="kind")]
WORK_REPLY_ADAPTER: TypeAdapter[Lease | LeaseBundle | NoWork] = TypeAdapter(WorkReply)


class RunProgress(Model):
    """Published on ``<prefix>/progress/<job_id>`` while a lease runs; renews the lease."""

    lease_id: Identifier
    job_id: Identifier
    worker: Identifier
    cell: str
    runs: list[int] = Field(description="run indices still running")
    iteration: int = Field(default=0, ge=0, description="iterations (or planner steps) done")
    iterations: int = Field(default=0, ge=0, description="total iterations, 0 if unknown")
    best_fitness: list[float] | None = Field(default=None, description="per run, benchmark only")
    seq: int = Field(ge=1, description="1, 2, ... per lease: only a higher seq renews the lease")
    proof: Secret = Field(description="HMAC of (lease_id, seq) with the lease's capability")


class RunResult(Model):
    """One finished run. ``status`` 'failed' (with ``failure``, the exception text) is a run that
    raised: it counts as finished and is not retried. Benchmark metrics: best_fitness and
    evaluations (more are kept); map metrics: the fields of ``swarmpath plan --json`` (success,
    collisions, length, error, smoothness, ...) without the path, which goes in ``path``.
    """

    lease_id: Identifier
    job_id: Identifier
    cell: str
    run: int = Field(ge=0)
    worker: Identifier
    status: Literal["ok", "failed"] = "ok"
    failure: str | None = Field(default=None, max_length=20_000)
    seconds: float = Field(ge=0, description="wall seconds of this run (its share of a batch)")
    cpu_seconds: float | None = Field(
        default=None, ge=0, description="CPU seconds of this run (its share of a batch): the "
        "computing thread's CPU time; null: not measured (a worker from before it was sent)")
    metrics: dict[str, Scalar] = Field(
        default_factory=dict,
        description="map runs may add notes on their map (swarmpath.service.cell_notes; the "
        "coordinator keeps only strings of at most 300 characters, schema cell_notes): "
        "'optimum_reason' (only when the run has no exact optimum: why) and "
        "'warning:goal_motion' / 'warning:obstacles[k]' (a stated path crossing a static "
        "obstacle, at most 8)")
    curve: list[float] | None = Field(
        default=None, max_length=MAX_ITERATIONS, description="best fitness after each iteration"
    )
    best_position: list[float] | None = Field(default=None, max_length=MAX_DIM)
    path: list[tuple[float, float, float]] | None = Field(
        default=None, description="executed trajectory rows [x, y, t] (map runs)"
    )
    proof: Secret | None = Field(
        default=None, description="HMAC of this result's JSON (without proof) with the lease's "
        "capability; a result without a valid one is stale",
    )


class ResultBatch(Model):
    """Published on ``<prefix>/results/<job_id>``: one or more results of one worker."""

    worker: Identifier
    results: list[RunResult] = Field(min_length=1, max_length=MAX_LEASE_RUNS)


class RunAck(Model):
    lease_id: str
    job_id: str
    cell: str
    run: int
    status: AckStatus


class LeaseDrop(Model):
    """The coordinator ends a lease: ``proof`` (HMAC of the lease id with the lease's capability)
    shows the order comes from the coordinator; workers ignore drops without a valid one."""

    lease_id: Identifier
    proof: Secret


class LeaseAck(Model):
    """The statuses of one lease's results in an :class:`Ack`: its run indices by status."""

    lease_id: str
    accepted: list[int] = Field(default_factory=list)
    duplicate: list[int] = Field(default_factory=list)
    stale: list[int] = Field(default_factory=list)


class Ack(Model):
    """Published on ``<prefix>/ack/<worker>`` after the results are durably stored.

    ``leases``: the statuses of the message's results, per lease (protocol 4; ``results``, one
    entry per result, is what protocol 3 sent and stays readable). ``drop_leases``: leases the
    worker must abandon (cancelled, expired, unknown); it stops their unfinished runs and stops
    retrying their results."""

    worker: Identifier
    results: list[RunAck] = Field(default_factory=list)
    leases: list[LeaseAck] = Field(default_factory=list)
    drop_leases: list[LeaseDrop] = Field(default_factory=list, max_length=MAX_BUNDLE_LEASES * 16)

    def statuses(self) -> list[tuple[str, int, AckStatus]]:
        """(lease id, run, status) of every result acknowledged, in either form."""
        out: list[tuple[str, int, AckStatus]] = [(r.lease_id, r.run, r.status)
                                                 for r in self.results]
        for la in self.leases:
            for status in ("accepted", "duplicate", "stale"):
                out += [(la.lease_id, run, status) for run in getattr(la, status)]
        return out


class Cancel(Model):
    """Published on ``<prefix>/cancel`` when a job is cancelled: the job's leases that were active,
    each with its drop proof (several messages for many leases). A worker drops the listed leases
    it holds whose proof is valid, and nothing else."""

    job_id: Identifier
    leases: list[LeaseDrop] = Field(default_factory=list, max_length=CANCEL_LEASES)


# ----------------------------------------------------------------------------------- encoding
M = TypeVar("M", bound=BaseModel)


def encode(message: BaseModel) -> bytes:
    """The wire form of a message: compact UTF-8 JSON."""
    return message.model_dump_json(exclude_none=False).encode()


def decode(model: type[M], payload: bytes | str) -> M:
    """Parse and validate a message (raises :class:`pydantic.ValidationError`)."""
    if isinstance(payload, bytes | bytearray) and len(payload) > MAX_BODY_BYTES:
        raise ValueError(f"payload of {len(payload)} bytes exceeds {MAX_BODY_BYTES}")
    return model.model_validate_json(payload)


def decode_work_reply(payload: bytes | str) -> Lease | LeaseBundle | NoWork:
    return WORK_REPLY_ADAPTER.validate_json(payload)


def error_fields(exc: Exception) -> list[str]:
    """Dotted locations of a ValidationError's errors (``['benchmark.dims.0', ...]``)."""
    errors = getattr(exc, "errors", None)
    if errors is None:
        return []
    return [".".join(str(p) for p in e["loc"]) for e in errors()]
