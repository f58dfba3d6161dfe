"""Protocol models: valid specs, limit errors naming their field, wire round trips, schemas."""

from __future__ import annotations

import json
import math
import sys

import pytest
from pydantic import ValidationError

from swarmpath.optimizers import list_optimizers
from swarmpath.service import protocol as p
from swarmpath.service import schemas

BASE = {
    "kind": "benchmark",
    "algorithms": ["GWO", "PSO"],
    "functions": ["F1", "F9"],
    "dims": [30],
    "runs": 30,
    "agents": 30,
    "iterations": 500,
    "seed": 1,
    "shifted": False,
    "params": {"GWO": {}},
}


def spec(**changes):
    out = dict(BASE)
    out.update(changes)
    return out


def locs(exc: ValidationError) -> list[tuple]:
    return [tuple(e["loc"]) for e in exc.errors()]


def fails_on(data, field: str) -> ValidationError:
    with pytest.raises(ValidationError) as info:
        p.parse_job_spec(data)
    found = locs(info.value)
    assert any(field in loc for loc in found), f"{field} not named in {found}"
    return info.value


# ---------------------------------------------------------------------------------- valid specs
def test_issue_example_benchmark_spec():
    algorithms = ["GWO", "ICOOT"] if "ICOOT" in list_optimizers() else ["GWO", "PSO"]
    s = p.parse_job_spec(spec(algorithms=algorithms, params={algorithms[1]: {}}))
    assert isinstance(s, p.BenchmarkJobSpec)
    assert p.runs_total(s) == 2 * 2 * 1 * 30
    cells = p.expand_cells(s)
    assert [c.key for c in cells] == [
        f"{a}/{f}/30" for a in algorithms for f in ("F1", "F9")
    ]
    assert all(c.agents == 30 and c.iterations == 500 for c in cells)


def test_defaults_and_json_text():
    s = p.parse_job_spec(json.dumps({"kind": "benchmark", "algorithms": ["GWO"],
                                     "functions": ["F1"]}))
    assert (s.dims, s.runs, s.agents, s.iterations, s.seed, s.shifted) == (
        [30], 30, 30, 500, 1, False
    )


def test_function_ranges_are_expanded():
    s = p.parse_job_spec(spec(functions=["F1-F4", "F9,F10"]))
    assert s.functions == ["F1", "F2", "F3", "F4", "F9", "F10"]
    s = p.parse_job_spec(spec(functions=["F1-F13"]))
    assert len(s.functions) == 13


def test_params_are_checked_by_the_optimizer_and_kept_per_cell():
    s = p.parse_job_spec(spec(params={"GWO": {"a_max": 1.5}}))
    cells = p.expand_cells(s)
    assert cells[0].params == {"a_max": 1.5}
    assert cells[-1].params == {}  # PSO


def test_limits_at_the_boundary_are_accepted():
    s = p.parse_job_spec(spec(algorithms=["GWO"], functions=["F1"], dims=[1000], agents=1000,
                              iterations=100_000, runs=10_000, params={}))
    assert p.runs_total(s) == 10_000
    # exactly one million runs
    s = p.parse_job_spec(spec(algorithms=["GWO", "PSO"], functions=["F1-F10"],
                              dims=[2, 3, 4, 5, 6], runs=10_000, params={}))
    assert p.runs_total(s) == 1_000_000


# ------------------------------------------------------------------------- errors name the field
@pytest.mark.parametrize(
    ("changes", "field"),
    [
        ({"dims": [1001]}, "dims"),
        ({"dims": [0]}, "dims"),
        ({"dims": []}, "dims"),
        ({"agents": 1001}, "agents"),
        ({"agents": 0}, "agents"),
        ({"iterations": 100_001}, "iterations"),
        ({"iterations": 0}, "iterations"),
        ({"runs": 10_001}, "runs"),
        ({"runs": 0}, "runs"),
        ({"seed": -1}, "seed"),
        ({"algorithms": ["NOPE"]}, "algorithms"),
        ({"algorithms": []}, "algorithms"),
        ({"algorithms": ["GWO", "GWO"], "params": {}}, "algorithms"),
        ({"functions": ["F99"]}, "functions"),
        ({"functions": ["F1", "F1"]}, "functions"),
        ({"dims": [30, 30]}, "dims"),
        ({"params": {"GWO": {"bogus": 1}}}, "params"),
        ({"params": {"GWO": {"a_max": "high"}}}, "params"),
        ({"params": {"SSA": {}}}, "params"),
        ({"shifted": "maybe"}, "shifted"),
        ({"unknown_field": 1}, "unknown_field"),
    ],
)
def test_each_limit_error_names_its_field(changes, field):
    fails_on(spec(**changes), field)


def test_more_than_a_million_runs_names_runs():
    err = fails_on(spec(algorithms=["GWO", "PSO"], functions=["F1-F13"], dims=[10, 20, 30, 40],
                        runs=10_000, params={}), "runs")
    assert "1000000" in str(err)


def test_messages_are_clear():
    err = fails_on(spec(algorithms=["NOPE"]), "algorithms")
    assert "unknown algorithm 'NOPE'" in str(err) and "GWO" in str(err)
    err = fails_on(spec(params={"GWO": {"bogus": 1}}), "params")
    assert "bogus" in str(err) and "a_max" in str(err)
    err = fails_on(spec(functions=["F99"]), "functions")
    assert "F99" in str(err)


def test_agents_below_an_algorithms_minimum():
    err = fails_on(spec(algorithms=["SSA"], agents=1, params={}), "agents")
    assert "SSA" in str(err)


def test_unknown_kind_is_rejected():
    with pytest.raises(ValidationError):
        p.parse_job_spec({"kind": "poetry"})


# -------------------------------------------------------------------------------------- map jobs


def test_unknown_map_name_names_maps():
    err = fails_on({"kind": "map", "planners": ["ICOOT"], "maps": ["no-such-map"]}, "maps")
    assert "no-such-map" in str(err)


def test_inline_scenario_needs_a_name():
    fails_on({"kind": "map", "planners": ["ICOOT"], "maps": [{"size": [10, 10]}]}, "maps")


def test_inline_scenario_is_validated_by_the_world_layer():
    bad = {"name": "bad", "size": [10, 10], "start": [0, 0], "goal": [10, 10],
           "obstacles": [{"shape": "circle", "center": [2, 2], "radius": -1}]}
    err = fails_on({"kind": "map", "planners": ["ICOOT"], "maps": [bad]}, "maps")
    assert "bad" in str(err)


def test_valid_map_spec():
    from swarmpath.planners import list_planners
    from swarmpath.world.presets import list_maps

    planner, map_name = list_planners()[0], list_maps()[0]
    s = p.parse_job_spec({"kind": "map", "planners": [planner], "maps": [map_name], "runs": 3})
    assert p.runs_total(s) == 3
    assert p.expand_cells(s)[0].key == f"{planner}/{map_name}"


@pytest.fixture
def fake_registries(monkeypatch):
    """Stand-in planner and preset registries, so the map path is tested whatever their state."""
    import types

    class FakePlanner:
        @classmethod
        def resolve_params(cls, params):
            for key in params:
                if key != "w1":
                    raise ValueError(f"FAKE has no parameter {key!r}; valid: w1")
            return dict(params)

    def get_planner(name):  # as the registry: an unknown name is a ValueError naming it
        if name not in ("ICOOT", "MFB"):
            raise ValueError(f"unknown planner {name!r}")
        return FakePlanner

    planners = types.ModuleType("swarmpath.planners")
    planners.list_planners = lambda: ["ICOOT", "MFB"]
    planners.get_planner = get_planner
    presets = types.ModuleType("swarmpath.world.presets")
    presets.list_maps = lambda: ["mfb-static", "mfb-dynamic"]
    monkeypatch.setitem(sys.modules, "swarmpath.planners", planners)
    monkeypatch.setitem(sys.modules, "swarmpath.world.presets", presets)


MAP = {"kind": "map", "planners": ["ICOOT", "MFB"], "maps": ["mfb-static"], "runs": 10,
       "seed": 1, "params": {}}


INLINE = {"name": "mine", "size": [10, 10], "start": [0, 0], "goal": [10, 10],
          "robot": {"model": "omni", "radius": 0.5}, "obstacles": []}


def test_map_spec_with_registries(fake_registries):
    inline = INLINE
    s = p.parse_job_spec({**MAP, "maps": ["mfb-static", inline], "params": {"ICOOT": {"w1": 2}}})
    assert isinstance(s, p.MapJobSpec) and p.runs_total(s) == 40
    cells = p.expand_cells(s)
    assert [c.key for c in cells] == ["ICOOT/mfb-static", "ICOOT/mine", "MFB/mfb-static",
                                      "MFB/mine"]
    assert cells[1].scenario == inline and cells[0].params == {"w1": 2}


@pytest.mark.parametrize(
    ("changes", "field", "text"),
    [
        ({"planners": ["NOPE"]}, "planners", "unknown planner 'NOPE'"),
        ({"planners": ["MFB", "MFB"]}, "planners", "duplicate"),
        ({"maps": ["atlantis"]}, "maps", "unknown map 'atlantis'"),
        ({"maps": ["mfb-static", {**INLINE, "name": "mfb-static"}]}, "maps", "duplicate"),
        ({"runs": 10_001}, "runs", "less than or equal"),
        ({"params": {"ICOOT": {"zz": 1}}}, "params", "zz"),
        ({"params": {"PSO": {}}}, "params", "not one of the job's planners"),
    ],
)
def test_map_spec_errors_name_the_field(fake_registries, changes, field, text):
    err = fails_on({**MAP, **changes}, field)
    assert text in str(err)


def test_map_cells_from_a_constructed_spec():
    s = p.MapJobSpec.model_construct(
        kind="map", planners=["A", "B"], maps=["m1", {"name": "inline", "size": [5, 5]}],
        runs=2, seed=1, params={"A": {"k": 1}},
    )
    cells = p.expand_cells(s)
    assert [c.key for c in cells] == ["A/m1", "A/inline", "B/m1", "B/inline"]
    assert cells[1].scenario == {"name": "inline", "size": [5, 5]} and cells[0].scenario is None
    assert cells[0].params == {"k": 1} and cells[2].params == {}
    assert p.runs_total(s) == 8


# -------------------------------------------------------------------------------------- messages
def make_lease() -> p.Lease:
    cell = p.expand_cells(p.parse_job_spec(spec()))[1]
    return p.Lease(
        lease_id="abc123", worker="w-1", job_id="job1", cell=cell.key, cell_index=1,
        runs_per_cell=30, seed=1, runs=[4, 5, 6], spec=cell, deadline=1e9, lease_seconds=60,
        heartbeat_seconds=20, capability="5e" * 32,
    )


def test_lease_round_trip_and_run_requests():
    lease = make_lease()
    back = p.decode_work_reply(p.encode(lease))
    assert back == lease
    assert back.run_ids() == [34, 35, 36]
    reqs = back.requests()
    assert [r.run for r in reqs] == [4, 5, 6] and reqs[0].spec.function == "F9"
    assert isinstance(p.decode_work_reply(p.encode(p.NoWork())), p.NoWork)


def test_run_result_keeps_non_finite_numbers():
    r = p.RunResult(lease_id="abc", job_id="j", cell="GWO/F1/30", run=0, worker="w",
                    seconds=0.1, metrics={"best_fitness": math.inf, "evaluations": 10,
                                          "flag": True},
                    curve=[math.inf, 1.0])
    back = p.decode(p.RunResult, p.encode(r))
    assert back.metrics["best_fitness"] == math.inf and back.curve[0] == math.inf
    assert back.metrics["evaluations"] == 10 and back.metrics["flag"] is True


def test_a_result_proof_survives_the_wire_and_binds_every_field():
    """The worker signs the result it built; the coordinator checks the one it parsed: the JSON
    round trip (non-finite floats, ints vs floats, tuples) must not change the signed text."""
    from swarmpath.service.capability import new_capability, result_ok, result_proof

    cap = new_capability()
    r = p.RunResult(lease_id="abc", job_id="j", cell="GWO/F1/30", run=3, worker="w",
                    seconds=0.1, metrics={"best_fitness": -0.0, "evaluations": 10, "ok": True,
                                          "gap": None, "x": 1e-300},
                    curve=[math.inf, 1.0, 0.1 + 0.2, math.nan], best_position=[1.0, -2.5],
                    path=[(0.0, 1.0, 2.0)])
    signed = r.model_copy(update={"proof": result_proof(cap, r)})
    back = p.decode(p.RunResult, p.encode(signed))
    assert result_ok(cap, back) and not result_ok(new_capability(), back)
    assert not result_ok("", back) and not result_ok(cap, r)  # no proof, no secret: never
    for change in ({"run": 4}, {"worker": "v"}, {"seconds": 0.2}, {"status": "failed"},
                   {"curve": [1.0]}, {"metrics": {"best_fitness": -1.0}}):
        assert not result_ok(cap, back.model_copy(update=change)), change


def test_garbage_and_oversized_payloads_are_rejected():
    with pytest.raises(ValidationError):
        p.decode(p.ResultBatch, b"not json")
    with pytest.raises(ValidationError):
        p.decode(p.ResultBatch, b'{"worker": "w", "results": []}')
    with pytest.raises(ValidationError):
        p.decode(p.Ack, b'{"worker": "w", "extra": 1}')
    with pytest.raises(ValueError, match="exceeds"):
        p.decode(p.ResultBatch, b" " * (p.MAX_BODY_BYTES + 1))


@pytest.mark.parametrize("extensions", [
    {"optimizer:GWO": "0123456789ABCDEF"},  # upper case
    {"optimizer:GWO": "0123456789abcde"},  # 15 digits
    {"optimizer:GWO": "0123456789abcdef0"},  # 17
    {"optimizer:GWO": "0123456789abcdeg"},
    {"optimizer:GWO": "0123456789abcde\n"},
    {"optimizer:GWO": "0123456789abcd\u0660\u0661"},  # Arabic-Indic digits
    {"optimizer:GWO": 12},
    {"GWO": "0123456789abcdef"},  # no kind
    {"o:" + "x" * 159: "0123456789abcdef"},  # key of 161 characters
    {f"optimizer:A{i}": "0123456789abcdef" for i in range(513)},
])
def test_a_lease_requests_advertisement_is_bounded_and_checked(extensions):
    good = {"optimizer:GWO": "0123456789abcdef", "o:" + "x" * 158: "fedcba9876543210"}
    assert p.LeaseRequest(worker="w1", extensions=good).extensions == good
    with pytest.raises(ValidationError, match="extensions"):
        p.LeaseRequest(worker="w1", extensions=extensions)


def test_key_expressions():
    k = p.Keys()
    assert k.work == "swarmpath/work"
    assert k.results("j1") == "swarmpath/results/j1"
    assert k.progress("j1") == "swarmpath/progress/j1"
    assert k.ack("w-1") == "swarmpath/ack/w-1"
    assert k.worker_token("w-1") == "swarmpath/workers/w-1"
    assert k.cancel == "swarmpath/cancel"
    assert k.all_results == "swarmpath/results/*"
    assert p.Keys.last_chunk(k.results("j1")) == "j1"
    assert p.Keys("lab/sp").work == "lab/sp/work"
    for bad in ("a/b", "*", "", "x$y"):
        with pytest.raises(ValueError):
            k.ack(bad)
    with pytest.raises(ValueError):
        p.Keys("bad/")
    with pytest.raises(ValidationError):
        p.LeaseRequest(worker="has/slash")


# ---------------------------------------------------------------------------------- schema files
def test_committed_schema_files_are_current():
    stale = schemas.stale_files()
    assert not stale, (
        f"schemas/ is stale ({', '.join(stale)}): run `python -m swarmpath.service.schemas`"
    )


def test_schema_export_writes_every_model(tmp_path):
    written = schemas.write_schemas(tmp_path)
    assert {w.name for w in written} == {f"{n}.schema.json" for n in schemas.SCHEMA_MODELS}
    assert schemas.stale_files(tmp_path) == []
    (tmp_path / "lease.schema.json").write_text("{}")
    assert schemas.stale_files(tmp_path) == ["lease.schema.json"]
    lease = json.loads(schemas.render("lease"))
    assert lease["$schema"].startswith("https://json-schema.org/")
    assert lease["additionalProperties"] is False
    assert "lease_id" in lease["required"] and "kind" in lease["required"]
    job = json.loads(schemas.render("job_spec"))
    assert job["discriminator"]["propertyName"] == "kind"
    assert job["$defs"]["BenchmarkJobSpec"]["properties"]["dims"]["items"]["maximum"] == 1000


# ------------------------------------------------------------------------------------ transforms
@pytest.mark.parametrize("transform", ["none", "shift", "rotate", "shift+rotate"])
def test_transform_reaches_every_cell(transform):
    s = p.parse_job_spec(spec(transform=transform))
    assert s.transform == transform and s.shifted == ("shift" in transform)
    assert {c.transform for c in p.expand_cells(s)} == {transform}


def test_backend_reaches_every_cell_and_what_has_no_kernel_names_the_field():
    s = p.parse_job_spec(spec(backend="numba", algorithms=["GWO", "PSO"]))
    assert {c.backend for c in p.expand_cells(s)} == {"numba"}
    assert {c.backend for c in p.expand_cells(p.parse_job_spec(spec()))} == {"auto"}
    fails_on(spec(backend="gpu"), "backend")
    fails_on(spec(backend="numba", transform="shift+rotate"), "backend")


def test_shifted_is_the_alias_of_transform_shift_and_contradictions_name_the_field():
    s = p.parse_job_spec(spec(shifted=True))
    assert s.transform == "shift" and all(c.transform == "shift" for c in p.expand_cells(s))
    assert p.parse_job_spec(spec(shifted=True, transform="shift+rotate")).transform == (
        "shift+rotate"
    )
    fails_on(spec(shifted=True, transform="rotate"), "transform")
    fails_on(spec(transform="spin"), "transform")
