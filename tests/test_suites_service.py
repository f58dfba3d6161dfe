"""Suite instances and evaluation budgets through the service: job spec -> cells -> worker ->
store -> REST -> MCAP, against the coordinator's app in-process (no network)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from fastapi.testclient import TestClient
from pydantic import ValidationError

from swarmpath.functions import get_function
from swarmpath.optimizers import minimize
from swarmpath.service.coordinator import CoordinatorSettings, create_app
from swarmpath.service.jobspec import expand_cells, parse_job_spec
from swarmpath.service.protocol import Lease, LeaseRequest, decode_work_reply, encode
from swarmpath.service.worker import execute_lease, pack_batches

SPEC = {
    "kind": "benchmark", "algorithms": ["GWO", "PSO"], "functions": ["bbob:f3", "cec2022:F1"],
    "instances": [1], "dims": [10], "runs": 2, "agents": 6, "seed": 3, "budget_evals": "20xD",
}


def test_a_job_spec_expands_suite_instances_and_budgets_into_cells():
    spec = parse_job_spec({**SPEC, "functions": ["bbob:f1-f2"], "instances": [1, 4]})
    assert spec.functions == ["bbob:f1", "bbob:f1@i4", "bbob:f2", "bbob:f2@i4"]
    cells = expand_cells(spec)
    assert {c.max_evaluations for c in cells} == {200}
    assert {c.iterations for c in cells} == {200 // 6 - 1}  # GWO, PSO: 6 + 6 T <= 200
    from swarmpath.service.cost import benchmark_evaluations

    assert benchmark_evaluations(spec) == 2 * 4 * 2 * 200  # algorithms x cells x runs x budget


def test_a_job_may_ask_for_numba_on_compiled_suites_and_is_refused_naming_another():
    bbob = {**SPEC, "functions": ["bbob:f3", "bbob:f21"], "instances": [1, 2],
            "budget_evals": None, "backend": "numba"}
    assert parse_job_spec(bbob).backend == "numba"
    both = {**bbob, "functions": ["bbob:f3", "cec2022:F1"], "instances": [1]}
    assert parse_job_spec(both).backend == "numba"
    assert parse_job_spec({**both, "functions": ["cec2017:F2", "cec2022:F1"]}).backend == "numba"
    with pytest.raises(ValidationError, match="cec2017:F1@centre"):  # a centred copy: none
        parse_job_spec({**both, "functions": ["cec2022:F1", "cec2017:F1@centre"]})
    centred = parse_job_spec({**SPEC, "functions": ["bbob:f3@centre", "F1"],
                              "instances": [1, 2]})
    assert centred.functions == ["bbob:f3@centre", "bbob:f3@i2@centre", "F1"]  # still centred


@pytest.mark.parametrize(("change", "field", "says"), [
    ({"instances": [2]}, "functions", "cec2022 has instances 1"),
    ({"functions": ["F1"], "instances": [2]}, "functions", "only suite functions"),
    ({"functions": ["bbob:f3@i7"], "instances": [1]}, "functions", "names its instance already"),
    ({"instances": [0]}, "instances", "greater than or equal to 1"),
    ({"dims": [30]}, "dims", "defined for dim in 10, 20"),
    ({"transform": "rotate"}, "transform", "transform must be 'none'"),
    ({"budget_evals": "3"}, "budget_evals", "less than GWO's 12"),
    ({"budget_evals": "ten"}, "budget_evals", "NxD"),
    ({"functions": ["cec2017:F1@centre"], "backend": "numba"}, "backend", "no numba kernel"),
])
def test_bad_suite_fields_are_named(change, field, says):
    with pytest.raises(ValidationError) as err:
        parse_job_spec({**SPEC, **change})
    errors = err.value.errors()
    assert any(field in map(str, e["loc"]) and says in e["msg"] for e in errors), errors


@pytest.fixture
def core(tmp_path, monkeypatch):
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    app = create_app(CoordinatorSettings(data_dir=tmp_path / "data"), use_zenoh=False)
    with TestClient(app) as http:
        app.state.core.publish = lambda key, payload: None
        yield http, app.state.core


def test_a_suite_job_runs_on_a_worker_like_minimize(core):
    http, service = core
    job = http.post("/jobs", json=SPEC).json()["id"]
    service.worker_alive("w1")
    while isinstance(lease := decode_work_reply(service.handle_lease_request(
            encode(LeaseRequest(worker="w1", max_runs=100)))), Lease):
        for payload in pack_batches("w1", [d for _r, d in execute_lease(lease)]):
            service.handle_results(f"swarmpath/results/{lease.job_id}", payload)
    assert http.get(f"/jobs/{job}").json()["state"] == "done"
    runs = [json.loads(line) for line in http.get(
        f"/jobs/{job}/runs", params={"format": "jsonl"}).text.splitlines() if line]
    assert {r["function"] for r in runs} == {"bbob:f3", "cec2022:F1"}
    for r in runs:
        cell = next(c for c in expand_cells(parse_job_spec(SPEC))
                    if (c.algorithm, c.function) == (r["algorithm"], r["function"]))
        res = minimize(r["algorithm"], r["function"], dim=10, agents=6,
                       iterations=cell.iterations, seed=3, run_ids=[r["run"]],
                       max_evaluations=200)
        assert r["best_fitness"] == float(res.best_fitness[0])
        assert r["evaluations"] <= 200
        fn = get_function(r["function"])
        assert np.isclose(fn.value(np.array(r["best_position"])) - fn.f_opt(10),
                          r["best_fitness"], rtol=1e-12, atol=1e-12)
    mcap = http.get(f"/jobs/{job}/mcap")
    assert mcap.status_code == 200 and b"cec2022:F1" in mcap.content
