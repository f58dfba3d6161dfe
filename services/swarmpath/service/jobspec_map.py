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
    model_validator,
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

#: Pairs one ``{"map": id, "scen": ...}`` entry may expand into.
MAX_SCEN_PAIRS_PER_MAP = 500
#: The highest MovingAI bucket a job names (as :data:`swarmpath.world.movingai_scen.MAX_BUCKET`).
MAX_BUCKET = 100_000


class ScenChoice(Model):
    """Pairs of the ``.scen`` uploaded with a MovingAI map: by row (0 = the file's first pair)
    or by bucket (the first ``per_bucket`` pairs of each bucket, in file order)."""

    rows: list[Annotated[int, Field(ge=0, le=10**9, strict=True)]] | None = Field(
        default=None, min_length=1, max_length=MAX_SCEN_PAIRS_PER_MAP,
        description="rows of the .scen (0 = first)")
    buckets: list[Annotated[int, Field(ge=0, le=MAX_BUCKET, strict=True)]] | None = Field(
        default=None, min_length=1, max_length=MAX_SCEN_PAIRS_PER_MAP,
        description="MovingAI buckets (bucket b: octile lengths in [4b, 4b + 4))")
    per_bucket: int = Field(default=1, ge=1, le=MAX_SCEN_PAIRS_PER_MAP, strict=True,
                            description="pairs taken from each bucket")

    @model_validator(mode="after")
    def _one_way(self) -> ScenChoice:
        if (self.rows is None) == (self.buckets is None):
            raise FieldProblems([(("rows",), "give either rows or buckets")])
        for field in ("rows", "buckets"):
            try:
                _unique(getattr(self, field) or [], field[:-1])
            except ValueError as exc:
                raise FieldProblems([((field,), str(exc))]) from None
        if self.rows is not None:
            if "per_bucket" in self.model_fields_set:
                raise FieldProblems([(("per_bucket",), "applies to buckets, not rows")])
        else:
            assert self.buckets is not None
            if len(self.buckets) * self.per_bucket > MAX_SCEN_PAIRS_PER_MAP:
                raise FieldProblems([(("per_bucket",), f"{len(self.buckets)} buckets x "
                                      f"{self.per_bucket} pairs is over "
                                      f"{MAX_SCEN_PAIRS_PER_MAP} pairs")])
        return self


class MapRef(Model):
    """A map uploaded with ``POST /maps``, by id, with optional start and goal (metres from the
    map's lower-left corner), or with ``scen``: pairs of the ``.scen`` uploaded with it, one map
    per pair. The coordinator replaces it with the stored scenario (one per pair) when the job
    is submitted, so the job carries its maps (:func:`swarmpath.service.maps.resolve_refs`)."""

    map: str = Field(pattern=ID_PATTERN, description="id from POST /maps")
    start: tuple[float, float] | None = None
    goal: tuple[float, float] | None = None
    scen: ScenChoice | None = Field(
        default=None, description="MovingAI pairs of the map's uploaded .scen: one map "
        "'NAME#row' per pair (start and goal at the pair's cells)")

    @field_validator("scen")
    @classmethod
    def _pairs_set_the_endpoints(cls, v: ScenChoice | None, info: ValidationInfo
                                 ) -> ScenChoice | None:
        # a field validator, not a model one: the union's member keeps its plain name in locs
        if v is not None:
            for key in ("start", "goal"):
                if info.data.get(key) is not None:
                    raise ValueError(f"a .scen pair sets start and goal; leave {key} out or "
                                     "leave scen out")
        return v


MapEntry = Annotated[str | MapRef | dict[str, Any], Field(union_mode="left_to_right")]


def map_name(entry: str | MapRef | dict[str, Any]) -> str:
    """The name of a map entry: a preset name, an uploaded map's id, or an inline scenario's
    ``name``."""
    if isinstance(entry, str):
        return entry
    if isinstance(entry, MapRef):
        return entry.map
    return str(entry["name"])


def _map_ref_problems(entry: dict[str, Any]) -> list[tuple[Loc, str]]:
    """Why ``entry`` is not a :class:`MapRef`, each problem at its place (``scen.rows.3``):
    the union would otherwise report it as an inline scenario without a name."""
    from pydantic import ValidationError

    try:
        MapRef.model_validate(entry)
    except ValidationError as exc:
        out: list[tuple[Loc, str]] = []
        for e in exc.errors():
            loc = tuple(p for p in e["loc"] if not (isinstance(p, str) and "[" in p))
            problem = (e.get("ctx") or {}).get("error")
            if isinstance(problem, FieldProblems):
                out += [((*loc, *sub), msg) for sub, msg in problem.problems]
            else:
                out.append((loc, str(e["msg"]).removeprefix("Value error, ")))
        return out
    return []


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

    buckets: dict[str, Annotated[int, Field(ge=0, le=MAX_BUCKET, strict=True)]] = Field(
        default_factory=dict, description="{map name: MovingAI bucket}: the summary and the "
        "dashboard report success and gap per bucket (the difficulty curve); set by the "
        "coordinator for {'map': id, 'scen': ...} pairs, or given for presets and inline maps")
    octile: dict[str, Annotated[float, Field(gt=0, allow_inf_nan=False)]] = Field(
        default_factory=dict, description="{map name: the .scen's octile optimal length (m)}")

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
            if "map" in entry and "name" not in entry:  # an uploaded map's entry gone wrong
                problems += [((i, *loc), msg) for loc, msg in _map_ref_problems(entry)]
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

    @model_validator(mode="after")
    def _bucketed_maps_exist(self) -> MapJobSpec:
        names = {map_name(m) for m in self.maps if not isinstance(m, MapRef)}
        problems: list[tuple[Loc, str]] = [
            ((field, name), "not the name of a preset or inline map of this job")
            for field in ("buckets", "octile") for name in getattr(self, field)
            if name not in names]
        if problems:
            raise FieldProblems(problems)
        return self

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
