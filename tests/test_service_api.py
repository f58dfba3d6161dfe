"""The coordinator without a network: REST routes (FastAPI TestClient), the protocol handlers driven
with bytes, the worker's execution functions, lease sizing and the Zenoh config builders."""

from __future__ import annotations

import io
import json
import logging
import time

import pytest
from fastapi.testclient import TestClient
from mcap.reader import make_reader

from swarmpath.optimizers import minimize
from swarmpath.optimizers.api import BACKENDS
from swarmpath.service.capability import (
    drop_ok,
    drop_proof,
    new_capability,
    progress_ok,
    progress_proof,
    result_proof,
)
from swarmpath.service.client import ServiceClient, ServiceError, error_field
from swarmpath.service.coordinator import (
    Coordinator,
    CoordinatorSettings,
    LeaseSizer,
    create_app,
    json_safe,
)
from swarmpath.service.protocol import (
    Ack,
    BenchmarkCell,
    Cancel,
    Lease,
    LeaseBundle,
    LeaseDrop,
    LeaseRequest,
    MapCell,
    NoWork,
    ResultBatch,
    RunProgress,
    RunResult,
    decode,
    decode_work_reply,
    encode,
)
from swarmpath.service.result_frame import as_dict, decode_frame, decode_record
from swarmpath.service.summary_stats import BENCHMARK_TEST_COLUMNS as TEST_COLUMNS
from swarmpath.service.worker import (
    Cancelled,
    ThreadSlot,
    benchmark_batches,
    execute_lease,
    fit_result,
    pack_batches,
)
from swarmpath.service.zenoh_config import check_endpoint, client_config, router_config

CAP = "c0de" * 16  # the capability of the hand-made leases below

SPEC = {
    "kind": "benchmark", "algorithms": ["GWO", "PSO"], "functions": ["F1", "F9"], "dims": [3],
    "runs": 5, "agents": 6, "iterations": 12, "seed": 4,
}


class Wire:
    """Stands in for Zenoh: records what the coordinator publishes."""

    def __init__(self) -> None:
        self.sent: list[tuple[str, bytes]] = []

    def __call__(self, key: str, payload: bytes) -> None:
        self.sent.append((key, payload))

    def acks(self) -> list[Ack]:
        return [decode(Ack, p) for k, p in self.sent if "/ack/" in k]


@pytest.fixture
def app(tmp_path, monkeypatch):
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    return create_app(CoordinatorSettings(data_dir=tmp_path / "data"), use_zenoh=False)


@pytest.fixture
def client(app):
    with TestClient(app) as c:
        yield c


@pytest.fixture
def core(client, app) -> Coordinator:
    core = app.state.core
    core.publish = Wire()
    return core


def statuses(ack: Ack | None) -> set[str]:
    assert ack is not None
    return {status for _lease, _run, status in ack.statuses()}


def frame_results(payload: bytes) -> list[dict]:
    """The results of a result frame as RunResult fields."""
    return [as_dict(r) for r in decode_frame(payload)[1]]


def as_json_result(record: bytes, capability: str) -> RunResult:
    """A worker's frame record as the JSON RunResult with its proof (the JSON form)."""
    r = RunResult(**as_dict(decode_record(record)))
    return r.model_copy(update={"proof": result_proof(capability, r)})


def lease_for(core: Coordinator, worker: str = "w1", max_runs: int = 100) -> Lease | NoWork:
    reply = core.handle_lease_request(encode(LeaseRequest(worker=worker, max_runs=max_runs)))
    return decode_work_reply(reply)


def work_off(core: Coordinator, worker: str = "w1", max_runs: int = 100) -> int:
    """What a worker does, without the network: lease, execute, publish, until no work."""
    core.worker_alive(worker)
    n = 0
    while isinstance(lease := lease_for(core, worker, max_runs), Lease):
        results = execute_lease(lease)
        for payload in pack_batches(worker, [data for _run, data in results]):
            ack = core.handle_results(f"swarmpath/results/{lease.job_id}", payload)
            assert ack is not None and statuses(ack) == {"accepted"}
        n += len(results)
    return n


# ------------------------------------------------------------------------------------ jobs
def test_submit_status_list_and_404(client):
    r = client.post("/jobs", json=SPEC)
    assert r.status_code == 201
    job = r.json()
    assert set(job) == {"id", "state", "runs_total"}
    assert job["state"] == "queued" and job["runs_total"] == 20
    status = client.get(f"/jobs/{job['id']}").json()
    assert (status["state"], status["runs_done"], status["kind"]) == ("queued", 0, "benchmark")
    assert [j["id"] for j in client.get("/jobs").json()] == [job["id"]]
    assert client.get("/jobs", params={"state": "queued"}).json()[0]["id"] == job["id"]
    assert client.get("/jobs", params={"state": "done"}).json() == []
    for path in ("/jobs/nope", "/jobs/nope/summary", "/jobs/nope/runs", "/jobs/nope/runs/0",
                 "/jobs/nope/mcap"):
        assert client.get(path).status_code == 404, path
    assert client.delete("/jobs/nope").status_code == 404
    assert client.get(f"/jobs/{job['id']}/runs/20").status_code == 404


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"algorithms": ["GWO", "NOPE"]}, "algorithms.1"),
        ({"functions": ["F99"]}, "functions.0"),
        ({"dims": [1001]}, "dims.0"),
        ({"agents": 1001}, "agents"),
        ({"iterations": 100_001}, "iterations"),
        ({"runs": 10_001}, "runs"),
        ({"functions": ["F1-F13"], "dims": [2, 3, 4, 5], "runs": 10_000}, "runs"),
        ({"params": {"GWO": {"nope": 1}}}, "params.GWO.nope"),
        ({"seed": -1}, "seed"),
        ({"kind": "nope"}, "kind"),
        ({"extra": 1}, "extra"),
        ({"reference": "NOPE"}, "reference"),
        ({"backend": "cuda"}, "backend"),
        ({"backend": "numba", "transform": "rotate"}, "backend"),
    ],
)
def test_malformed_jobs_are_422_naming_the_field(client, change, field):
    r = client.post("/jobs", json={**SPEC, **change})
    assert r.status_code == 422
    fields = [error_field(d["loc"]) for d in r.json()["detail"]]
    assert field in fields, r.json()
    assert all(d["msg"] for d in r.json()["detail"])
    assert client.get("/jobs").json() == []


def test_bad_bodies_and_queries_are_422(client):
    r = client.post("/jobs", content=b"{not json", headers={"content-type": "application/json"})
    assert r.status_code == 422 and r.json()["detail"][0]["loc"][0] == "body"
    big = json.dumps({**SPEC, "pad": "x" * 1_000_001})
    r = client.post("/jobs", content=big, headers={"content-type": "application/json"})
    assert r.status_code == 422
    assert r.json()["detail"][0]["loc"] == ["body"] and "exceeds" in r.json()["detail"][0]["msg"]
    r = client.get("/jobs", params={"state": "bogus"})
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["query", "state"]
    r = client.get("/jobs", params={"limit": 0})
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["query", "limit"]


def test_map_job_without_planners_or_with_unknown_map_names_the_field(client):
    r = client.post("/jobs", json={"kind": "map", "planners": ["NOPE"], "maps": ["nowhere"]})
    assert r.status_code == 422
    fields = {error_field(d["loc"]) for d in r.json()["detail"]}
    assert fields == {"planners.0", "maps.0"}


def test_token_protects_mutating_endpoints(tmp_path, monkeypatch):
    monkeypatch.setenv("SWARMPATH_TOKEN", "s3cret")
    app = create_app(CoordinatorSettings(data_dir=tmp_path / "d"), use_zenoh=False)
    with TestClient(app) as c:
        assert c.post("/jobs", json=SPEC).status_code == 401
        bad = {"Authorization": "Bearer nope"}
        assert c.post("/jobs", json=SPEC, headers=bad).status_code == 401
        good = {"Authorization": "Bearer s3cret"}
        r = c.post("/jobs", json=SPEC, headers=good)
        assert r.status_code == 201
        assert c.delete(f"/jobs/{r.json()['id']}").status_code == 401
        assert c.get(f"/jobs/{r.json()['id']}").status_code == 200  # reading is open
        assert c.delete(f"/jobs/{r.json()['id']}", headers=good).json()["state"] == "cancelled"


# -------------------------------------------------------------------------------- protocol
def test_a_job_worked_off_through_the_handlers(client, core):
    job = client.post("/jobs", json=SPEC).json()
    assert client.get(f"/jobs/{job['id']}/mcap").status_code == 409
    assert "queued (0/20 runs finished)" in client.get(f"/jobs/{job['id']}/mcap").json()["detail"]
    assert work_off(core) == 20
    status = client.get(f"/jobs/{job['id']}").json()
    assert status["state"] == "done" and status["runs_done"] == 20

    # every run equals a direct minimize() call with the same seed
    items = client.get(f"/jobs/{job['id']}/runs", params={"limit": 100}).json()["items"]
    assert [i["run_id"] for i in items] == list(range(20))
    for a in SPEC["algorithms"]:
        for f in SPEC["functions"]:
            direct = minimize(a, f, 3, 6, 12, runs=5, seed=4).best_fitness.tolist()
            got = [i["best_fitness"] for i in items if i["algorithm"] == a and i["function"] == f]
            assert got == direct
    page = client.get(f"/jobs/{job['id']}/runs", params={"limit": 3, "offset": 18}).json()
    assert page["total"] == 20 and [i["run_id"] for i in page["items"]] == [18, 19]
    one = client.get(f"/jobs/{job['id']}/runs/7").json()
    assert len(one["curve"]) == 12 and one["state"] == "done" and one["worker"] == "w1"

    summary = client.get(f"/jobs/{job['id']}/summary").json()
    assert not summary["partial"] and len(summary["rows"]) == 4
    csv = client.get(f"/jobs/{job['id']}/summary", params={"format": "csv"})
    assert csv.headers["content-type"].startswith("text/csv")
    assert csv.text.splitlines()[0].startswith("algorithm,function,dim")
    assert csv.text.splitlines()[0].endswith(",rank,origin_suspect," + ",".join(TEST_COLUMNS))
    assert summary["statistics"]["comparison"]["reference"] == "PSO"  # the last algorithm
    assert [r["marker"] for r in summary["rows"] if r["algorithm"] == "PSO"] == [None, None]
    assert all(r["marker"] in ("+", "=", "-") for r in summary["rows"] if r["algorithm"] == "GWO")

    r = client.get(f"/jobs/{job['id']}/mcap")
    assert r.status_code == 200
    reader = make_reader(io.BytesIO(r.content))
    results = [json.loads(m.data) for _s, _c, m in reader.iter_messages(topics=["/results"])]
    assert sorted(m["run_id"] for m in results) == list(range(20))


def test_duplicates_stale_and_garbage(client, core, caplog):
    job = client.post("/jobs", json=SPEC).json()
    core.worker_alive("w1")
    lease = lease_for(core)
    assert isinstance(lease, Lease)
    payloads = pack_batches("w1", [d for _r, d in execute_lease(lease)])
    key = f"swarmpath/results/{job['id']}"
    first = core.handle_results(key, payloads[0])
    again = core.handle_results(key, payloads[0])
    assert statuses(first) == {"accepted"}
    assert statuses(again) == {"duplicate"}
    # someone else's lease, or published under another job's key: stale
    forged = payloads[0].replace(b'"worker":"w1"', b'"worker":"w2"')
    assert statuses(core.handle_results(key, forged)) == {"stale"}
    assert statuses(core.handle_results("swarmpath/results/other", payloads[0])) == {"stale"}
    with caplog.at_level(logging.WARNING, logger="swarmpath.coordinator"):
        for garbage in (b"", b"\xff\x00", b"{}", b"[1,2]", b'{"worker": "w1", "results": []}',
                        b"x" * 2_000_000):
            assert core.handle_results(key, garbage) is None
            assert core.handle_progress(f"swarmpath/progress/{job['id']}", garbage) is None
        reply = decode_work_reply(core.handle_lease_request(b"garbage"))
        assert isinstance(reply, NoWork) and "malformed" in reply.reason
    assert "malformed result batch" in caplog.text
    assert core.stats["malformed"] >= 13
    assert client.get("/healthz").json()["status"] == "ok"
    assert "swarmpath_messages_malformed_total 13" in client.get("/metrics").text
    n = client.get(f"/jobs/{job['id']}").json()["runs_done"]
    assert n == len(lease.runs)


def test_progress_renews_and_drops_only_with_the_proof(client, core):
    job = client.post("/jobs", json=SPEC).json()
    core.worker_alive("w1")
    lease = lease_for(core)
    key = f"swarmpath/progress/{lease.job_id}"

    def progress(seq: int, cap: str = lease.capability, lease_id: str = lease.lease_id) -> bytes:
        return encode(RunProgress(lease_id=lease_id, job_id=lease.job_id, worker="w1",
                                  cell=lease.cell, runs=lease.runs, seq=seq,
                                  proof=progress_proof(cap, lease_id, seq)))

    assert core.handle_progress(key, progress(1)) is None  # active: renewed, no answer
    # a stolen lease id with a made-up secret, a replayed message, an unknown lease: ignored
    assert core.handle_progress(key, progress(2, cap="0" * 64)) is None
    assert core.handle_progress(key, progress(1)) is None
    assert core.handle_progress(key, progress(3, lease_id="nope")) is None
    assert core.publish.acks() == [] and core.stats["unproven"] == 3
    client.delete(f"/jobs/{job['id']}")
    ack = core.handle_progress(key, progress(2))  # the lease ended: drop it, with the proof
    assert [d.lease_id for d in ack.drop_leases] == [lease.lease_id]
    assert drop_ok(lease.capability, lease.lease_id, ack.drop_leases[0].proof)
    assert core.publish.acks()[-1] == ack


def test_forged_results_and_stolen_lease_ids_are_stale(client, core):
    """What an attacker on the bus can see (lease ids, workers, cells and runs are broadcast in
    progress messages) is not enough: without the lease's capability every result is stale,
    and the real worker's results are accepted afterwards."""
    job = client.post("/jobs", json=SPEC).json()
    core.worker_alive("w1")
    lease = lease_for(core)
    real = [as_json_result(d, lease.capability) for _r, d in execute_lease(lease)]
    key = f"swarmpath/results/{job['id']}"
    forged = [r.model_copy(update={"metrics": {**r.metrics, "best_fitness": -12345.0},
                                   "proof": None}) for r in real]
    guessed = [r.model_copy(update={"proof": result_proof(new_capability(), r)}) for r in forged]
    altered = [r.model_copy(update={"metrics": forged[0].metrics}) for r in real]  # proof kept
    for batch in (forged, guessed, altered):
        payload = encode(ResultBatch(worker="w1", results=batch))
        assert statuses(core.handle_results(key, payload)) == {"stale"}
    assert client.get(f"/jobs/{job['id']}").json()["runs_done"] == 0
    payload = encode(ResultBatch(worker="w1", results=real))
    assert statuses(core.handle_results(key, payload)) == {"accepted"}
    values = [r["best_fitness"] for r in client.get(f"/jobs/{job['id']}/runs").json()["items"]
              if r["state"] == "done"]
    assert sorted(values) == sorted(r.metrics["best_fitness"] for r in real)
    assert -12345.0 not in values


def test_a_result_frame_is_checked_record_by_record(client, core):
    """One altered record of a frame (a bit of its curve) is stale; the others are accepted
    and stored with their exact curves."""
    job = client.post("/jobs", json=SPEC).json()
    core.worker_alive("w1")
    lease = lease_for(core)
    records = [d for _r, d in execute_lease(lease)]
    altered = bytearray(records[1])
    altered[-40] ^= 0x01  # inside the last array, before the proof
    payload = pack_batches("w1", [records[0], bytes(altered), *records[2:]])[0]
    ack = core.handle_results(f"swarmpath/results/{job['id']}", payload)
    runs = [as_dict(decode_record(rec))["run"] for rec in records]
    assert ack.leases[0].accepted == [runs[0], *runs[2:]] and ack.leases[0].stale == [runs[1]]
    for rec in (records[0], records[-1]):
        sent = as_dict(decode_record(rec))
        run = core.store.run(job["id"], lease.cell_index * SPEC["runs"] + sent["run"])
        assert run["curve"] == sent["curve"] and run["best_fitness"] == sent["metrics"][
            "best_fitness"]


def test_leases_only_to_live_workers_and_requeue_when_gone(client, core):
    job = client.post("/jobs", json=SPEC).json()
    assert isinstance(lease_for(core, "ghost"), NoWork)
    core.worker_alive("w1")
    lease = lease_for(core, "w1", 3)
    assert isinstance(lease, Lease) and len(lease.runs) == 3
    workers = {w["id"]: w for w in client.get("/workers").json()}
    assert len(workers["w1"]["current_runs"]) == 3 and workers["w1"]["alive"] is True
    assert "ghost" not in workers  # a lease request alone makes no worker entry
    assert core.worker_gone("w1") == 3
    assert {w["id"]: w for w in client.get("/workers").json()}["w1"]["alive"] is False
    core.worker_alive("w2")
    again = lease_for(core, "w2", 3)
    assert (again.cell, again.runs) == (lease.cell, lease.runs)  # requeued runs first
    assert "swarmpath_lease_requeues_total 3" in client.get("/metrics").text
    assert client.get(f"/jobs/{job['id']}").json()["state"] == "running"


def test_cancel_publishes_and_finalizes(client, core):
    job = client.post("/jobs", json=SPEC).json()
    core.worker_alive("w1")
    lease = lease_for(core)
    r = client.delete(f"/jobs/{job['id']}")
    assert r.status_code == 200 and r.json()["state"] == "cancelled"
    cancels = [decode(Cancel, p) for k, p in core.publish.sent if k == "swarmpath/cancel"]
    assert [c.job_id for c in cancels] == [job["id"]]
    (drop,) = cancels[0].leases  # the one active lease, with the coordinator's proof
    assert drop.lease_id == lease.lease_id and drop_ok(lease.capability, drop.lease_id, drop.proof)
    assert client.get(f"/jobs/{job['id']}/mcap").status_code == 200
    results = pack_batches("w1", [d for _r, d in execute_lease(lease)])
    ack = core.handle_results(f"swarmpath/results/{job['id']}", results[0])
    assert statuses(ack) == {"stale"}
    assert isinstance(lease_for(core), NoWork)
    assert client.delete(f"/jobs/{job['id']}").json()["state"] == "cancelled"


def test_made_up_worker_ids_leave_no_state(client, core):
    """3,000 ids in lease requests, results and progress add nothing; 10,000 liveliness tokens
    (20 times the cap) keep the table at its cap and leave nothing when they go; a newcomer is
    refused (and counted) only when proven workers fill the table, and gone workers are pruned.
    (scripts/bench/bus_state.py measures memory and GET /workers for 100,000 ids.)"""
    core.worker_table.max_entries = 500
    job = client.post("/jobs", json=SPEC).json()
    for i in range(3_000):
        worker = f"made-up-{i}"
        if i % 3 == 0:
            core.handle_lease_request(encode(LeaseRequest(worker=worker, slots=10**6)))
        elif i % 3 == 1:
            batch = {"worker": worker, "results": [{"lease_id": f"L{i}", "job_id": job["id"],
                                                    "cell": "GWO/F1/3", "run": 0,
                                                    "worker": worker, "seconds": 0.0}]}
            core.handle_results(f"swarmpath/results/{job['id']}", json.dumps(batch).encode())
        else:
            progress = {"lease_id": f"L{i}", "job_id": job["id"], "worker": worker,
                        "cell": "GWO/F1/3", "runs": [0], "seq": 1, "proof": "0" * 64}
            core.handle_progress(f"swarmpath/progress/{job['id']}",
                                 json.dumps(progress).encode())
    assert len(core.worker_table) == 0 and client.get("/workers").json() == []
    assert core.sizer.slots == 1
    for i in range(10_000):  # tokens alone: unproven entries, each making room for the next
        core.worker_alive(f"token-{i}", now=1000.0 + i)
    assert len(core.worker_table) == 500 and core.worker_table.refused == 0
    assert len(client.get("/workers").json()) == 500
    assert "swarmpath_worker_table_entries 500" in client.get("/metrics").text
    for i in range(10_000):  # tokens that leave take their (unproven) entries with them
        core.worker_mark_gone(f"token-{i}")
    assert len(core.worker_table) == 0
    for i in range(500):  # proven workers (a lease request each) fill the table ...
        core.worker_alive(f"real-{i}")
        lease_for(core, f"real-{i}", max_runs=1)
    core.worker_alive("late")  # ... and only then is a newcomer refused, and counted
    assert not core.is_alive("late") and core.worker_table.refused == 1
    assert "swarmpath_workers_refused_total 1" in client.get("/metrics").text
    for i in range(500):
        core.worker_mark_gone(f"real-{i}")
    core.worker_alive("newcomer")  # room is made by forgetting a gone worker
    assert core.is_alive("newcomer") and len(core.worker_table) == 500
    core.tick(now=time.time() + core.settings.forget_workers_seconds + 1)
    assert [w["id"] for w in client.get("/workers").json()] == ["newcomer"]


def test_the_worker_tables_live_counts_follow_every_change():
    """alive_count/alive_slots (asked by every lease request) are kept, not recounted per
    request: after tokens, slots, departures, returns and evictions they equal a recount."""
    from swarmpath.service.worker_table import MAX_SLOTS, WorkerTable

    table = WorkerTable(max_entries=4, forget_seconds=10.0)

    def check() -> None:
        live = [e for e in table.snapshot().values() if e.alive]
        assert (table.alive_count(), table.alive_slots()) == (len(live),
                                                               sum(e.slots for e in live))

    steps = [
        lambda: table.alive("a", 1.0), lambda: table.alive("b", 2.0),
        lambda: table.seen("a", 3.0, slots=8, proven=True),
        lambda: table.seen("a", 3.5, slots=10**9, proven=True),  # bounded: MAX_SLOTS
        lambda: table.seen("b", 4.0, slots=3), lambda: table.gone("b", 5.0),  # unproven: out
        lambda: table.alive("c", 6.0), lambda: table.seen("c", 6.5, slots=2, proven=True),
        lambda: table.gone("a", 7.0), lambda: table.alive("a", 8.0),  # back
        lambda: table.alive("d", 9.0), lambda: table.alive("e", 9.5),
        lambda: table.alive("f", 9.7),  # full: the oldest unproven (d) makes room
        lambda: table.gone("c", 10.0), lambda: table.prune(30.0),
    ]
    for step in steps:
        step()
        check()
    assert table.alive_slots() == MAX_SLOTS + 2  # a (capped), e, f
    assert table.alive_count() == 3


def test_catalog_health_metrics(client):
    cat = client.get("/catalog").json()
    gwo = next(o for o in cat["optimizers"] if o["name"] == "GWO")
    assert "params" in gwo and gwo["min_agents"] >= 1
    assert {"F1", "F13"} <= {f["name"] for f in cat["functions"]}
    assert "mfb-static" in {m["name"] for m in cat["maps"]}
    assert "planners" in cat
    health = client.get("/healthz").json()
    assert health["status"] == "ok" and health["zenoh"] is False
    text = client.get("/metrics").text
    for name in ("swarmpath_queue_depth", "swarmpath_runs_per_second", "swarmpath_workers",
                 "swarmpath_lease_requeues_total"):
        assert f"# TYPE {name}" in text
    assert client.get("/openapi.json").status_code == 200


def test_client_against_the_app(app):
    with TestClient(app) as c:
        client = ServiceClient("http://testserver", transport=c._transport)
        job = client.submit(SPEC)
        assert client.job(job["id"])["state"] == "queued"
        with pytest.raises(ServiceError) as err:
            client.submit({**SPEC, "dims": [0]})
        assert err.value.status == 422 and err.value.fields == ["dims.0"]
        with pytest.raises(ServiceError) as err:
            client.download(job["id"], "/nonexistent/x.mcap")
        assert err.value.status == 409


# --------------------------------------------------------------------------------- worker
def make_lease(spec, runs, seed=4) -> Lease:
    return Lease(lease_id="L1", worker="w1", job_id="j1", cell=spec.key, cell_index=0,
                 runs_per_cell=10, seed=seed, runs=runs, spec=spec, deadline=0.0,
                 lease_seconds=30.0, heartbeat_seconds=10.0, capability=CAP)


@pytest.mark.parametrize("backend", BACKENDS)
def test_execute_lease_equals_minimize_and_splits_batches(monkeypatch, backend):
    spec = BenchmarkCell(algorithm="GWO", function="F9", dim=4, agents=6, iterations=10,
                         backend=backend)
    import swarmpath.service.worker.execution as w

    monkeypatch.setattr(w, "BATCH_ELEMENTS", 6 * 4 * 2)  # batches of two runs
    assert benchmark_batches([3, 5, 7], 6, 4) == [[3, 5], [7]]
    got = execute_lease(make_lease(spec, [3, 5, 7]))
    # every backend gives the numpy reference's numbers (auto, the job spec's default, too)
    direct = minimize("GWO", "F9", 4, 6, 10, seed=4, run_ids=[3, 5, 7], backend="numpy")
    records = [as_dict(decode_record(d)) for _r, d in got]
    assert [r for r, _d in got] == [3, 5, 7]
    assert [r["metrics"]["best_fitness"] for r in records] == direct.best_fitness.tolist()
    assert [r["curve"] for r in records] == direct.curve.tolist()


def test_execute_lease_failures_and_cancellation():
    spec = BenchmarkCell(algorithm="GWO", function="F1", dim=2, agents=6, iterations=5,
                         params={"nope": 1})
    results = [as_dict(decode_record(d)) for _r, d in execute_lease(make_lease(spec, [0, 1]))]
    assert [r["status"] for r in results] == ["failed", "failed"]
    assert "nope" in results[0]["failure"]
    ok = spec.model_copy(update={"params": {}})
    with pytest.raises(Cancelled):
        execute_lease(make_lease(ok, [0]), cancelled=lambda: True)


def test_thread_slot_runs_a_lease():
    import threading

    done = threading.Event()
    seen = []

    def on_done(slot, outcomes):
        seen.extend((lease.lease_id, outcome) for lease, outcome in outcomes)
        done.set()

    slot = ThreadSlot(0, on_done)
    spec = BenchmarkCell(algorithm="PSO", function="F1", dim=2, agents=5, iterations=5)
    second = make_lease(spec, [2]).model_copy(update={"lease_id": "L2"})
    slot.submit([make_lease(spec, [0, 1]), second])  # a group: run one after the other
    assert done.wait(30)
    assert [lease_id for lease_id, _ in seen] == ["L1", "L2"]
    assert [r for r, _ in seen[0][1]] == [0, 1] and [r for r, _ in seen[1][1]] == [2]
    slot.close()


def test_pack_batches_and_fit_result():
    spec = BenchmarkCell(algorithm="GWO", function="F1", dim=2, agents=6, iterations=5)
    lease = make_lease(spec, list(range(10)))
    records = [fit_result(RunResult(lease_id="L1", job_id="j1", cell=spec.key, run=i,
                                    worker="w1", seconds=0.5, curve=[float(i)] * 40),
                          capability=lease.capability) for i in range(10)]
    frames = pack_batches("w1", records, limit=2000)
    assert len(frames) > 1 and all(len(f) <= 2000 for f in frames)
    merged = [r for f in frames for r in frame_results(f)]
    assert [r["run"] for r in merged] == list(range(10))
    assert all(r["curve"] == [float(r["run"])] * 40 for r in merged)

    big = RunResult(lease_id="L1", job_id="j1", cell=spec.key, run=0, worker="w1", seconds=1.0,
                    curve=[1.0 / (i + 1) for i in range(50_000)])
    data = fit_result(big, limit=100_000)
    obj = as_dict(decode_record(data))
    assert len(data) <= 100_000 and obj["metrics"]["curve_stride"] > 1
    assert obj["curve"][0] == 1.0 and obj["curve"][-1] == 1.0 / 50_000


# ------------------------------------------------------------------------------ sizing etc.
def test_lease_sizer():
    sizer = LeaseSizer(target_seconds=2.0, min_runs=8)
    cheap = BenchmarkCell(algorithm="GWO", function="F1", dim=2, agents=5, iterations=10)
    costly = BenchmarkCell(algorithm="GWO", function="F1", dim=100, agents=100, iterations=5000)
    assert sizer.runs_for(cheap) > 1000
    assert sizer.runs_for(costly) == 8  # vectorization floor
    sizer.observe(cheap, 0.1)
    assert sizer.runs_for(cheap) == 20
    m = MapCell(planner="ICOOT", map="mfb-static")
    assert sizer.runs_for(m) == 1
    sizer.observe(m, 0.01)
    assert sizer.runs_for(m) == 200


def test_json_safe():
    assert json_safe({"a": [1.0, float("inf"), float("nan")], "b": float("-inf")}) == {
        "a": [1.0, "inf", "nan"], "b": "-inf"}


def test_zenoh_configs_never_scout():
    r = router_config("tcp/127.0.0.1:7447", extra={"scouting": {"multicast": {"enabled": True}}})
    c = client_config(["tcp/127.0.0.1:7447"], user="u", password="p")
    for conf in (r, c):
        assert conf["scouting"] == {"multicast": {"enabled": False}, "gossip": {"enabled": False}}
        assert conf["transport"]["shared_memory"] == {"enabled": False}
    assert r["mode"] == "router" and r["listen"]["endpoints"] == ["tcp/127.0.0.1:7447"]
    assert r["connect"]["endpoints"] == []
    assert c["mode"] == "client" and c["listen"]["endpoints"] == []
    assert c["transport"]["auth"]["usrpwd"] == {"user": "u", "password": "p"}
    assert router_config(shm=True)["transport"]["shared_memory"]["enabled"] is True
    for bad in ("127.0.0.1:7447", "tcp/127.0.0.1", "tcp/:7447", "tcp/h:99999", ""):
        with pytest.raises(ValueError):
            check_endpoint(bad)
    with pytest.raises(ValueError):
        client_config("tcp/127.0.0.1:7447", user="u")
    with pytest.raises(ValueError):
        router_config(dictionary_file="/nonexistent/users.txt")


# ------------------------------------------------------------- worker bookkeeping, no network
class FakeSession:
    def __init__(self) -> None:
        self.puts: list[tuple[str, bytes]] = []

    def put(self, key: str, payload: bytes, **_kw) -> None:
        self.puts.append((key, payload))


class Sample:
    def __init__(self, payload: bytes) -> None:
        self.payload = type("Z", (), {"to_bytes": lambda _self: payload})()


def offline_worker(**settings):
    from types import SimpleNamespace

    from swarmpath.service.worker import Worker, WorkerSettings

    w = Worker(WorkerSettings(worker_id="w1", **settings))
    w._session = FakeSession()
    w._zenoh = SimpleNamespace(Encoding=SimpleNamespace(APPLICATION_JSON=None),
                               CongestionControl=SimpleNamespace(BLOCK=None))
    return w


def run_ack(lease: Lease, runs, status="accepted", drop=()) -> Sample:
    from swarmpath.service.protocol import RunAck

    drops = [LeaseDrop(lease_id=d, proof=drop_proof(CAP, d)) for d in drop]
    return Sample(encode(Ack(worker="w1", drop_leases=drops, results=[
        RunAck(lease_id=lease.lease_id, job_id=lease.job_id, cell=lease.cell, run=r,
               status=status) for r in runs])))


def test_worker_resends_until_acknowledged():
    import time as _time

    w = offline_worker(ack_timeout=5.0)
    spec = BenchmarkCell(algorithm="PSO", function="F1", dim=2, agents=5, iterations=3)
    lease = make_lease(spec, [0, 1, 2])
    w._publish_results(lease, execute_lease(lease))
    assert len(w._session.puts) == 1 and w._session.puts[0][0] == "swarmpath/results/j1"
    t = _time.monotonic()
    assert w.resend_due(t + 1) == 0  # not yet due
    w._on_ack(run_ack(lease, [0]))  # the coordinator is working through them ...
    w._last_ack = t + 4  # ... (an ack came 1.5 s ago): no resend
    assert w.resend_due(t + 5.5) == 0
    assert w.resend_due(t + 9.5) == 2  # silent for longer than ack_timeout: put again
    assert len(w._session.puts) == 2 and len(frame_results(w._session.puts[1][1])) == 2
    w._on_ack(run_ack(lease, [1, 2], status="duplicate"))
    assert w._pending == {} and w.resend_due(t + 100) == 0


def test_worker_resends_a_result_overtaken_by_a_later_one():
    import time as _time

    w = offline_worker()
    spec = BenchmarkCell(algorithm="PSO", function="F1", dim=2, agents=5, iterations=3)
    first, second = make_lease(spec, [0]), make_lease(spec, [1]).model_copy(
        update={"lease_id": "L2"})
    w._publish_results(first, execute_lease(first))
    w._publish_results(second, execute_lease(second))
    w._on_ack(run_ack(second, [1]))  # the later put was handled: the first one was lost
    assert w.resend_due(_time.monotonic() + 5.1) == 1
    assert frame_results(w._session.puts[-1][1])[0]["lease_id"] == "L1"


def test_worker_drops_leases_only_on_the_coordinators_word():
    w = offline_worker()
    spec = BenchmarkCell(algorithm="PSO", function="F1", dim=2, agents=5, iterations=3)
    lease = make_lease(spec, [0, 1])
    w._publish_results(lease, execute_lease(lease))
    w._on_ack(run_ack(lease, [], drop=["L1"]))
    assert w._pending == {} and "L1" in w._dropped
    w._dropped.clear()
    w._publish_results(lease, execute_lease(lease))
    # forged: a cancel naming the job only, one with a made-up proof, an ack with a drop proof
    # of another lease (replayed from the bus): nothing is dropped
    made_up = LeaseDrop(lease_id="L1", proof=drop_proof(new_capability(), "L1"))
    replayed = LeaseDrop(lease_id="L1", proof=drop_proof(CAP, "L2"))
    w._on_cancel(Sample(encode(Cancel(job_id="j1"))))
    w._on_cancel(Sample(encode(Cancel(job_id="j1", leases=[made_up]))))
    w._on_ack(Sample(encode(Ack(worker="w1", drop_leases=[replayed]))))
    assert len(w._pending) == 2 and not w._dropped and w.unproven_drops == 2
    proven = LeaseDrop(lease_id="L1", proof=drop_proof(CAP, "L1"))
    w._on_cancel(Sample(encode(Cancel(job_id="j1", leases=[proven]))))
    assert w._pending == {} and "L1" in w._dropped
    w._on_ack(Sample(b"garbage"))  # logged, ignored


def test_worker_heartbeats_running_leases():
    import time as _time

    from swarmpath.service.worker import _Active

    w = offline_worker()
    spec = BenchmarkCell(algorithm="PSO", function="F1", dim=2, agents=5, iterations=30)
    lease = make_lease(spec, [0, 1])
    slot = ThreadSlot(0, lambda *a: None)
    t = _time.monotonic()
    w._active[lease.lease_id] = _Active(lease, slot, t, t)
    assert w.heartbeat_due(t + 1) == 0
    assert w.heartbeat_due(t + 5.1) == 1  # half of heartbeat_seconds (10 s)
    key, payload = w._session.puts[-1]
    progress = decode(RunProgress, payload)
    assert key == "swarmpath/progress/j1" and progress.iterations == 30 and progress.runs == [0, 1]
    assert progress.seq == 1 and progress_ok(CAP, lease.lease_id, 1, progress.proof)
    assert CAP not in payload.decode()  # the secret itself never goes on the bus
    assert w.heartbeat_due(t + 6) == 0


# ------------------------------------------------------------------------- CLI, no network
@pytest.fixture
def cli(app, monkeypatch):
    """Run ``swarmpath ...`` in-process against the app (the client talks to TestClient)."""
    from typer.testing import CliRunner

    import swarmpath.cli.service as service_cli
    from swarmpath.cli import app as cli_app

    with TestClient(app) as c:
        monkeypatch.setattr(service_cli, "_client",
                            lambda url: ServiceClient("http://testserver", transport=c._transport))
        runner = CliRunner()
        yield lambda *args: runner.invoke(cli_app, list(args))


def one_error_line(result, command: str, named: str) -> None:
    assert result.exit_code == 2, (result.stdout, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"swarmpath {command}: error: "), lines
    assert named in lines[0] and "Traceback" not in result.stderr


def test_cli_client_commands(cli, tmp_path):
    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps(SPEC))
    result = cli("submit", str(spec))
    assert result.exit_code == 0, result.stderr
    job = result.stdout.strip()
    assert len(job) == 12
    status = cli("status", job)
    assert status.exit_code == 0 and job in status.stdout and "queued" in status.stdout
    listing = cli("status", "--json")
    assert json.loads(listing.stdout)["jobs"][0]["id"] == job
    contents = json.loads(listing.stdout)["jobs"][0]["contents"]  # what the job runs (issue 25)
    assert contents == "GWO, PSO x F1, F9 x D 3"  # SPEC
    assert contents in cli("status").stdout
    csv = cli("results", job, "--format", "csv")
    assert csv.exit_code == 0 and csv.stdout.startswith("algorithm,function,dim")
    table = cli("results", job)
    assert table.exit_code == 0 and "GWO" in table.stdout and "partial" in table.stdout
    early = cli("download", job, "-o", str(tmp_path / "x.mcap"))
    assert early.exit_code == 1 and "409" in early.stderr and "queued" in early.stderr
    assert early.stderr.startswith("swarmpath download: error: ")  # named like input errors


def test_cli_results_prints_markers_counts_and_friedman(cli, app, tmp_path):
    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps({**SPEC, "algorithms": ["GWO", "PSO", "COOT"], "reference": "gwo"}))
    job = cli("submit", str(spec)).stdout.strip()
    app.state.core.publish = Wire()
    assert work_off(app.state.core) == 30
    summary = json.loads(cli("results", job, "--format", "json").stdout)
    table = cli("results", job)
    assert table.exit_code == 0, table.stderr
    counts = summary["statistics"]["comparison"]["counts"]
    line = next(ln for ln in table.stdout.splitlines() if ln.startswith("+/=/- vs GWO: "))
    assert line == "+/=/- vs GWO: " + ", ".join(
        f"{a} {counts[a]['+']}/{counts[a]['=']}/{counts[a]['-']}" for a in ("PSO", "COOT"))
    assert "Friedman D=3 over 2 blocks: " in table.stdout
    assert "p_holm" in table.stdout and "a12" in table.stdout
    csv = cli("results", job, "--format", "csv").stdout.splitlines()
    assert csv[0].endswith("," + ",".join(TEST_COLUMNS)) and len(csv) == 1 + 6


def test_cli_bad_input_names_the_field(cli, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({**SPEC, "dims": [5000]}))
    one_error_line(cli("submit", str(bad)), "submit", "dims.0")
    bad.write_text("{nope")
    one_error_line(cli("submit", str(bad)), "submit", "SPEC.json")
    one_error_line(cli("submit", str(tmp_path / "missing.json")), "submit", "SPEC.json")
    one_error_line(cli("status", "nosuchjob"), "status", "JOB")
    one_error_line(cli("results", "nosuchjob", "--format", "xml"), "results", "--format")
    one_error_line(cli("worker", "--connect", "127.0.0.1:7447"), "worker", "--connect")
    one_error_line(cli("worker", "--slots", "0"), "worker", "--slots")
    one_error_line(cli("worker", "--max-leases", "0"), "worker", "--max-leases")
    one_error_line(cli("worker", "--max-leases", "1000"), "worker", "--max-leases")
    one_error_line(cli("worker", "--prefetch", "-1"), "worker", "--prefetch")
    one_error_line(cli("worker", "--id", "bad id!"), "worker", "--id")
    one_error_line(cli("coordinator", "--http", "nowhere"), "coordinator", "--http")
    data = tmp_path / "up-data"
    one_error_line(cli("up", "--zenoh", "tcp/127.0.0.1", "--data", str(data)), "up", "--zenoh")
    assert not data.exists()  # refused before the local login file is written


# ------------------------------------------------------------- bundles, group commit, prefetch
def test_lease_sizer_shrinks_leases_at_the_end_and_fills_bundles():
    sizer = LeaseSizer(target_seconds=10.0, min_runs=8)
    cell = BenchmarkCell(algorithm="GWO", function="F1", dim=30, agents=30, iterations=500)
    sizer.observe(cell, 0.05)
    assert sizer.runs_for(cell) == 200  # 10 s of 0.05 s runs
    assert sizer.runs_for(cell, remaining=10_000) == 200
    sizer.slots = 2
    assert sizer.runs_for(cell, remaining=400) == 100  # a quarter of what is left
    assert sizer.runs_for(cell, remaining=20) == 8  # never below the vectorization floor
    one = make_lease(cell, [0])
    assert sizer.runs_for(cell, remaining=10_000, bundle=[one] * 100) == 100
    assert sizer.runs_for(cell, remaining=10_000, bundle=[one] * 200) == 0  # bundle is full


def test_a_big_farm_gets_leases_of_at_least_its_slots_over_the_lease_rate():
    """The tail rule's leases shrink with the farm, but not below live slots / max_lease_rate
    seconds of work (the farm's lease rate is bounded), nor is that floor above the target."""
    sizer = LeaseSizer(target_seconds=10.0, min_runs=8, max_lease_rate=100.0)
    cell = BenchmarkCell(algorithm="GWO", function="F1", dim=30, agents=30, iterations=500)
    sizer.observe(cell, 0.005)
    sizer.slots = 2
    assert sizer.runs_for(cell, remaining=10_000) == 2000  # 10 s: the tail rule's 12.5 s
    sizer.slots = 200
    assert sizer.runs_for(cell, remaining=10_000) == 400  # 2 s, not the tail rule's 0.125 s
    assert sizer.runs_for(cell, remaining=100) == 400  # more than is left: the store clips it
    sizer.slots = 100_000
    assert sizer.runs_for(cell, remaining=10_000) == 2000  # the target's 10 s, not 1000 s
    no_floor = LeaseSizer(target_seconds=10.0, min_runs=8, max_lease_rate=float("inf"))
    no_floor.observe(cell, 0.005)
    no_floor.slots = 200
    assert no_floor.runs_for(cell, remaining=10_000) == 25  # the tail rule alone


def test_lease_bundles_and_group_commit(core, client):
    job = client.post("/jobs", json={**SPEC, "runs": 1}).json()["id"]  # 4 cells of one run
    core.worker_alive("w1")
    core.sizer.max_lease_rate = float("inf")  # the tail rule alone: these runs cost 0.3 ms
    request = encode(LeaseRequest(worker="w1", max_runs=100, max_leases=8, slots=1))
    bundles = [decode_work_reply(core.handle_lease_request(request)) for _ in range(3)]
    assert all(isinstance(b, LeaseBundle) for b in bundles)
    # one slot: each bundle takes half of the job's work left (the tail rule), at least a lease
    assert [[lease.cell_index for lease in b.leases] for b in bundles] == [[0, 1], [2], [3]]
    leases = [lease for b in bundles for lease in b.leases]
    results = [data for lease in leases for _r, data in execute_lease(lease)]
    first, second = (pack_batches("w1", results[:2])[0], pack_batches("w1", results[2:])[0])
    key = f"swarmpath/results/{job}"
    acks = core.handle_result_batches([(key, first), (key, b"garbage"), (key, second),
                                       (key, first)])
    assert acks[1] is None
    assert [s for _lease, _run, s in acks[0].statuses()] == ["accepted", "accepted"]
    assert [s for _lease, _run, s in acks[2].statuses()] == ["accepted", "accepted"]
    assert [s for _lease, _run, s in acks[3].statuses()] == ["duplicate", "duplicate"]
    assert client.get(f"/jobs/{job}").json()["state"] == "done"
    assert isinstance(lease_for(core), NoWork)
    single = decode_work_reply(core.handle_lease_request(encode(LeaseRequest(worker="w1"))))
    assert isinstance(single, NoWork)


def test_worker_prefetches_and_runs_bundles_in_one_slot(monkeypatch):
    import threading

    from swarmpath.service.worker import slots as slots_module

    # The slot's thread waits for ``release`` before computing: otherwise a fast thread can
    # finish the first bundle before the test looks at the slot (a race, not a feature).
    release = threading.Event()
    compute = slots_module.stacked_outcomes

    def gated(*args, **kwargs):
        assert release.wait(60)
        return compute(*args, **kwargs)

    monkeypatch.setattr(slots_module, "stacked_outcomes", gated)
    w = offline_worker(prefetch=1)
    done = threading.Event()
    original = w._on_slot_done

    def on_done(slot, outcomes):
        original(slot, outcomes)
        if not w._active:
            done.set()

    w._slots = [ThreadSlot(0, on_done)]
    assert w._wants_work()
    spec = BenchmarkCell(algorithm="PSO", function="F1", dim=2, agents=5, iterations=200)
    first = [make_lease(spec, [0]), make_lease(spec, [1]).model_copy(update={"lease_id": "L2"})]
    w._take(first)
    assert w._slots[0].busy and w._wants_work()  # one bundle running, room for one more
    w._take([make_lease(spec, [2]).model_copy(update={"lease_id": "L3"})])
    assert not w._wants_work() and len(w._queue) == 1
    assert w.heartbeat_due(w._active["L3"].received + 60) == 3  # queued leases renew too
    release.set()
    assert done.wait(60)
    puts = [frame_results(p) for k, p in w._session.puts if k == "swarmpath/results/j1"]
    assert [[r["lease_id"] for r in p] for p in puts] == [["L1", "L2"], ["L3"]]
    assert w._wants_work() and len(w._pending) == 3
    for slot in w._slots:
        slot.close()


def test_worker_forgets_a_dropped_lease_that_has_not_started():
    w = offline_worker()
    w._slots = [ThreadSlot(0, w._on_slot_done)]
    spec = BenchmarkCell(algorithm="PSO", function="F1", dim=2, agents=5, iterations=2000)
    w._take([make_lease(spec, [0])])
    w._take([make_lease(spec, [1]).model_copy(update={"lease_id": "L2"})])
    assert set(w._active) == {"L1", "L2"} and w._active["L2"].slot is None
    w._drop("L2")
    assert set(w._active) == {"L1"}
    w._drop("L1")  # running: cancelled in its slot
    w._slots[0].close(timeout=30)
    assert w._active == {} and w._pending == {}
