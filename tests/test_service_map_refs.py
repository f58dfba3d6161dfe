"""Real-size uploaded maps through the service: the upload (over the 1 MB limit of the other
routes), leases that name the scenario by its SHA-256 instead of carrying it, the worker's fetch
from the coordinator's ``scenarios/<sha256>`` queryable, its hash check and bounded cache, and
the refusals (a wrong hash, an unknown lease, a request not proven by the lease's holder) that
fail the runs with the reason instead of crashing the worker."""

from __future__ import annotations

import base64
import hashlib
import sys
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient

from swarmpath.planners import Episode
from swarmpath.service.http.app import create_app
from swarmpath.service.protocol import (
    INLINE_SCENARIO_BYTES,
    Keys,
    Lease,
    LeaseRequest,
    MapCell,
    ScenarioRequest,
    decode_work_reply,
    encode,
)
from swarmpath.service.result_columns import decode_columns
from swarmpath.service.result_frame import as_dict, decode_record
from swarmpath.service.scenarios import (
    ByteLRU,
    ScenarioRefused,
    ScenarioUnavailable,
    answer,
    canonical,
    request_proof,
    resolve,
)
from swarmpath.service.settings import CoordinatorSettings
from swarmpath.service.worker import execute_lease, pack_batches
from swarmpath.service.worker.execution import failed_lease
from swarmpath.world.scenario_io import scenario_from_dict

sys.path.insert(0, str(Path(__file__).parent))

YAML = ("image: pillars.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
START, GOAL = [3.75, 1.0], [3.75, 14.0]  # a pillar at (3.75, 3.75) and one at (3.75, 11.25)
PARAMS = {"OMPL-RRTstar": {"iterations": 300}}  # iteration-bound: reproducible


def pillars_pgm(width: int = 1500, height: int = 1200, spacing: int = 150) -> bytes:
    """A 1500 x 1200 nav2 PGM (1.8 MB, 75 x 60 m at 5 cm): a wall around, plus-shaped pillars
    every 7.5 m; imported it is 170 obstacles, about 35 KB of scenario JSON."""
    img = np.full((height, width), 254, dtype=np.uint8)
    img[0, :] = img[-1, :] = img[:, 0] = img[:, -1] = 0
    for cy in range(spacing // 2, height, spacing):
        for cx in range(spacing // 2, width, spacing):
            img[cy - 6:cy + 6, cx - 2:cx + 2] = 0
            img[cy - 2:cy + 2, cx - 6:cx + 6] = 0
    return f"P5\n{width} {height}\n255\n".encode() + img.tobytes()


def doc_hash(doc: dict) -> str:
    return hashlib.sha256(canonical(doc)).hexdigest()


def upload_body() -> dict:
    return {"name": "pillars", "format": "nav2", "yaml": YAML,
            "image": base64.b64encode(pillars_pgm()).decode()}


@pytest.fixture
def data_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    return tmp_path / "data"


def _lease(core, worker: str = "w1") -> Lease:
    core.worker_alive(worker)
    reply = decode_work_reply(core.handle_lease_request(
        encode(LeaseRequest(worker=worker, max_runs=10))))
    assert isinstance(reply, Lease), reply
    return reply


def _request(lease: Lease, sha256: str, worker: str | None = None,
             capability: str | None = None) -> bytes:
    return ScenarioRequest(
        worker=worker or lease.worker, lease_id=lease.lease_id,
        proof=request_proof(capability or lease.capability, lease.lease_id, sha256),
    ).model_dump_json().encode()


def test_a_large_scenario_travels_by_reference_and_is_refused_to_anyone_else(
        data_dir: Path) -> None:
    with TestClient(create_app(CoordinatorSettings(data_dir=data_dir), use_zenoh=False)) as c:
        up = c.post("/maps", json=upload_body())
        assert up.status_code == 201, up.text
        map_id = up.json()["id"]
        job = c.post("/jobs", json={"kind": "map", "planners": ["OMPL-RRTstar"], "runs": 2,
                                    "seed": 3, "params": PARAMS,
                                    "maps": [{"map": map_id, "start": START, "goal": GOAL}]})
        assert job.status_code == 201, job.text
        core = c.app.state.core  # type: ignore[attr-defined]
        core.publish = lambda key, payload: None
        lease = _lease(core)
        spec = lease.spec
        assert isinstance(spec, MapCell) and spec.scenario is None
        ref = spec.scenario_ref
        assert ref is not None and ref.bytes > INLINE_SCENARIO_BYTES
        assert len(encode(lease)) < 2_000  # the lease names the scenario, it does not carry it
        store, cache = core.store, ByteLRU(10_000_000)
        keys = Keys()
        key = keys.scenario(ref.sha256)

        def fetch(k: str, payload: bytes) -> bytes:
            return answer(k, payload, store.lease_scenario_ref, store.lease_scenario, cache)

        data = fetch(key, _request(lease, ref.sha256))
        assert hashlib.sha256(data).hexdigest() == ref.sha256 and len(data) == ref.bytes
        job_map = store.job_spec(job.json()["id"]).maps[0]
        assert canonical(job_map) == data  # exactly the job's scenario (start/goal applied)
        # refusals, each naming its reason
        other = keys.scenario("0" * 64)
        for k, payload, words in (
            (other, _request(lease, "0" * 64), "has no scenario"),
            (key, _request(lease, ref.sha256, worker="w2"), "not proven"),
            (key, _request(lease, ref.sha256, capability="1" * 64), "not proven"),
            (key, b"{not json", "malformed"),
            (key, ScenarioRequest(worker="w1", lease_id="nolease", proof="x")
             .model_dump_json().encode(), "unknown lease"),
        ):
            with pytest.raises(ScenarioRefused, match=words):
                fetch(k, payload)
        # the worker's side: fetched once, then from its bounded cache
        calls: list[str] = []

        def counting(k: str, payload: bytes) -> bytes:
            calls.append(k)
            return fetch(k, payload)

        worker_cache = ByteLRU(ref.bytes)  # room for exactly this one
        ready = resolve(lease, key, counting, worker_cache)
        assert isinstance(ready.spec, MapCell) and ready.spec.scenario == job_map
        assert resolve(lease, key, counting, worker_cache).spec == ready.spec
        assert calls == [key] and worker_cache.size == ref.bytes
        # ... and runs it exactly as a direct episode does (seed 3, runs 0 and 1)
        results = execute_lease(ready)
        scenario = scenario_from_dict(job_map)
        for run, payload in results:
            episode = Episode(scenario, "OMPL-RRTstar", 3, run, PARAMS["OMPL-RRTstar"])
            while not episode.done:
                episode.step()
            direct = episode.outcome()
            assert as_dict(decode_record(payload))["metrics"]["length"] == direct.length
        for payload in pack_batches("w1", [data for _run, data in results]):
            core.handle_results(f"swarmpath/results/{lease.job_id}", payload)
        runs = c.get(f"/jobs/{lease.job_id}/runs").json()["items"]
        assert sorted(r["run"] for r in runs if r["state"] == "done") == lease.runs


def test_a_wrong_hash_or_a_refusal_fails_the_runs_with_the_reason(data_dir: Path) -> None:
    with TestClient(create_app(CoordinatorSettings(data_dir=data_dir), use_zenoh=False)) as c:
        map_id = c.post("/maps", json=upload_body()).json()["id"]
        job = c.post("/jobs", json={"kind": "map", "planners": ["OMPL-RRTstar"], "runs": 1,
                                    "params": PARAMS, "maps": [{"map": map_id}]}).json()
        core = c.app.state.core  # type: ignore[attr-defined]
        core.publish = lambda key, payload: None
        lease = _lease(core)
        ref = lease.spec.scenario_ref  # type: ignore[union-attr]
        assert ref is not None
        key = Keys().scenario(ref.sha256)
        real = answer(key, _request(lease, ref.sha256), core.store.lease_scenario_ref,
                      core.store.lease_scenario, ByteLRU(1 << 24))
        tampered = real.replace(b'"start":[', b'"start":[0.5,0.5],"x":[', 1)

        def refuse(_k: str, _p: bytes) -> bytes:
            raise RuntimeError("refused: unknown lease")

        cache = ByteLRU(1 << 24)
        reasons = []
        for fetch, words in ((lambda k, p: tampered, "does not match its reference"),
                             (lambda k, p: real[:-1], "does not match its reference"),
                             (refuse, "did not send scenario")):
            with pytest.raises(ScenarioUnavailable, match=words) as exc:
                resolve(lease, key, fetch, cache)
            # the cell names the map as it was uploaded (its name, not the id)
            assert isinstance(lease.spec, MapCell) and lease.spec.map == "pillars"
            assert f"map {lease.spec.map}:" in str(exc.value)
            reasons.append(str(exc.value))
        assert cache.size == 0  # nothing unchecked is kept
        # the worker reports such a lease as failed runs with the reason (as Worker._take does)
        for payload in pack_batches("w1", [d for _r, d in failed_lease(lease, reasons[0])]):
            core.handle_results(f"swarmpath/results/{lease.job_id}", payload)
        run = c.get(f"/jobs/{job['id']}/runs").json()["items"][0]
        assert run["state"] == "failed"
        detail = c.get(f"/jobs/{job['id']}/runs/{run['run_id']}").json()
        assert "does not match its reference" in str(detail)


def test_byte_lru_keeps_the_most_recent_within_its_bytes() -> None:
    cache = ByteLRU(10)
    cache.put("a", b"aaaa")
    cache.put("b", b"bbbb")
    assert cache.get("a") == b"aaaa"  # a is now the most recent
    cache.put("c", b"cccc")  # 12 bytes: the least recent (b) goes
    assert cache.get("b") is None and cache.get("a") == b"aaaa" and cache.get("c") == b"cccc"
    assert cache.size == 8 and len(cache) == 2
    cache.put("huge", b"x" * 11)  # larger than the whole cache: not kept, nothing evicted
    assert cache.get("huge") is None and cache.size == 8


def test_a_real_size_map_job_through_a_coordinator_and_a_worker(tmp_path: Path) -> None:
    """Subprocesses on loopback (as in test_service_e2e): a 2.4 MB upload, a map job on it whose
    leases name the scenario by hash, the worker fetching it over Zenoh; every run done with the
    exact optimum's gap, and the very length a direct episode gives."""
    from test_service_e2e import Service

    svc = Service(tmp_path)
    try:
        svc.start_worker("w1")
        svc.start_coordinator()
        svc.wait_workers(["w1"])
        body = upload_body()
        up = svc.http_client.post("/maps", json=body)
        assert up.status_code == 201, up.text
        assert len(up.request.content) > 2_000_000
        job = svc.submit({"kind": "map", "planners": ["OMPL-RRTstar"], "runs": 2, "seed": 3,
                          "params": PARAMS,
                          "maps": [{"map": up.json()["id"], "start": START, "goal": GOAL}]})
        status = svc.wait_done(job, 300)
        assert status["state"] == "done" and status["runs_done"] == 2, status
        doc = svc.get(f"/maps/{up.json()['id']}").json()["scenario"] | {"start": START,
                                                                         "goal": GOAL}
        assert len(canonical(doc)) > INLINE_SCENARIO_BYTES  # so every lease named it by hash
        scenario = scenario_from_dict(doc)
        for item in svc.runs(job):
            m = svc.get(f"/jobs/{job}/runs/{item['run_id']}").json()
            episode = Episode(scenario, "OMPL-RRTstar", 3, item["run"], PARAMS["OMPL-RRTstar"])
            while not episode.done:
                episode.step()
            direct = episode.outcome()
            assert direct.optimum is not None
            assert m["state"] == "done" and m["success"] and m["collisions"] == 0
            assert m["length"] == direct.length and m["optimum"] == direct.optimum
            assert m["gap"] == pytest.approx((m["length"] - m["optimum"]) / m["optimum"])
        assert "refused a scenario request" not in svc.log("coordinator")
        # over the wire: a request for a lease nobody holds gets a reply error with the reason
        import zenoh

        from swarmpath.service.zenoh_config import client_config, to_zenoh

        session = zenoh.open(to_zenoh(client_config(svc.zenoh)))
        try:
            forged = ScenarioRequest(worker="w1", lease_id="made-up", proof="0" * 64)
            replies = list(session.get(Keys().scenario(doc_hash(doc)),
                                       payload=forged.model_dump_json().encode(), timeout=10.0))
        finally:
            session.close()
        assert [r.ok for r in replies] == [None]
        assert replies[0].err.payload.to_bytes() == b"unknown lease made-up"
        assert "refused a scenario request: unknown lease made-up" in svc.log("coordinator")
        assert svc.get("/healthz").status_code == 200
    finally:
        svc.close()


class _Payload:
    def __init__(self, data: bytes) -> None:
        self.payload = type("Z", (), {"to_bytes": lambda _self: data})()


class _Reply:
    def __init__(self, ok: bytes | None = None, err: bytes | None = None) -> None:
        self.ok = None if ok is None else _Payload(ok)
        self.err = None if err is None else _Payload(err)


class _Session:
    """The worker's Zenoh session, answered in process by the coordinator's own
    ``scenarios.answer`` (puts are kept)."""

    def __init__(self, core) -> None:
        self.core = core
        self.cache = ByteLRU(1 << 26)
        self.puts: list[tuple[str, bytes]] = []
        self.gets: list[str] = []

    def put(self, key: str, payload: bytes, **_kw) -> None:
        self.puts.append((key, payload))

    def get(self, key: str, payload: bytes, **_kw) -> list[_Reply]:
        self.gets.append(key)
        store = self.core.store
        try:
            return [_Reply(ok=answer(key, payload, store.lease_scenario_ref,
                                     store.lease_scenario, self.cache))]
        except ScenarioRefused as exc:
            return [_Reply(err=str(exc).encode())]


def test_the_worker_fails_a_lease_whose_scenario_is_refused_and_goes_on(data_dir: Path) -> None:
    """Worker._take: a lease naming a hash the coordinator does not have for it (a wrong hash,
    as for an unknown map) is reported at once as failed runs naming the refusal; the next lease
    is fetched, checked and queued for a slot with its scenario in place."""
    from types import SimpleNamespace

    from swarmpath.service.worker import Worker, WorkerSettings

    with TestClient(create_app(CoordinatorSettings(data_dir=data_dir), use_zenoh=False)) as c:
        map_id = c.post("/maps", json=upload_body()).json()["id"]
        c.post("/jobs", json={"kind": "map", "planners": ["OMPL-RRTstar"], "runs": 2,
                              "params": PARAMS, "maps": [{"map": map_id}]})
        core = c.app.state.core  # type: ignore[attr-defined]
        core.publish = lambda key, payload: None
        worker = Worker(WorkerSettings(worker_id="w1", max_runs=1))
        worker._session = session = _Session(core)
        worker._zenoh = SimpleNamespace(Encoding=SimpleNamespace(APPLICATION_JSON=None),
                                        CongestionControl=SimpleNamespace(BLOCK=None))
        good = _lease(core)
        wrong = _lease(core)
        spec = wrong.spec
        assert isinstance(spec, MapCell) and spec.scenario_ref is not None
        wrong = wrong.model_copy(update={"spec": spec.model_copy(update={
            "scenario_ref": spec.scenario_ref.model_copy(update={"sha256": "ab" * 32})})})
        worker._take([wrong])
        assert wrong.lease_id not in worker._active and not worker._queue
        (key, payload), = session.puts
        head = decode_columns(payload).head
        assert key.endswith(wrong.job_id) and head.lease_id == wrong.lease_id
        assert set(head.status) == {"failed"} and head.runs == wrong.runs
        failure = head.failure[0] or ""
        assert f"map {spec.map}: the coordinator did not send scenario" in failure
        assert "refused: lease" in failure and "has no scenario" in failure
        worker._take([good])
        (queued,), = worker._queue
        assert isinstance(queued.spec, MapCell) and queued.spec.scenario is not None
        assert worker.scenarios.size == good.spec.scenario_ref.bytes  # type: ignore[union-attr]
        assert session.gets == [Keys().scenario("ab" * 32),
                                Keys().scenario(good.spec.scenario_ref.sha256)]  # type: ignore


def test_an_expired_lease_is_answered_a_cancelled_one_refused_and_silence_fails_nothing(
        data_dir: Path) -> None:
    """Fencing accepts an expired lease's late results, so its holder still gets the scenario;
    a cancelled job's lease is refused; with no reply at all the worker reports nothing and
    leaves the lease to expire (its runs are leased again, not failed)."""
    from types import SimpleNamespace

    from swarmpath.service.worker import Worker, WorkerSettings

    with TestClient(create_app(CoordinatorSettings(data_dir=data_dir, lease_seconds=5.0),
                               use_zenoh=False)) as c:
        map_id = c.post("/maps", json=upload_body()).json()["id"]
        job = c.post("/jobs", json={"kind": "map", "planners": ["OMPL-RRTstar"], "runs": 2,
                                    "params": PARAMS, "maps": [{"map": map_id}]}).json()
        core = c.app.state.core  # type: ignore[attr-defined]
        core.publish = lambda key, payload: None
        lease = _lease(core)
        ref = lease.spec.scenario_ref  # type: ignore[union-attr]
        assert ref is not None
        key = Keys().scenario(ref.sha256)
        store = core.store

        def ask(held: Lease = lease) -> bytes:
            return answer(key, _request(held, ref.sha256), store.lease_scenario_ref,
                          store.lease_scenario, ByteLRU(1 << 24))

        store.requeue_expired(lease.deadline + 1.0)
        assert store.lease_scenario_ref(lease.lease_id)[2] == "expired"
        assert hashlib.sha256(ask()).hexdigest() == ref.sha256
        worker = Worker(WorkerSettings(worker_id="w1"))
        worker._session = session = _Session(core)
        session.get = lambda *_a, **_kw: []  # type: ignore[method-assign]  # nobody answers
        worker._zenoh = SimpleNamespace(Encoding=SimpleNamespace(APPLICATION_JSON=None),
                                        CongestionControl=SimpleNamespace(BLOCK=None))
        worker._take([lease])
        assert session.puts == [] and not worker._queue and lease.lease_id not in worker._active
        again = _lease(core)  # the expired lease's runs, leased again
        assert again.lease_id != lease.lease_id and again.runs == lease.runs
        assert c.delete(f"/jobs/{job['id']}").status_code == 200
        with pytest.raises(ScenarioRefused, match="is cancelled"):
            ask(again)
