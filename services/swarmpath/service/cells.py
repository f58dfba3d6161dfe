"""The cells a job expands into: what a worker needs to run one cell, as leased to it.

A benchmark cell is one algorithm on one function and dimension, a map cell one planner on one
map (its scenario inline, or by content hash when large). The job specs that expand into them
are in :mod:`swarmpath.service.jobspec`."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field, TypeAdapter, ValidationInfo, field_validator

from swarmpath.service.model import MAX_OPTIMUM_BUDGET, MAX_SCENARIO_BYTES, Model, ParamValue


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
    backend: str = Field(default="numpy",
                         description="auto, numpy or numba (optimizers.api.BACKENDS)")
    max_evaluations: int | None = Field(
        default=None, ge=1, description="evaluations each run may count (the job's budget_evals "
        "at this dim; iterations then spend it); null: agents x iterations")

    @field_validator("transform")
    @classmethod
    def _known_transform(cls, v: str, info: ValidationInfo) -> str:
        return _transform(v, bool(info.data.get("shifted")))

    @field_validator("backend")
    @classmethod
    def _known_backend(cls, v: str) -> str:
        from swarmpath.optimizers.api import BACKENDS

        if v not in BACKENDS:
            raise ValueError(f"must be one of {', '.join(BACKENDS)}, got {v!r}")
        return v

    @property
    def key(self) -> str:
        return f"{self.algorithm}/{self.function}/{self.dim}"


class ScenarioRef(Model):
    """A scenario by content: the SHA-256 and length of its canonical JSON
    (:func:`swarmpath.service.scenarios.canonical`)."""

    sha256: str = Field(pattern=r"^[0-9a-f]{64}$")
    bytes: int = Field(ge=1, le=MAX_SCENARIO_BYTES)


class MapCell(Model):
    """One planner on one map. ``scenario`` is the inline scenario object, or null for a preset.
    In a lease, a scenario over INLINE_SCENARIO_BYTES is replaced by ``scenario_ref``: the worker
    fetches it from the coordinator and checks the hash before it runs."""

    kind: Literal["map"] = "map"
    planner: str
    map: str
    scenario: dict[str, Any] | None = None
    params: dict[str, Any] = Field(default_factory=dict)
    scenario_ref: ScenarioRef | None = None
    optimum_budget: float | None = Field(
        default=None, gt=0, le=MAX_OPTIMUM_BUDGET, allow_inf_nan=False,
        description="seconds the exact optimum may take before it gives up (null: the "
        "default, swarmpath.world.optimum.DEFAULT_BUDGET)")

    @property
    def key(self) -> str:
        return f"{self.planner}/{self.map}"


CellSpec = Annotated[BenchmarkCell | MapCell, Field(discriminator="kind")]
CELL_ADAPTER: TypeAdapter[BenchmarkCell | MapCell] = TypeAdapter(CellSpec)


def run_key(job_id: str, run_id: int) -> str:
    """A run's name across jobs, as listed in ``WorkerStatus.current_runs``."""
    return f"{job_id}:{run_id}"

