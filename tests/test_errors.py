"""Bad input, told plainly: REST 422 items (one per problem, loc down to the field, no pydantic
wording, "did you mean"), and the CLI printing one line per problem naming the field once."""

from __future__ import annotations

import json

import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

import swarmpath.cli.service as service_cli
from swarmpath.cli import app as cli_app
from swarmpath.names import closest, did_you_mean
from swarmpath.service.client import ServiceClient, error_field
from swarmpath.service.coordinator import CoordinatorSettings, create_app

PYDANTIC_WORDS = ("Input should", "Value error", "valid tuple", "Extra inputs")
SCENARIO = {
    "name": "box", "size": [10, 10], "strt": [0, 0], "goal": [9, 9],
    "obstacles": [{"shape": "circle", "center": [2, 2], "radius": 1},
                  {"shape": "circle", "center": [5, 5], "radius": "a"},
                  {"shape": "circle", "center": [7, 7], "radius": -1}],
}


@pytest.fixture
def http(tmp_path, monkeypatch):
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    app = create_app(CoordinatorSettings(data_dir=tmp_path / "d"), use_zenoh=False)
    with TestClient(app) as c:
        yield c


def details(http, body):
    r = http.post("/jobs", json=body)
    assert r.status_code == 422
    items = r.json()["detail"]
    for d in items:
        assert "\n" not in d["msg"] and not any(w in d["msg"] for w in PYDANTIC_WORDS), d
    return {error_field(d["loc"]): d["msg"] for d in items}


def test_inline_scenario_errors_reach_the_field(http):
    got = details(http, {"kind": "map", "planners": ["MFB"], "maps": ["mfb-static", SCENARIO]})
    assert got == {
        "maps.1.start": "required",
        "maps.1.strt": "unknown field (did you mean 'start'?)",
        "maps.1.obstacles.1.radius": "must be a number",
        "maps.1.obstacles.2.radius": "must be > 0",
    }
    r = http.post("/jobs", json={"kind": "map", "planners": ["MFB"], "maps": [SCENARIO]})
    locs = [d["loc"] for d in r.json()["detail"]]
    assert ["body", "maps", 0, "obstacles", 2, "radius"] in locs


def test_unknown_names_suggest_the_near_miss(http):
    got = details(http, {"kind": "benchmark", "algorithms": ["GWO", "gw0"],
                         "functions": ["F1", "F99"], "dims": ["x", 5000], "seeed": 2})
    assert got["algorithms.1"].startswith("unknown algorithm 'gw0' (did you mean 'GWO'?); valid:")
    assert got["functions.1"].startswith("unknown function 'F99' (did you mean 'F9'?)")
    assert got["dims.0"] == "must be an integer" and got["dims.1"] == "must be <= 1000"
    assert got["seeed"] == "unknown field (did you mean 'seed'?)"
    got = details(http, {"kind": "benchmark", "algorithms": ["GWO"], "functions": ["F1"],
                         "params": {"GWO": {"a_mx": 2, "a_max": "x"}, "GW": {}}})
    assert got["params.GWO.a_mx"].startswith("GWO has no parameter 'a_mx' (did you mean "
                                             "'a_max'?)")
    assert "a_max" in got["params.GWO.a_max"]
    assert got["params.GW"].startswith("not one of the job's algorithms (did you mean 'GWO'?)")
    got = details(http, {"kind": "map", "planners": ["MFBB"], "maps": ["mfb-statc", 3]})
    assert got["planners.0"].startswith("unknown planner 'MFBB' (did you mean 'MFB'?)")
    assert got["maps.1"] == "must be a string or an object"
    assert details(http, {"kind": "nope"}) == {"kind": "must be one of 'benchmark', 'map', "
                                                       "got 'nope'"}


def test_cli_prints_one_line_per_problem_naming_the_field_once(http, tmp_path, monkeypatch):
    monkeypatch.setattr(service_cli, "_client",
                        lambda url: ServiceClient("http://testserver", transport=http._transport))
    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps({"kind": "benchmark", "algorithms": ["GWO"], "functions": ["F1"],
                                "dims": [2, "x"], "agents": 0}))
    result = CliRunner().invoke(cli_app, ["submit", str(spec)])
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert lines == ["swarmpath submit: error: dims.1: must be an integer",
                     "swarmpath submit: error: agents: must be >= 1"]


def test_cli_scenario_file_problems_one_per_line(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(SCENARIO))
    result = CliRunner().invoke(cli_app, ["plan", "-p", "MFB", "-m", str(bad), "-j", "1"])
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 4 and all(line.startswith("swarmpath plan: error: --maps: ")
                                   for line in lines)
    assert any("obstacles[2].radius: must be > 0" in line for line in lines)
    assert any("strt: unknown field (did you mean 'start'?)" in line for line in lines)


def test_cli_names_suggest_the_near_miss():
    result = CliRunner().invoke(cli_app, ["bench", "-a", "GW0", "-f", "F1", "-d", "2"])
    assert result.exit_code == 2 and "did you mean 'GWO'?" in result.stderr


def test_closest_name():
    assert closest("icot", ["COOT", "ICOOT", "GWO"]) == "ICOOT"
    assert closest("gwo", ["GWO"]) == "GWO"
    assert closest("zzz", ["GWO", "PSO"]) is None and did_you_mean("zzz", ["GWO"]) == ""


def test_a_missing_scenario_name_is_one_problem_said_once(http):
    """The name check and the scenario reader both see a missing name: one item, one message
    (not "... '-' or required", two problems glued on one line)."""
    r = http.post("/jobs", json={"kind": "map", "planners": ["MFB"], "maps": [
        {"size": [10, 10], "start": [1, 1], "goal": [9, 9]}]})
    assert r.status_code == 422
    items = [d for d in r.json()["detail"] if error_field(d["loc"]) == "maps.0.name"]
    assert len(items) == 1
    assert items[0]["msg"] == "an inline scenario needs a 'name' of letters, digits, '_', '.', '-'"


def test_near_miss_values_of_a_fixed_set_are_suggested(http):
    scenario = {"name": "box", "size": [10, 10], "start": [0, 0], "goal": [9, 9],
                "robot": {"preset": "turtlebot3-burgr"},
                "obstacles": [{"shape": "circel", "center": [2, 2], "radius": 1}]}
    got = details(http, {"kind": "map", "planners": ["MFB"], "maps": [scenario]})
    assert got["maps.0.robot.preset"].endswith("(did you mean 'turtlebot3-burger'?)")
    assert got["maps.0.obstacles.0.shape"].endswith("(did you mean 'circle'?)")
    assert details(http, {"kind": "mapp"}) == {
        "kind": "must be one of 'benchmark', 'map', got 'mapp' (did you mean 'map'?)"}
    assert details(http, {"kind": "benchmark", "algorithms": ["GWO"], "functions": ["F1"],
                          "transform": "shfit"})["transform"].endswith("(did you mean 'shift'?)")
