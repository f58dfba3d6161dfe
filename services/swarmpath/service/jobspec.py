"""Job specs (benchmark and map), validated completely, and the cells a job expands into
(the cell models are in :mod:`swarmpath.service.cells`; their names stay importable here).

Every problem is a :class:`pydantic.ValidationError` whose location names the field; use
:func:`parse_job_spec` (or :data:`JOB_SPEC_ADAPTER`). Run ``r`` of cell ``c`` has the job-wide
``run_id = c * runs + r``."""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Annotated, Any, Literal

from pydantic import (
    BeforeValidator,
    Field,
    TypeAdapter,
    ValidationInfo,
    field_validator,
    model_validator,
)

from swarmpath.service.cells import CELL_ADAPTER as CELL_ADAPTER
from swarmpath.service.cells import BenchmarkCell, MapCell, _transform
from swarmpath.service.cells import CellSpec as CellSpec
from swarmpath.service.cells import ScenarioRef as ScenarioRef
from swarmpath.service.cells import run_key as run_key
from swarmpath.service.jobspec_map import MapEntry as MapEntry
from swarmpath.service.jobspec_map import MapJobSpec as MapJobSpec
from swarmpath.service.jobspec_map import MapRef as MapRef
from swarmpath.service.jobspec_map import map_name as map_name
from swarmpath.service.model import (
    MAX_AGENTS,
    MAX_DIM,
    MAX_ITERATIONS,
    MAX_RUNS_PER_CELL,
    MAX_SEED,
    Model,
    ParamValue,
)
from swarmpath.service.racing import RacingSpec, check_racing
from swarmpath.service.spec_checks import (
    FieldProblems,
    Loc,
    _bounded_numbers,
    _check_total,
    _params_of_members,
    _reference,
    _unique,
    _unknown_names,
)
from swarmpath.service.spec_suites import (
    MAX_INSTANCE,
    MAX_INSTANCES,
    _check_budget,
    _with_instances,
)


# -------------------------------------------------------------------------------------- job specs
class BenchmarkJobSpec(Model):
    """Optimizer benchmark: every algorithm on every function at every dimension, ``runs`` runs
    each. The field order matters for validation (later fields are checked against earlier ones)."""

    kind: Literal["benchmark"]
    algorithms: list[str] = Field(min_length=1, description="registered optimizer names")
    instances: list[Annotated[int, Field(ge=1, le=MAX_INSTANCE, strict=True)]] | None = Field(
        default=None, min_length=1, max_length=MAX_INSTANCES,
        description="suite instances (bbob: COCO's ids; CEC: 1): every suite function runs on "
        "each, as its own cells (named <suite>:<function>@i<k>); null: instance 1")
    functions: list[str] = Field(
        min_length=1, description="function names; ranges such as 'F1-F13', suite names "
        "('bbob', 'cec2017', 'cec2022') and suite ranges ('bbob:f1-f5') are expanded"
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
        kind = _transform(v, bool(info.data.get("shifted")))
        from swarmpath.functions import get_function

        for name in info.data.get("functions") or ():
            if kind != "none" and getattr(get_function(name), "suite", ""):
                raise ValueError(f"{name} is shifted and rotated by its instance; transform "
                                 f"must be 'none', got {kind!r}")
        return kind

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
    def _known_functions(cls, v: list[str], info: ValidationInfo) -> list[str]:
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
        return _with_instances(names, info.data.get("instances"))

    @field_validator("dims")
    @classmethod
    def _unique_dims(cls, v: list[int], info: ValidationInfo) -> list[int]:
        _unique(v, "dim")
        from swarmpath.functions import get_function

        for name in info.data.get("functions") or ():
            fn = get_function(name)
            low = int(getattr(fn, "min_dim", 1))
            bad = [d for d in v if d < low]
            if bad:
                raise ValueError(f"{name} needs dim >= {low}, got {bad[0]}")
            for d in v:
                try:
                    fn.check_study(d, "none")
                except ValueError as exc:
                    raise ValueError(str(exc)) from None
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

    backend: str = Field(
        default="auto",
        description="auto (the compiled kernels where the worker has numba and the study has "
        "kernels, else numpy), numpy (the reference) or numba (compiled kernels only): the "
        "reference's numbers run for run, within each kernel's stated tolerance (0 for every "
        "built-in kernel). Workers compile the kernels before they take work",
    )

    @field_validator("backend")
    @classmethod
    def _supported_backend(cls, v: str, info: ValidationInfo) -> str:
        from swarmpath.optimizers import ParameterError
        from swarmpath.optimizers.api import check_backend

        try:
            check_backend(v, info.data.get("algorithms") or (),
                          info.data.get("transform") or "none", info.data.get("params"),
                          info.data.get("functions") or ())
        except ParameterError as exc:
            raise ValueError(str(exc)) from None
        return v

    racing: RacingSpec | None = Field(
        default=None,
        description="race the cells: runs in rounds, a cell stops once its comparisons are "
        "decided (docs/statistics.md, Racing); runs is then the most a cell may get",
    )

    @field_validator("racing")
    @classmethod
    def _racing_fits_the_job(cls, v: RacingSpec | None, info: ValidationInfo) -> (
            RacingSpec | None):
        if v is None or "runs" not in info.data or "algorithms" not in info.data:
            return v  # no race, or runs/algorithms failed themselves: that error is reported
        problems = check_racing(v, info.data["runs"], info.data["algorithms"])
        if problems:
            raise FieldProblems(problems)
        return v.model_copy(update={"max_runs": info.data["runs"]})

    budget_evals: str | None = Field(
        default=None, max_length=32,
        description="evaluations per run, 'N' or 'NxD' (N times the dimension: CEC's "
        "'10000xD'); each algorithm gets the iterations that spend it (swarmpath.optimizers."
        "budget) and no run counts an evaluation past it; null: agents x iterations")

    @field_validator("budget_evals")
    @classmethod
    def _budget_fits(cls, v: str | None, info: ValidationInfo) -> str | None:
        return _check_budget(v, info)

    def evaluations(self, dim: int) -> int | None:
        """The budget of one run at ``dim`` (None: agents x iterations)."""
        from swarmpath.optimizers.budget import budget_at

        return budget_at(self.budget_evals, dim)

    def iterations_for(self, algorithm: str, dim: int) -> int:
        from swarmpath.optimizers.budget import study_iterations

        return study_iterations(algorithm, self.budget_evals, self.iterations, self.agents, dim,
                                self.params.get(algorithm))


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
    if isinstance(obj.get("racing"), Mapping):  # nested models are not built by model_construct
        obj["racing"] = RacingSpec.model_construct(**obj["racing"])
    return cls.model_construct(**obj)


# ---------------------------------------------------------------------------------------- cells
def expand_cells(spec: BenchmarkJobSpec | MapJobSpec) -> list[BenchmarkCell | MapCell]:
    """The job's cells in table order (algorithm-major / planner-major); index = position."""
    if isinstance(spec, BenchmarkJobSpec):
        return [
            BenchmarkCell(
                algorithm=a,
                function=f,
                dim=d,
                agents=spec.agents,
                iterations=spec.iterations_for(a, d),
                shifted=spec.shifted,
                params=dict(spec.params.get(a, {})),
                transform=spec.transform,
                backend=spec.backend,
                max_evaluations=spec.evaluations(d),
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
            optimum_budget=spec.optimum_budget,
        )
        for p in spec.planners
        for m in spec.maps
    ]


def first_runs(spec: BenchmarkJobSpec | MapJobSpec) -> int:
    """The runs each cell may have at first: all of them, or a raced job's ``min_runs``."""
    racing = getattr(spec, "racing", None)
    return spec.runs if racing is None else min(racing.min_runs, spec.runs)


def runs_total(spec: BenchmarkJobSpec | MapJobSpec) -> int:
    """Runs the job has at first (a race adds rounds as it goes)."""
    if isinstance(spec, BenchmarkJobSpec):
        return len(spec.algorithms) * len(spec.functions) * len(spec.dims) * first_runs(spec)
    return len(spec.planners) * len(spec.maps) * spec.runs
