"""The messages of the swarmpath service and the Zenoh key expressions they travel on.

Every message is UTF-8 JSON of one of the pydantic models below (unknown fields are rejected). The
protocol itself - who sends what on which key, leases, fencing, acknowledgements, cancellation - is
documented for implementers in other languages in ``schemas/README.md``; the JSON Schemas exported
from these models by :mod:`swarmpath.service.schemas` are next to it.

Job specs are validated here, completely: unknown algorithm / function / planner / map names,
unknown or out-of-range algorithm parameters, and the size limits all fail with a
:class:`pydantic.ValidationError` whose error location names the field (FastAPI turns that into a
422 with the same location). Use :func:`parse_job_spec` (or :data:`JOB_SPEC_ADAPTER`).

A job expands into *cells* (benchmark: algorithm x function x dim; map: planner x map), each with
``runs`` runs numbered 0..runs-1. Run ``r`` of cell ``c`` has the job-wide ``run_id = c * runs +
r``. A run is fully determined by (cell spec, job seed, run index): whichever worker executes it,
it gives the same numbers.
"""

from __future__ import annotations

import importlib
import json
import math
import re
from collections.abc import Callable, Mapping, Sequence
from datetime import UTC, datetime
from typing import Annotated, Any, Literal, TypeVar

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    TypeAdapter,
    ValidationInfo,
    computed_field,
    field_validator,
    model_validator,
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

PROTOCOL_VERSION = 2  # 2: lease capabilities (see swarmpath.service.capability)
DEFAULT_PREFIX = "swarmpath"

# Identifiers that appear inside key expressions: one chunk, none of the reserved characters.
ID_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,127}$"
_ID_RE = re.compile(ID_PATTERN)

ParamValue = bool | int | float | str
Scalar = bool | int | float | str | None
JobState = Literal["queued", "running", "done", "failed", "cancelled"]
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


# ------------------------------------------------------------------------------------ validation
Loc = tuple[str | int, ...]


class FieldProblems(ValueError):
    """Problems inside one field, each at its own place: ``(location below the field,
    message)``. The REST error handler (:mod:`swarmpath.service.errors`) gives each its own
    detail item, so that ``loc`` reaches the field (``maps.0.obstacles.2.radius``)."""

    def __init__(self, problems: Sequence[tuple[Loc, str]]):
        self.problems = list(problems)
        super().__init__("; ".join(
            f"{'.'.join(str(p) for p in loc)}: {msg}" if loc else msg for loc, msg in problems))


#: Parameter numbers: integers within 64 bits, floats finite (anything else would only fail later,
#: inside numpy, with numpy's words).
INT64 = 2**63


def _bounded_numbers(value: Any) -> Any:
    """Every number inside job parameters, checked before the parameters' own validation:
    integers within +-2**63, floats finite; each problem at its place (``GWO.a_max``)."""
    problems: list[tuple[Loc, str]] = []
    todo: list[tuple[Loc, Any]] = [((), value)]
    while todo and len(problems) < 20:
        loc, v = todo.pop()
        if isinstance(v, bool) or v is None or isinstance(v, str):
            continue
        if isinstance(v, int):
            if not -INT64 <= v < INT64:
                digits = len(str(abs(v))) if abs(v) < 10**4300 else 4300
                problems.append((loc, f"an integer of {digits} digits is out of range "
                                      f"(parameters are 64-bit: |value| < 9.22e18)"))
        elif isinstance(v, float):
            if not math.isfinite(v):
                problems.append((loc, f"must be a finite number, got {v}"))
        elif isinstance(v, dict):
            if len(loc) < 8:
                todo += [((*loc, k), x) for k, x in v.items()]
        elif isinstance(v, list | tuple) and len(loc) < 8:
            todo += [((*loc, i), x) for i, x in enumerate(v)]
    if problems:
        raise FieldProblems(problems)
    return value


def _scenario_loc(path: str) -> Loc:
    """``obstacles[2].radius`` (the world layer's paths) -> ``('obstacles', 2, 'radius')``."""
    parts: list[str | int] = []
    for token in re.findall(r"\[(\d+)\]|([^.\[\]]+)", path):
        parts.append(int(token[0]) if token[0] else token[1])
    return tuple(parts)


def _unknown_names(v: Sequence[str], valid: Sequence[str], kind: str) -> None:
    from swarmpath.names import unknown

    problems: list[tuple[Loc, str]] = [
        ((i,), unknown(kind, name, valid)) for i, name in enumerate(v) if name not in valid
    ]
    if problems:
        raise FieldProblems(problems)


def _unique(values: Sequence[Any], what: str) -> None:
    seen: set[Any] = set()
    for v in values:
        key = json.dumps(v, sort_keys=True) if isinstance(v, dict) else v
        if key in seen:
            raise ValueError(f"duplicate {what} {v!r}")
        seen.add(key)


def _check_total(info: ValidationInfo, runs: int, axes: Sequence[str]) -> int:
    """The 1,000,000-runs-per-job limit, raised on ``runs`` (a field the user can change)."""
    sizes = []
    for axis in axes:
        value = info.data.get(axis)
        if value is None:  # that field failed its own validation: its error is reported already
            return runs
        sizes.append(len(value))
    total = runs * math.prod(sizes)
    if total > MAX_RUNS_PER_JOB:
        shape = " x ".join(f"{n} {axis}" for n, axis in zip(sizes, axes, strict=True))
        raise ValueError(
            f"{shape} x {runs} runs = {total} runs; a job may have at most {MAX_RUNS_PER_JOB}"
        )
    return runs


def _planner_registry() -> Any:
    """``swarmpath.planners``, imported on first use (it pulls in the whole planning stack)."""
    return importlib.import_module("swarmpath.planners")


def _map_names() -> list[str]:
    from swarmpath.world.presets import list_maps

    return list(list_maps())


def _inline_scenario_problems(scenario: Mapping[str, Any]) -> list[tuple[Loc, str]]:
    """Full validation of an inline scenario by the world layer's JSON reader: each problem at
    its place inside the scenario."""
    from swarmpath.world.scenario_io import ScenarioError, scenario_from_dict

    try:
        scenario_from_dict(dict(scenario))
    except ScenarioError as exc:
        return [(_scenario_loc(path), msg) for path, msg in exc.problems]
    except (ValueError, TypeError, KeyError) as exc:
        return [((), str(exc))]
    return []


# -------------------------------------------------------------------------------------- job specs
class BenchmarkJobSpec(Model):
    """Optimizer benchmark: every algorithm on every function at every dimension, ``runs`` runs
    each. The field order matters for validation (later fields are checked against earlier ones)."""

    kind: Literal["benchmark"]
    algorithms: list[str] = Field(min_length=1, description="registered optimizer names")
    functions: list[str] = Field(
        min_length=1, description="function names; ranges such as 'F1-F13' are expanded"
    )
    dims: list[Annotated[int, Field(ge=1, le=MAX_DIM, strict=True)]] = Field(
        default=[30], min_length=1)
    runs: int = Field(default=30, ge=1, le=MAX_RUNS_PER_CELL, strict=True,
                      description="runs per cell")
    agents: int = Field(default=30, ge=1, le=MAX_AGENTS, strict=True)
    iterations: int = Field(default=500, ge=1, le=MAX_ITERATIONS, strict=True)
    seed: int = Field(default=1, ge=0, le=MAX_SEED, strict=True)
    shifted: bool = Field(default=False, strict=True, description="alias of transform 'shift'")
    transform: str = Field(
        default="none",
        validate_default=True,
        description="none, shift, rotate or shift+rotate: each run's function moved and/or "
        "turned with numbers from the run's own streams",
    )
    params: Annotated[dict[str, dict[str, ParamValue]], BeforeValidator(_bounded_numbers)] = Field(
        default_factory=dict, description="{algorithm: {parameter: value}}"
    )

    @field_validator("transform")
    @classmethod
    def _known_transform(cls, v: str, info: ValidationInfo) -> str:
        return _transform(v, bool(info.data.get("shifted")))

    @model_validator(mode="after")
    def _shifted_follows_transform(self) -> BenchmarkJobSpec:
        self.shifted = "shift" in self.transform
        return self

    @field_validator("algorithms")
    @classmethod
    def _known_algorithms(cls, v: list[str]) -> list[str]:
        from swarmpath.optimizers import list_optimizers

        _unknown_names(v, list_optimizers(), "algorithm")
        _unique(v, "algorithm")
        return v

    @field_validator("functions")
    @classmethod
    def _known_functions(cls, v: list[str]) -> list[str]:
        from swarmpath.functions import expand_function_names

        names: list[str] = []
        problems: list[tuple[Loc, str]] = []
        for i, item in enumerate(v):
            try:
                names.extend(expand_function_names(item))
            except KeyError as exc:
                problems.append(((i,), str(exc.args[0]) if exc.args else str(exc)))
        if problems:
            raise FieldProblems(problems)
        if not names:
            raise ValueError("no function names given")
        _unique(names, "function")
        return names

    @field_validator("dims")
    @classmethod
    def _unique_dims(cls, v: list[int], info: ValidationInfo) -> list[int]:
        _unique(v, "dim")
        from swarmpath.functions import get_function

        for name in info.data.get("functions") or ():
            low = int(getattr(get_function(name), "min_dim", 1))
            bad = [d for d in v if d < low]
            if bad:
                raise ValueError(f"{name} needs dim >= {low}, got {bad[0]}")
        return v

    @field_validator("runs")
    @classmethod
    def _total_runs(cls, v: int, info: ValidationInfo) -> int:
        return _check_total(info, v, ("algorithms", "functions", "dims"))

    @field_validator("agents")
    @classmethod
    def _enough_agents(cls, v: int, info: ValidationInfo) -> int:
        from swarmpath.optimizers import get_optimizer

        for name in info.data.get("algorithms") or ():
            low = get_optimizer(name).min_agents
            if v < low:
                raise ValueError(f"{name} needs agents >= {low}, got {v}")
        return v

    @field_validator("params")
    @classmethod
    def _known_params(
        cls, v: dict[str, dict[str, ParamValue]], info: ValidationInfo
    ) -> dict[str, dict[str, ParamValue]]:
        from swarmpath.optimizers import get_optimizer

        return _params_of_members(
            v, info.data.get("algorithms"), "algorithms",
            lambda name, params: get_optimizer(name).resolve_params(params),
        )

    reference: str | None = Field(
        default=None,
        description="algorithm the summary's +/=/- markers compare against "
        "(default: the last of algorithms)",
    )

    @field_validator("reference")
    @classmethod
    def _reference_of_members(cls, v: str | None, info: ValidationInfo) -> str | None:
        return _reference(v, info.data.get("algorithms"))


def _transform(v: str, shifted: bool) -> str:
    """A registered transform; ``shifted`` (the former flag) means ``shift`` and must agree."""
    from swarmpath.functions.transforms import TRANSFORMS
    from swarmpath.names import did_you_mean

    if v not in TRANSFORMS:
        raise ValueError(f"must be one of {', '.join(TRANSFORMS)}, got {v!r}"
                         + did_you_mean(v, TRANSFORMS))
    if shifted and v == "none":
        return "shift"
    if shifted and "shift" not in v:
        raise ValueError(f"{v!r} contradicts shifted: true (which means 'shift')")
    return v


def _reference(v: str | None, members: list[str] | None) -> str | None:
    """A reference among the job's members (case-insensitive, stored as registered)."""
    if v is None or members is None:  # no reference, or the members failed their validation
        return v
    from swarmpath.compare import resolve_reference

    return resolve_reference(members, v)


def _params_of_members(
    v: dict[str, Any], members: list[str] | None, what: str, resolve: Callable[[str, Any], Any]
) -> dict[str, Any]:
    """Per-member parameters: only for the job's own members, each accepted by its resolver."""
    from swarmpath.names import did_you_mean

    if members is None:  # the member list itself failed validation: that error is reported
        return v
    problems: list[tuple[Loc, str]] = []
    for name, params in v.items():
        if name not in members:
            problems.append(((name,), f"not one of the job's {what}{did_you_mean(name, members)}"
                             f" ({', '.join(members)})"))
            continue
        keyed = False
        for key, value in params.items():  # each parameter on its own: loc params.NAME.KEY
            try:
                resolve(name, {key: value})
            except (ValueError, TypeError, KeyError, ArithmeticError) as exc:
                problems.append(((name, key), str(exc.args[0]) if exc.args else str(exc)))
                keyed = True
        if not keyed:  # then together (a rule across parameters)
            try:
                resolve(name, params)
            except (ValueError, TypeError, KeyError, ArithmeticError) as exc:
                problems.append(((name,), str(exc.args[0]) if exc.args else str(exc)))
    if problems:
        raise FieldProblems(problems)
    return v


class MapRef(Model):
    """A map uploaded with ``POST /maps``, by id, with optional start and goal (metres from the
    map's lower-left corner). The coordinator replaces it with the stored scenario when the job
    is submitted, so the job carries its map (:func:`swarmpath.service.maps.resolve_refs`)."""

    map: str = Field(pattern=ID_PATTERN, description="id from POST /maps")
    start: tuple[float, float] | None = None
    goal: tuple[float, float] | None = None


MapEntry = Annotated[str | MapRef | dict[str, Any], Field(union_mode="left_to_right")]


def map_name(entry: str | MapRef | dict[str, Any]) -> str:
    """The name of a map entry: a preset name, an uploaded map's id, or an inline scenario's
    ``name``."""
    if isinstance(entry, str):
        return entry
    if isinstance(entry, MapRef):
        return entry.map
    return str(entry["name"])


class MapJobSpec(Model):
    """Path-planning study: every planner on every map (preset name or inline scenario object)."""

    kind: Literal["map"]
    planners: list[str] = Field(min_length=1, description="registered planner names")
    maps: list[MapEntry] = Field(
        min_length=1, description="preset map names, inline scenario objects (with a 'name') "
        "or uploaded maps {'map': id, 'start'?: [x, y], 'goal'?: [x, y]}"
    )
    runs: int = Field(default=10, ge=1, le=MAX_RUNS_PER_CELL, strict=True,
                      description="runs per cell")
    seed: int = Field(default=1, ge=0, le=MAX_SEED, strict=True)
    params: Annotated[dict[str, dict[str, Any]], BeforeValidator(_bounded_numbers)] = Field(
        default_factory=dict, description="{planner: {parameter: value}}"
    )

    @field_validator("planners")
    @classmethod
    def _known_planners(cls, v: list[str]) -> list[str]:
        _unknown_names(v, list(_planner_registry().list_planners()), "planner")
        _unique(v, "planner")
        return v

    @field_validator("maps")
    @classmethod
    def _known_maps(cls, v: list[MapEntry]) -> list[MapEntry]:
        from swarmpath.names import unknown

        presets: list[str] | None = None
        problems: list[tuple[Loc, str]] = []
        for i, entry in enumerate(v):
            if isinstance(entry, str):
                if presets is None:
                    presets = _map_names()
                if entry not in presets:
                    problems.append(((i,), unknown("map", entry, presets)))
                continue
            if isinstance(entry, MapRef):  # resolved against the stored maps on submission
                continue
            inner = [((i, *loc), msg) for loc, msg in _inline_scenario_problems(entry)]
            name = entry.get("name")
            if not isinstance(name, str) or not _ID_RE.match(name):
                # this one message says all about the name (the reader's "required" is dropped)
                inner = [(loc, msg) for loc, msg in inner if loc != (i, "name")]
                problems.append(((i, "name"), "an inline scenario needs a 'name' of letters, "
                                 "digits, '_', '.', '-'"))
            problems += inner
        if problems:
            raise FieldProblems(problems)
        _unique([map_name(e) for e in v], "map name")
        return v

    @field_validator("runs")
    @classmethod
    def _total_runs(cls, v: int, info: ValidationInfo) -> int:
        return _check_total(info, v, ("planners", "maps"))

    @field_validator("params")
    @classmethod
    def _known_params(
        cls, v: dict[str, dict[str, Any]], info: ValidationInfo
    ) -> dict[str, dict[str, Any]]:
        def resolve(name: str, params: Any) -> None:
            getter = getattr(_planner_registry(), "get_planner", None)
            resolver = getattr(getter(name), "resolve_params", None) if getter else None
            if resolver is not None:
                resolver(params)

        return _params_of_members(v, info.data.get("planners"), "planners", resolve)

    reference: str | None = Field(
        default=None,
        description="planner the summary's +/=/- markers compare against "
        "(default: the last of planners)",
    )

    @field_validator("reference")
    @classmethod
    def _reference_of_members(cls, v: str | None, info: ValidationInfo) -> str | None:
        return _reference(v, info.data.get("planners"))


JobSpec = Annotated[BenchmarkJobSpec | MapJobSpec, Field(discriminator="kind")]
JOB_SPEC_ADAPTER: TypeAdapter[BenchmarkJobSpec | MapJobSpec] = TypeAdapter(JobSpec)


def parse_job_spec(data: Mapping[str, Any] | str | bytes) -> BenchmarkJobSpec | MapJobSpec:
    """Validate a job spec (a dict, or JSON text). Raises :class:`pydantic.ValidationError`."""
    if isinstance(data, str | bytes):
        return JOB_SPEC_ADAPTER.validate_json(data)
    return JOB_SPEC_ADAPTER.validate_python(data)


def load_job_spec(data: Mapping[str, Any] | str | bytes) -> BenchmarkJobSpec | MapJobSpec:
    """A spec this service stored earlier (validated and normalized then): rebuilt without
    registry lookups, so stored jobs stay readable when the registries change."""
    obj = json.loads(data) if isinstance(data, str | bytes) else dict(data)
    cls: type[BenchmarkJobSpec] | type[MapJobSpec] = (
        BenchmarkJobSpec if obj.get("kind") == "benchmark" else MapJobSpec
    )
    return cls.model_construct(**obj)


# ---------------------------------------------------------------------------------------- cells
class BenchmarkCell(Model):
    """Everything a worker needs to run one benchmark cell (besides the job seed and run index):
    ``minimize(algorithm, function, dim, agents, iterations, seed=seed, params=params,
    shifted=shifted, run_ids=[...])``."""

    kind: Literal["benchmark"] = "benchmark"
    algorithm: str
    function: str
    dim: int
    agents: int
    iterations: int
    shifted: bool = False
    params: dict[str, ParamValue] = Field(default_factory=dict)
    transform: str = Field(default="none", validate_default=True)

    @field_validator("transform")
    @classmethod
    def _known_transform(cls, v: str, info: ValidationInfo) -> str:
        return _transform(v, bool(info.data.get("shifted")))

    @property
    def key(self) -> str:
        return f"{self.algorithm}/{self.function}/{self.dim}"


class MapCell(Model):
    """One planner on one map. ``scenario`` is the inline scenario object, or null for a preset."""

    kind: Literal["map"] = "map"
    planner: str
    map: str
    scenario: dict[str, Any] | None = None
    params: dict[str, Any] = Field(default_factory=dict)

    @property
    def key(self) -> str:
        return f"{self.planner}/{self.map}"


CellSpec = Annotated[BenchmarkCell | MapCell, Field(discriminator="kind")]
CELL_ADAPTER: TypeAdapter[BenchmarkCell | MapCell] = TypeAdapter(CellSpec)


def expand_cells(spec: BenchmarkJobSpec | MapJobSpec) -> list[BenchmarkCell | MapCell]:
    """The job's cells in table order (algorithm-major / planner-major); index = position."""
    if isinstance(spec, BenchmarkJobSpec):
        return [
            BenchmarkCell(
                algorithm=a,
                function=f,
                dim=d,
                agents=spec.agents,
                iterations=spec.iterations,
                shifted=spec.shifted,
                params=dict(spec.params.get(a, {})),
                transform=spec.transform,
            )
            for a in spec.algorithms
            for f in spec.functions
            for d in spec.dims
        ]
    if any(isinstance(m, MapRef) for m in spec.maps):
        raise ValueError("uploaded maps must be resolved (swarmpath.service.maps.resolve_refs)")
    return [
        MapCell(
            planner=p,
            map=map_name(m),
            scenario=None if isinstance(m, str) else dict(m),  # type: ignore[arg-type]
            params=dict(spec.params.get(p, {})),
        )
        for p in spec.planners
        for m in spec.maps
    ]


def runs_total(spec: BenchmarkJobSpec | MapJobSpec) -> int:
    if isinstance(spec, BenchmarkJobSpec):
        return len(spec.algorithms) * len(spec.functions) * len(spec.dims) * spec.runs
    return len(spec.planners) * len(spec.maps) * spec.runs


def run_key(job_id: str, run_id: int) -> str:
    """A run's name across jobs, as listed in ``WorkerStatus.current_runs``."""
    return f"{job_id}:{run_id}"


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


class NoWork(Model):
    """Reply to a LeaseRequest when nothing is leasable; ask again after ``retry_after`` s."""

    kind: Literal["no_work"] = "no_work"
    retry_after: float = Field(default=1.0, ge=0)
    reason: str = "empty"


class LeaseBundle(Model):
    """Reply to a LeaseRequest with ``max_leases`` > 1: one or more leases (of any cells and jobs)
    that together make about the coordinator's target of work. Each lease is independent (own
    id, deadline, heartbeats, results); a worker may run them one after the other in one slot
    and report their results in one ResultBatch."""

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
    metrics: dict[str, Scalar] = Field(default_factory=dict)
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


class Ack(Model):
    """Published on ``<prefix>/ack/<worker>`` after the results are durably stored.

    ``drop_leases``: leases the worker must abandon (cancelled, expired, unknown); it stops their
    unfinished runs and stops retrying their results."""

    worker: Identifier
    results: list[RunAck] = Field(default_factory=list)
    drop_leases: list[LeaseDrop] = Field(default_factory=list, max_length=MAX_BUNDLE_LEASES * 16)


class Cancel(Model):
    """Published on ``<prefix>/cancel`` when a job is cancelled: the job's leases that were active,
    each with its drop proof (several messages for many leases). A worker drops the listed leases
    it holds whose proof is valid, and nothing else."""

    job_id: Identifier
    leases: list[LeaseDrop] = Field(default_factory=list, max_length=CANCEL_LEASES)


def iso_time(t: float | None) -> str | None:
    """Unix time -> ISO 8601 in UTC with milliseconds (``2026-11-25T07:41:01.123Z``)."""
    if not t:
        return None
    stamp = datetime.fromtimestamp(t, tz=UTC)
    return stamp.strftime("%Y-%m-%dT%H:%M:%S.") + f"{stamp.microsecond // 1000:03d}Z"


class WorkerStatus(Model):
    """One entry of ``GET /workers``."""

    id: Identifier
    host: str = ""
    pid: int = 0
    slots: int = 1
    current_runs: list[str] = Field(default_factory=list, description="'<job_id>:<run_id>'")
    runs_done: int = 0
    last_seen: float = Field(0.0, description="Unix time")
    alive: bool = True

    @computed_field  # type: ignore[prop-decorator]
    @property
    def last_seen_at(self) -> str | None:
        """``last_seen`` in ISO 8601 (UTC)."""
        return iso_time(self.last_seen)


class JobStatus(Model):
    """``GET /jobs/{id}``."""

    id: str
    kind: Literal["benchmark", "map"]
    state: JobState
    runs_total: int
    runs_done: int
    runs_failed: int
    created: float = Field(description="Unix time; created_at is the same in ISO 8601")
    started: float | None = None
    finished: float | None = None

    @computed_field  # type: ignore[prop-decorator]
    @property
    def created_at(self) -> str | None:
        """``created`` in ISO 8601 (UTC)."""
        return iso_time(self.created)

    @computed_field  # type: ignore[prop-decorator]
    @property
    def started_at(self) -> str | None:
        return iso_time(self.started)

    @computed_field  # type: ignore[prop-decorator]
    @property
    def finished_at(self) -> str | None:
        return iso_time(self.finished)


# ------------------------------------------------------------------------------- key expressions
class Keys:
    """The key expressions, all under one prefix (default ``swarmpath``)."""

    def __init__(self, prefix: str = DEFAULT_PREFIX):
        if not prefix or prefix.startswith("/") or prefix.endswith("/") or any(
            c in prefix for c in "*$#?"
        ):
            raise ValueError(f"bad key prefix {prefix!r}")
        self.prefix = prefix

    @property
    def work(self) -> str:
        """Queryable: LeaseRequest -> Lease | NoWork."""
        return f"{self.prefix}/work"

    def results(self, job_id: str) -> str:
        return f"{self.prefix}/results/{_chunk(job_id)}"

    def progress(self, job_id: str) -> str:
        return f"{self.prefix}/progress/{_chunk(job_id)}"

    def ack(self, worker: str) -> str:
        return f"{self.prefix}/ack/{_chunk(worker)}"

    def worker_token(self, worker: str) -> str:
        """Liveliness token of a worker."""
        return f"{self.prefix}/workers/{_chunk(worker)}"

    @property
    def cancel(self) -> str:
        return f"{self.prefix}/cancel"

    # subscriptions of the coordinator
    @property
    def all_results(self) -> str:
        return f"{self.prefix}/results/*"

    @property
    def all_progress(self) -> str:
        return f"{self.prefix}/progress/*"

    @property
    def all_workers(self) -> str:
        return f"{self.prefix}/workers/*"

    @staticmethod
    def last_chunk(key: str) -> str:
        return key.rsplit("/", 1)[-1]


def _chunk(value: str) -> str:
    if not _ID_RE.match(value):
        raise ValueError(f"{value!r} is not a valid identifier ({ID_PATTERN})")
    return value


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


# The models exported to schemas/ (file stem -> model or adapter); see swarmpath.service.schemas.
# Messages the coordinator sends are exported as it writes them (every field present); those it
# receives (from users and workers) as it reads them (fields with defaults may be left out).
SENT_BY_COORDINATOR = frozenset(
    {"cell_spec", "run_request", "work_reply", "lease", "lease_bundle", "no_work", "ack", "cancel",
     "lease_drop", "worker_status", "job_status"}
)
SCHEMA_MODELS: dict[str, Any] = {
    "job_spec": JOB_SPEC_ADAPTER,
    "benchmark_job_spec": BenchmarkJobSpec,
    "map_job_spec": MapJobSpec,
    "cell_spec": CELL_ADAPTER,
    "run_request": RunRequest,
    "lease_request": LeaseRequest,
    "work_reply": WORK_REPLY_ADAPTER,
    "lease": Lease,
    "lease_bundle": LeaseBundle,
    "no_work": NoWork,
    "run_progress": RunProgress,
    "run_result": RunResult,
    "result_batch": ResultBatch,
    "ack": Ack,
    "lease_drop": LeaseDrop,
    "cancel": Cancel,
    "worker_status": WorkerStatus,
    "job_status": JobStatus,
}
