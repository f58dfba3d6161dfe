"""The REST API never answers 500 on bad input: bounded paging, strict types, overflowing numbers,
bodies that do not parse, a job cost guard, every error documented, Allow headers, enums from the
registries in the OpenAPI document."""

from __future__ import annotations

import re

import pytest
from fastapi.testclient import TestClient

from swarmpath.functions import list_names
from swarmpath.optimizers import list_optimizers
from swarmpath.planners import list_planners
from swarmpath.service.coordinator import CoordinatorSettings, create_app
from swarmpath.world.presets import list_maps

SPEC = {"kind": "benchmark", "algorithms": ["GWO"], "functions": ["F1"], "dims": [2], "runs": 2,
        "agents": 5, "iterations": 5, "seed": 1}


@pytest.fixture
def client(tmp_path, monkeypatch):
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    settings = CoordinatorSettings(data_dir=tmp_path / "data", max_job_evaluations=1e6,
                                   max_job_steps=1e5)
    with TestClient(create_app(settings, use_zenoh=False)) as c:
        yield c


def problem(r) -> tuple[str, str]:
    assert r.status_code == 422, r.text
    (item,) = r.json()["detail"]
    return ".".join(str(p) for p in item["loc"]), item["msg"]


def _paged_paths() -> list[str]:
    """Every GET route of the app that takes offset/limit (path parameters filled with 'x')."""
    doc = create_app(CoordinatorSettings(), use_zenoh=False).openapi()
    paths = []
    for path, ops in doc["paths"].items():
        params = {p["name"] for p in ops.get("get", {}).get("parameters", [])}
        if {"offset", "limit"} <= params:
            paths.append(re.sub(r"\{[^}]+\}", "x", path))
    return sorted(paths)


def test_the_paged_routes_are_found():
    assert {"/jobs", "/jobs/x/runs", "/maps"} <= set(_paged_paths())


@pytest.mark.parametrize("path", _paged_paths())
@pytest.mark.parametrize(("name", "value"), [("offset", 2**63), ("offset", -1), ("limit", 0),
                                             ("limit", 10**6), ("offset", "1e3")])
def test_paging_is_bounded(client, path, name, value):
    assert problem(client.get(path, params={name: value}))[0] == f"query.{name}"


def test_run_ids_are_bounded(client):
    job = client.post("/jobs", json=SPEC).json()["id"]
    assert problem(client.get(f"/jobs/{job}/runs/{2**64}"))[0] == "path.run_id"
    assert client.get(f"/jobs/{job}/runs/999999").status_code == 404


@pytest.mark.parametrize(("field", "value"), [("iterations", True), ("runs", 2.0),
                                              ("agents", "5"), ("seed", False),
                                              ("shifted", 1), ("dims", [True])])
def test_no_silent_coercion(client, field, value):
    loc, _msg = problem(client.post("/jobs", json={**SPEC, field: value}))
    assert loc.startswith(f"body.{field}")


@pytest.mark.parametrize("literal", ["1" + "0" * 400, "-1" + "0" * 30, "1e400"])
def test_overflowing_parameters_get_our_own_message(client, literal):
    head = ('{"kind": "benchmark", "algorithms": ["GWO"], "functions": ["F1"], "dims": [2], '
            '"runs": 2, "agents": 5, "iterations": 5, "params": {"GWO": {"a_max": ')
    body = head + literal + "}}}"
    loc, msg = problem(client.post("/jobs", content=body.encode(),
                                   headers={"content-type": "application/json"}))
    assert loc == "body.params.GWO.a_max"
    assert "out of range" in msg or "finite" in msg
    assert "ufunc" not in msg and "numpy" not in msg


def test_map_parameters_overflowing_are_422_not_500(client):
    spec = {"kind": "map", "planners": [list_planners()[0]], "maps": [list_maps()[0]], "runs": 1,
            "params": {list_planners()[0]: {"anything": [1, {"x": 10**400}]}}}
    loc, _msg = problem(client.post("/jobs", json=spec))
    assert loc.startswith("body.params.")


@pytest.mark.parametrize(("body", "words"), [
    (b"[" * 100_000 + b"]" * 100_000, "nests too deeply"),
    (b'{"runs": ' + b"1" * 5000 + b"}", "too many digits"),
    (b'{"kind": "benchmark\xff"}', "UTF-8"),
    (b"\xff\xfe{}", "JSON"),  # a UTF-16 byte order mark: decoded, then not JSON
    (b"{", "JSON"),
])
def test_unparseable_bodies_are_422_naming_the_problem(client, body, words):
    r = client.post("/jobs", content=body, headers={"content-type": "application/json"})
    assert r.status_code == 422, r.text
    assert any(words in item["msg"] or words.lower() in item["msg"].lower()
               for item in r.json()["detail"]), r.text


def test_cost_guard_names_the_estimate_and_the_knob(client):
    r = client.post("/jobs", json={**SPEC, "runs": 100, "agents": 100, "iterations": 1000})
    loc, msg = problem(r)
    item = r.json()["detail"][0]
    assert item["estimate"] == 100 * 100 * 1000 and item["limit"] == 1e6
    assert "SWARMPATH_MAX_JOB_EVALUATIONS" in msg and "1e+07" in msg
    assert client.post("/jobs", json=SPEC).status_code == 201
    big_map = {"kind": "map", "planners": list_planners()[:2], "maps": [list_maps()[0]],
               "runs": 1000}
    loc, msg = problem(client.post("/jobs", json=big_map))
    assert loc == "body.runs" and "SWARMPATH_MAX_JOB_STEPS" in msg


def test_allow_lists_every_method_of_a_path(client):
    r = client.options("/jobs/abc")
    assert r.status_code == 204
    assert r.headers["allow"] == "DELETE, GET, HEAD, OPTIONS"
    r = client.put("/jobs/abc")
    assert r.status_code == 405 and r.headers["allow"] == "DELETE, GET, HEAD, OPTIONS"
    assert client.options("/jobs").headers["allow"] == "GET, HEAD, OPTIONS, POST"


def test_openapi_documents_errors_and_enumerates_names(client):
    doc = client.get("/openapi.json").json()
    paths = doc["paths"]
    for path, ops in paths.items():
        for method, op in ops.items():
            codes = set(op["responses"])
            assert "422" in codes, (method, path)
            if "{" in path:
                assert "404" in codes, (method, path)
    assert {"401", "422"} <= set(paths["/jobs"]["post"]["responses"])
    assert "401" in paths["/jobs/{job_id}"]["delete"]["responses"]
    schemas = doc["components"]["schemas"]
    bench, maps = schemas["BenchmarkJobSpec"]["properties"], schemas["MapJobSpec"]["properties"]
    assert bench["algorithms"]["items"]["enum"] == list(list_optimizers())
    assert bench["functions"]["items"]["enum"] == list_names()
    assert {"F1", "bbob:f24", "cec2017:F30", "cec2022:F12", "bbob"} <= set(list_names())
    assert maps["planners"]["items"]["enum"] == list(list_planners())
    preset = [b for b in maps["maps"]["items"]["anyOf"] if b.get("type") == "string"]
    assert preset[0]["enum"] == list(list_maps())


def test_the_201_answers_are_typed_in_openapi(client):
    """A client generated from /openapi.json knows the new job's id (the 201 of POST /jobs was
    untyped, issue 25) and an uploaded map's; the answers have what the schemas say."""
    spec = client.get("/openapi.json").json()
    schemas = spec["components"]["schemas"]
    for path, model, required in (("/jobs", "JobCreated", {"id", "state", "runs_total"}),
                                  ("/maps", "MapInfo", {"id", "name", "size", "start", "goal"})):
        created = spec["paths"][path]["post"]["responses"]["201"]["content"]
        assert created["application/json"]["schema"] == {"$ref": f"#/components/schemas/{model}"}
        assert required <= set(schemas[model]["required"])
    assert schemas["JobCreated"]["properties"]["id"]["type"] == "string"
    r = client.post("/jobs", json={"kind": "benchmark", "algorithms": ["GWO"], "functions": ["F1"],
                                   "dims": [2], "runs": 2, "agents": 6, "iterations": 3})
    assert r.status_code == 201 and set(r.json()) == {"id", "state", "runs_total"}
    listed = spec["paths"]["/maps"]["get"]["responses"]["200"]["content"]["application/json"]
    assert listed["schema"]["items"] == {"$ref": "#/components/schemas/MapInfo"}
