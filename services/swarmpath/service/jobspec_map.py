"""The map job spec: every planner on every map (a preset's name, an inline scenario, or a map
uploaded with ``POST /maps`` by its id). :mod:`.jobspec` holds the benchmark spec and the parsing
of either kind; every name here is importable from there too."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import (
    BeforeValidator,
    Field,
    ValidationInfo,
    field_validator,
)

from swarmpath.service.model import (
    _ID_RE,
    ID_PATTERN,
    MAX_OPTIMUM_BUDGET,
    MAX_RUNS_PER_CELL,
    MAX_SEED,
    Model,
)
from swarmpath.service.spec_checks import (
    FieldProblems,
    Loc,
    _bounded_numbers,
    _check_total,
    _inline_scenario_problems,
    _map_names,
    _params_of_members,
    _planner_registry,
    _reference,
    _unique,
)


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

    optimum_budget: float | None = Field(
        default=None, gt=0, le=MAX_OPTIMUM_BUDGET, allow_inf_nan=False, strict=True,
        description="seconds of wall time the exact optimum of each map may take before it "
        "gives up (the summary's optimum_reason says so, with the budget); null: the default "
        "(30 s, as swarmpath plan --optimum-budget)")

    @field_validator("planners")
    @classmethod
    def _known_planners(cls, v: list[str]) -> list[str]:
        from swarmpath.names import unknown

        registry = _planner_registry()
        known = list(registry.list_planners())
        problems: list[tuple[Loc, str]] = []
        for i, name in enumerate(v):
            if name in known:
                continue
            if name.startswith("swarm:"):  # the family: swarm:<any registered optimizer>
                try:
                    registry.get_planner(name)
                    continue
                except ValueError as exc:
                    problems.append(((i,), str(exc)))
                    continue
            problems.append(((i,), unknown("planner", name, [*known, "swarm:<optimizer>"])))
        if problems:
            raise FieldProblems(problems)
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
