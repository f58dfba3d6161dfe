"""The result commands against the coordinator's app in-process (no network): cancel, download,
per-run exports, IOHprofiler files and plots of a finished job."""

from __future__ import annotations

from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

import swarmpath.cli.service as service_cli
from swarmpath.cli import app as cli_app
from swarmpath.service.client import ServiceClient
from swarmpath.service.coordinator import CoordinatorSettings, create_app
from swarmpath.service.protocol import Lease, LeaseRequest, decode_work_reply, encode
from swarmpath.service.worker import execute_lease, pack_batches

BENCH = {
    "kind": "benchmark", "algorithms": ["GWO", "PSO"], "functions": ["F1", "F8"], "dims": [2],
    "runs": 3, "agents": 6, "iterations": 10, "seed": 4,
}
MAPS = {"kind": "map", "planners": ["OMPL-RRTstar"], "maps": ["mfb-static"], "runs": 2,
        "seed": 2, "params": {"OMPL-RRTstar": {"time": 0.1}}}


@pytest.fixture
def service(tmp_path, monkeypatch):
    """(cli(*args), http client, core) against one in-process coordinator."""
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    monkeypatch.chdir(tmp_path)
    app = create_app(CoordinatorSettings(data_dir=tmp_path / "data"), use_zenoh=False)
    with TestClient(app) as http:
        monkeypatch.setattr(service_cli, "_client",
                            lambda url: ServiceClient("http://testserver",
                                                      transport=http._transport))
        runner = CliRunner()
        app.state.core.publish = lambda key, payload: None
        yield (lambda *args: runner.invoke(cli_app, list(args))), http, app.state.core


def work_off(core) -> int:
    core.worker_alive("w1")
    n = 0
    while isinstance(lease := decode_work_reply(core.handle_lease_request(
            encode(LeaseRequest(worker="w1", max_runs=100)))), Lease):
        results = execute_lease(lease)
        for payload in pack_batches("w1", [data for _run, data in results]):
            core.handle_results(f"swarmpath/results/{lease.job_id}", payload)
        n += len(results)
    return n


def finished(service, spec) -> str:
    _cli, http, core = service
    job = http.post("/jobs", json=spec).json()["id"]
    work_off(core)
    assert http.get(f"/jobs/{job}").json()["state"] == "done"
    return job


def test_cancel_cancels_and_prints_the_state(service):
    cli, http, _core = service
    job = http.post("/jobs", json=BENCH).json()["id"]
    result = cli("cancel", job)
    assert result.exit_code == 0, result.stderr
    assert result.stdout.strip() == f"job {job}: cancelled (0/12 runs finished, 0 failed)"
    assert http.get(f"/jobs/{job}").json()["state"] == "cancelled"
    bad = cli("cancel", "nosuchjob")
    assert bad.exit_code == 2 and bad.stderr.count("\n") == 1 and "JOB" in bad.stderr


def test_download_without_output_writes_job_mcap_here(service):
    cli, _http, _core = service
    job = finished(service, BENCH)
    result = cli("download", job)
    assert result.exit_code == 0, result.stderr
    data = Path(f"{job}.mcap").read_bytes()
    assert data.startswith(b"\x89MCAP0\r\n") and len(data) > 1000


def test_results_and_status_tables_explain_their_columns(service):
    cli = service[0]
    job = finished(service, MAPS)
    table = cli("results", job)
    assert table.exit_code == 0, table.stderr
    out = " ".join(table.stdout.split())
    assert "failed: runs that crashed" in out and "not failed" in out
    assert "collisions: simulated steps in which the robot body touched an obstacle, summed" in out
    assert "gap_mean: " in out and "moving obstacles" in out
    status = " ".join(cli("status").stdout.split())
    assert "failed: runs that crashed" in status and "gap_mean" not in status


def test_legend_follows_the_columns_it_is_given():
    from swarmpath.legend import NOTES, legend

    assert [c for c, _ in legend(["planner", "failed", "Gap (%)", "x"])] == ["failed", "Gap (%)"]
    assert legend(["Collisions"]) == [("Collisions", NOTES["collisions"])]
