"""The numeric platform fingerprint: stable in a process, bounded when it comes from outside."""

import io
import json

import numpy as np
import pytest
from typer.testing import CliRunner

from swarmpath import provenance
from swarmpath.cli import app


def test_platform_names_numpy_and_a_stable_fingerprint():
    first, second = provenance.numeric_platform(), provenance.numeric_platform()
    assert first == second
    assert first["numpy"] == np.__version__
    assert len(first["fingerprint"]) == provenance.FINGERPRINT_CHARS
    assert first["fingerprint"] == provenance.fingerprint(first)
    assert set(first) <= set(provenance.clean_platform(first))


def test_fingerprint_changes_with_any_field():
    platform = provenance.numeric_platform()
    for key in (k for k in platform if k != "fingerprint"):
        changed = {**platform, key: platform[key] + " X86_V4"}
        assert provenance.fingerprint(changed) != platform["fingerprint"], key


@pytest.mark.parametrize(("value", "named"), [
    ({f"k{i}": "v" for i in range(provenance.MAX_KEYS + 1)}, "at most"),
    ({"simd": "x" * (provenance.MAX_VALUE_CHARS + 1)}, "platform.simd"),
    ({"simd": 3}, "platform.simd"),
    ({"k" * (provenance.MAX_KEY_CHARS + 1): "v"}, "keys are strings"),
    (["numpy"], "must be an object"),
])
def test_hostile_platform_is_refused_by_name(value, named):
    with pytest.raises(ValueError, match=named):
        provenance.clean_platform(value)


def test_bench_json_carries_the_local_platform():
    result = CliRunner().invoke(app, ["bench", "-a", "pso", "-f", "F1", "-d", "2", "--runs", "2",
                                      "--agents", "5", "--iterations", "3", "--json"])
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert doc["platform"] == provenance.numeric_platform()


# ------------------------------------------------------------------------- through the service
@pytest.fixture(params=[False, True], ids=["in-process", "recorder-process"])
def service(request, tmp_path, monkeypatch):
    from fastapi.testclient import TestClient

    from swarmpath.service.coordinator import CoordinatorSettings, create_app

    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    settings = CoordinatorSettings(data_dir=tmp_path / "data", recorder_process=request.param)
    app = create_app(settings, use_zenoh=False)
    with TestClient(app) as client:
        yield client, app.state.core


def test_a_workers_platform_shows_in_get_workers(service):
    from swarmpath.service.protocol import LeaseRequest, encode

    client, core = service
    core.worker_alive("w1")
    core.handle_lease_request(encode(LeaseRequest(worker="w1",
                                                  platform=provenance.numeric_platform())))
    (shown,) = client.get("/workers").json()
    assert shown["id"] == "w1" and shown["platform"] == provenance.numeric_platform()


def test_an_oversize_platform_is_refused_naming_the_field(service):
    from swarmpath.service.protocol import LeaseRequest, NoWork, decode_work_reply

    client, core = service
    core.worker_alive("w1")
    hostile = json.dumps({"worker": "w1", "platform": {"simd": "x" * 100_000}}).encode()
    reply = decode_work_reply(core.handle_lease_request(hostile))
    assert isinstance(reply, NoWork) and "platform" in reply.reason
    assert client.get("/workers").json()[0]["platform"] == {}
    with pytest.raises(ValueError, match="platform"):
        LeaseRequest(worker="w1", platform={f"k{i}": "v" for i in range(100)})


def test_a_jobs_mcap_names_the_platform_of_each_worker(service):
    from mcap.reader import make_reader

    from swarmpath.service.protocol import Lease, LeaseRequest, decode_work_reply, encode
    from swarmpath.service.worker import execute_lease, pack_batches

    client, core = service
    spec = {"kind": "benchmark", "algorithms": ["PSO"], "functions": ["F1"], "dims": [2],
            "runs": 2, "agents": 5, "iterations": 3, "seed": 1}
    job = client.post("/jobs", json=spec).json()
    core.worker_alive("w1")
    request = encode(LeaseRequest(worker="w1", max_runs=10,
                                  platform=provenance.numeric_platform()))
    while isinstance(lease := decode_work_reply(core.handle_lease_request(request)), Lease):
        for payload in pack_batches("w1", [d for _r, d in execute_lease(lease)]):
            core.handle_results(f"swarmpath/results/{lease.job_id}", payload)
    assert client.get(f"/jobs/{job['id']}").json()["state"] == "done"
    mcap = client.get(f"/jobs/{job['id']}/mcap")
    records = [m.metadata for m in make_reader(io.BytesIO(mcap.content)).iter_metadata()
               if m.name == "swarmpath.platform"]
    assert records == [{**provenance.numeric_platform(), "worker": "w1"}]  # once, not per run
