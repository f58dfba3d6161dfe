"""The dashboard's routes and live state without a browser: pages and static files, the jobs
snapshot (rate, ETA), aggregates fed on accept equal to aggregates built from the store, ETags,
scenes and their errors, the events stream."""

from __future__ import annotations

import json

import pytest
from fastapi.testclient import TestClient

from swarmpath.functions.transforms import TRANSFORMS
from swarmpath.service.coordinator import CoordinatorSettings, create_app
from swarmpath.service.http.routes import dashboard as dashboard_routes
from swarmpath.service.http.routes.pages import ASSETS
from swarmpath.service.protocol import Lease, LeaseRequest, decode_work_reply, encode
from swarmpath.service.web.live import Dashboard
from swarmpath.service.worker import execute_lease, pack_batches

BENCH = {"kind": "benchmark", "algorithms": ["GWO", "PSO"], "functions": ["F1"], "dims": [2],
         "runs": 4, "agents": 5, "iterations": 15}


@pytest.fixture
def app(tmp_path, monkeypatch):
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    return create_app(CoordinatorSettings(data_dir=tmp_path / "data"), use_zenoh=False)


@pytest.fixture
def client(app):
    with TestClient(app) as c:
        yield c


def work_off(core, worker="w1"):
    core.worker_alive(worker)
    while isinstance(lease := decode_work_reply(core.handle_lease_request(
            encode(LeaseRequest(worker=worker, max_runs=100)))), Lease):
        for payload in pack_batches(worker, [d for _r, d in execute_lease(lease)]):
            core.handle_results(f"swarmpath/results/{lease.job_id}", payload)


@pytest.mark.parametrize("path", ["/", "/ui/jobs/abc", "/ui/jobs/abc/runs/3", "/ui/workers",
                                  "/ui/submit"])
def test_pages_are_html_that_loads_only_shipped_assets(client, path):
    r = client.get(path)
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/html")
    for src in ("/static/common.js", "/static/plot.js", "/static/style.css"):
        assert src in r.text
        assert client.get(src).status_code == 200
    assert "http://" not in r.text and "https://" not in r.text  # nothing from a CDN


def test_static_files_are_a_whitelist(client):
    assert set(ASSETS) >= {"plot.js", "common.js", "style.css", "jobs.js", "job.js"}
    for name in ASSETS:
        assert client.get(f"/static/{name}").status_code == 200
    for bad in ("../pages.py", "..%2Fpages.py", "pages.py", "nope.js"):
        assert client.get(f"/static/{bad}").status_code == 404


def test_jobs_snapshot_rate_eta_and_config(client, app):
    core = app.state.core
    job = client.post("/jobs", json=BENCH).json()["id"]
    snap = client.get("/ui/jobs").json()
    (item,) = snap["jobs"]
    assert item["id"] == job and item["progress"] == 0.0 and item["eta"] is None
    work_off(core)
    core.dashboard._snapshot = (-1.0, b"")  # the snapshot is shared for 0.5 s
    (item,) = client.get("/ui/jobs").json()["jobs"]
    assert item["state"] == "done" and item["progress"] == 1.0 and item["eta"] is None
    assert core.dashboard.rate(job) > 0
    cfg = client.get("/ui/config").json()
    assert cfg["token_required"] is False
    assert cfg["defaults"]["benchmark"]["runs"] == 30 and cfg["defaults"]["map"]["runs"] == 10
    assert cfg["transforms"] == list(TRANSFORMS) and cfg["defaults"]["benchmark"]["transform"] == (
        "none"
    )


def test_eta_from_the_rate_of_a_running_job(tmp_path):
    from swarmpath.service.protocol import parse_job_spec
    from swarmpath.service.store import Store

    store = Store(tmp_path)
    try:
        job = store.create_job(parse_job_spec(BENCH))
        dash = Dashboard(store)

        class R:  # the fields observe() reads of a RunResult
            def __init__(self, run):
                self.cell, self.run, self.status, self.metrics = "GWO/F1/2", run, "ok", {}
                self.curve = self.path = None

        store.lease("w1", 100, now=100.0)  # the job is running
        dash.observe(job, [R(0), R(1)], now=100.0)
        dash.observe(job, [R(2)], now=110.0)
        assert dash.rate(job, now=110.0) == pytest.approx(3 / 10)
        (item,) = json.loads(dash.jobs_snapshot(now=110.0))["jobs"]
        assert item["state"] == "running" and item["rate"] == pytest.approx(0.3)
        assert item["eta"] == pytest.approx(8 / 0.3, abs=0.1)  # the store has no results: 8 left
        assert dash.rate(job, now=1000.0) == 0.0  # the window has passed
    finally:
        store.close()


def test_aggregates_fed_on_accept_equal_those_built_from_the_store(client, app, monkeypatch):
    from swarmpath.service.web import live

    monkeypatch.setattr(live, "VIEW_SECONDS", 0.0)  # no sharing of a young view here
    core = app.state.core
    job = client.post("/jobs", json=BENCH).json()["id"]
    r = client.get(f"/ui/jobs/{job}/data")
    assert r.status_code == 200 and r.json()["finished"] == 0
    work_off(core)
    live = client.get(f"/ui/jobs/{job}/data")
    etag = live.headers["etag"]
    assert live.json()["finished"] == 8 and live.json()["loading"] is False
    assert client.get(f"/ui/jobs/{job}/data", headers={"If-None-Match": etag}).status_code == 304
    cold = Dashboard(core.store).aggregates(job)  # as after a restart
    assert cold is not None
    assert json.loads(json.dumps(cold.view(), default=str)) == json.loads(
        json.dumps(core.dashboard.aggregates(job).view(), default=str))
    group = live.json()["groups"][0]
    assert set(group["algorithms"]) == {"GWO", "PSO"}
    assert live.json()["statistics"]["reference"] == "PSO"
    assert client.get("/ui/jobs/nope/data").status_code == 404


def test_scene_routes(client, app):
    core = app.state.core
    bench = client.post("/jobs", json=BENCH).json()["id"]
    assert client.get(f"/ui/jobs/{bench}/scene?cell=0").status_code == 404  # no map
    spec = {"kind": "map", "planners": ["MFB"], "maps": ["mfb-dynamic"], "runs": 1, "seed": 2}
    job = client.post("/jobs", json=spec).json()["id"]
    assert client.get(f"/ui/jobs/{job}/scene").status_code == 422
    assert client.get(f"/ui/jobs/{job}/scene?cell=0&run=0").status_code == 422
    assert client.get(f"/ui/jobs/{job}/scene?cell=5").status_code == 404
    assert client.get(f"/ui/jobs/{job}/scene?run=5").status_code == 404
    s = client.get(f"/ui/jobs/{job}/scene?cell=0&t_end=5").json()
    assert s["dynamic"] and s["motion"]["times"] == []  # no run yet: no track to show
    assert (s["frame"], s["origin"]) == ("scenario", [0.0, 0.0])  # a preset has no other frame
    work_off(core)
    s = client.get(f"/ui/jobs/{job}/scene?cell=0&t_end=5").json()
    assert s["motion"]["offsets"] and s["motion"]["times"][-1] == 5.0
    s = client.get(f"/ui/jobs/{job}/scene?run=0&t_end=1000000").json()  # hostile t_end
    path = core.store.run(job, 0)["path"]
    assert s["run"] == 0 and s["motion"]["times"][-1] == pytest.approx(path[-1][2], abs=1e-3)


def test_events_stream_pushes_the_jobs_list(client, app, monkeypatch):
    monkeypatch.setattr(dashboard_routes, "STREAM_SECONDS", 0.5)  # the stream ends by itself
    job = client.post("/jobs", json=BENCH).json()["id"]
    with client.stream("GET", "/events") as r:
        assert r.headers["content-type"].startswith("text/event-stream")
        text = "".join(r.iter_text())
    assert text.startswith("retry: 1000")
    events = [block for block in text.split("\n\n") if block.startswith("event: jobs")]
    assert len(events) == 1  # nothing changed afterwards: not sent again
    data = json.loads(events[0].split("data: ", 1)[1])
    assert [j["id"] for j in data["jobs"]] == [job]


def test_finished_jobs_aggregates_are_saved_and_reloaded(client, app, tmp_path):
    core = app.state.core
    job = client.post("/jobs", json=BENCH).json()["id"]
    spec = {"kind": "map", "planners": ["MFB"], "maps": ["mfb-static"], "runs": 1, "seed": 2}
    map_job = client.post("/jobs", json=spec).json()["id"]
    work_off(core)
    core.tick()  # finalizes the jobs: their aggregates are saved
    for j in (job, map_job):
        saved = core.dashboard.cache_dir / f"{j}.npz"
        assert saved.is_file()
        page = Dashboard(core.store, core.dashboard.cache_dir)  # after a restart: the saved
        assert content(page.page_data(j)[1]) == content(core.dashboard.page_data(j)[1])
        assert page.aggregates_loaded() == []  # page, the arrays not loaded
        fresh = Dashboard(core.store, core.dashboard.cache_dir)
        reloaded = fresh.aggregates(j)
        assert content(json.dumps(reloaded.view(), default=str)) == content(
            json.dumps(core.dashboard.aggregates(j).view(), default=str))
    # a file that does not match the store is ignored: the store is read again
    other = tmp_path / "other"
    other.mkdir()
    (core.dashboard.cache_dir / f"{job}.npz").replace(other / f"{map_job}.npz")
    again = Dashboard(core.store, other).aggregates(map_job)
    assert again.view()["kind"] == "map" and again.finished_runs() == 1


def content(page: bytes | str) -> dict:
    """A page's data without its version (a counter of changes, not content)."""
    data = json.loads(page)
    data.pop("version")
    return data


class _Result:
    """The fields Dashboard.observe reads of a RunResult."""

    def __init__(self, cell: str, run: int):
        self.cell, self.run, self.status = cell, run, "ok"
        self.metrics = {"best_fitness": float(run)}
        self.curve = self.path = None


def test_observe_never_waits_for_a_build_from_the_store(tmp_path, monkeypatch):
    import threading

    from swarmpath.service.protocol import parse_job_spec
    from swarmpath.service.store import Store

    store = Store(tmp_path)
    try:
        job = store.create_job(parse_job_spec(BENCH))
        release = threading.Event()
        reading = threading.Event()

        def slow_records(job_id, batch=500):  # a store scan that takes as long as we like
            reading.set()
            release.wait(30)
            yield {"cell_index": 0, "run": 0, "status": "ok", "metrics": {"best_fitness": 0.0}}

        monkeypatch.setattr(store, "iter_run_records", slow_records)
        from swarmpath.service.web import live

        monkeypatch.setattr(live, "VIEW_SECONDS", 0.0)  # no sharing of a young view here
        dash = Dashboard(store)
        page = threading.Thread(target=dash.aggregates, args=(job,))
        page.start()  # a page asks first: it builds (and blocks in the scan)
        assert reading.wait(30)
        dash.observe(job, [_Result("GWO/F1/2", 0), _Result("GWO/F1/2", 1)])  # returns at once
        agg = dash.aggregates(job, wait=False)
        assert agg is not None and agg.finished_runs() == 2
        _version, body = dash.page_data(job)  # a page does not wait either: it says "loading"
        assert json.loads(body)["loading"] is True
        release.set()
        page.join(30)
        assert dash.aggregates(job).finished_runs() == 2  # run 0 once, not twice
        assert json.loads(dash.page_data(job)[1])["loading"] is False
    finally:
        store.close()


def test_eviction_keeps_running_jobs_before_ended_ones(tmp_path):
    from swarmpath.service.protocol import parse_job_spec
    from swarmpath.service.store import Store

    store = Store(tmp_path)
    try:
        ids = [store.create_job(parse_job_spec({**BENCH, "seed": s})) for s in range(4)]
        dash = Dashboard(store, max_jobs=2)
        dash.aggregates(ids[0])
        dash.aggregates(ids[1])
        dash.finished(ids[1])  # ended: goes first although used more recently
        dash.aggregates(ids[2])
        assert dash.aggregates_loaded() == [ids[0], ids[2]]
        dash.aggregates(ids[3])  # nothing ended left: the least recently used goes
        assert dash.aggregates_loaded() == [ids[2], ids[3]]
    finally:
        store.close()


def test_closing_the_coordinator_stops_a_running_build_without_an_error(tmp_path, monkeypatch,
                                                                         caplog):
    import logging
    import threading
    import time

    from swarmpath.service.coordinator import Coordinator
    from swarmpath.service.protocol import parse_job_spec
    from swarmpath.service.store import StoreError

    core = Coordinator(CoordinatorSettings(data_dir=tmp_path / "data"))
    job = core.submit(parse_job_spec(BENCH)).id
    reading = threading.Event()

    def endless_records(job_id, batch=500):  # a long scan: fails once the store is closed
        run = 0
        while True:
            if core.store._closed:
                raise StoreError("store is closed")
            reading.set()
            yield {"cell_index": 0, "run": run % 4, "status": "ok",
                   "metrics": {"best_fitness": 0.0}}
            run += 1
            time.sleep(0.001)

    monkeypatch.setattr(core.store, "iter_run_records", endless_records)
    core.dashboard.aggregates(job, wait=False)  # builds in a thread
    assert reading.wait(30)
    builds = [t for t in threading.enumerate() if t.name == f"dashboard-{job}"]
    assert builds
    with caplog.at_level(logging.INFO, logger="swarmpath"):
        core.close()
    assert not any(t.is_alive() for t in builds)
    assert not [r for r in caplog.records if r.levelno >= logging.ERROR]


def test_a_jobs_first_results_are_not_read_back_from_the_store(client, app, monkeypatch):
    """The aggregates of a job whose first results were just stored start from those results
    (nothing read back); a dashboard that lost a running job reads the store again."""
    core = app.state.core
    dash = core.dashboard
    reads: list[str] = []
    build = dash._build

    def counted(job, *args):  # a build reads the job's finished runs from the store
        reads.append(job.job_id)
        return build(job, *args)

    monkeypatch.setattr(dash, "_build", counted)
    job = client.post("/jobs", json={**BENCH, "runs": 20}).json()["id"]
    core.worker_alive("w1")

    def one_lease() -> int:
        lease = decode_work_reply(core.handle_lease_request(
            encode(LeaseRequest(worker="w1", max_runs=5))))
        assert isinstance(lease, Lease)
        for payload in pack_batches("w1", [d for _run, d in execute_lease(lease)]):
            core.handle_results(f"swarmpath/results/{job}", payload)
        return len(lease.runs)

    first = one_lease()
    assert reads == [] and dash.aggregates(job).finished_runs() == first
    del dash._jobs[job]  # evicted while running: the next batch rebuilds it
    second = one_lease()
    assert dash.aggregates(job).finished_runs() == first + second and reads == [job]


RACED = {"kind": "benchmark", "algorithms": ["PSO", "GWO"], "functions": ["F10"], "dims": [5],
         "runs": 60, "agents": 8, "iterations": 30, "seed": 3,
         "racing": {"min_runs": 10, "batch": 10}}


def test_a_raced_job_page_holds_every_run_the_race_gives(client, app, monkeypatch):
    """The page is opened when each cell may have 10 runs (the first round); the race then gives
    them more, up to the job's runs: every finished run is on the page, fed live and built from
    the store, and the page says the job races (the job page then shows GET /jobs/{id}/race)."""
    from swarmpath.service.web import live

    monkeypatch.setattr(live, "VIEW_SECONDS", 0.0)
    core = app.state.core
    job = client.post("/jobs", json=RACED).json()["id"]
    first = client.get(f"/ui/jobs/{job}/data").json()
    assert first["racing"] is True and first["finished"] == 0
    work_off(core)
    status = client.get(f"/jobs/{job}").json()
    race = client.get(f"/jobs/{job}/race").json()
    runs = {c["algorithm"]: c["runs"] for c in race["blocks"][0]["cells"]}
    assert status["state"] == "done" and max(runs.values()) > 10  # the race went past round 0
    data = client.get(f"/ui/jobs/{job}/data").json()
    assert data["finished"] == status["runs_done"] == sum(runs.values())
    for a, cell in data["groups"][0]["algorithms"].items():
        assert cell["runs"] == runs[a]
    cold = Dashboard(core.store).aggregates(job)  # as after a restart
    assert cold is not None and cold.finished_runs() == sum(runs.values())
    assert cold.view()["racing"] is True
    plain = client.post("/jobs", json={k: v for k, v in RACED.items() if k != "racing"}).json()
    assert client.get(f"/ui/jobs/{plain['id']}/data").json()["racing"] is False


def test_the_submit_pages_pairs_picker_reads_its_limit_and_the_maps_pairs(client):
    """What the submit page's .scen upload and pairs picker talk to, without a browser: the
    page loads pairs.js; /ui/config gives the pairs one map entry may name; the upload body the
    page sends (a .map with its .scen) is imported and GET /maps (the page's list) reports its
    pairs per bucket; the three choices the picker builds (every pair as rows, a range of rows,
    pairs per bucket beside a preset) are the job spec POST /jobs takes, and a bad one is a 422
    at the entry's index (the page puts it in that map's picker)."""
    from pathlib import Path

    from swarmpath.service.jobspec_map import MAX_SCEN_PAIRS_PER_MAP

    page = client.get("/ui/submit").text
    assert page.index("/static/pairs.js") < page.index("/static/submit.js")
    js = client.get("/static/pairs.js")
    assert js.status_code == 200 and js.headers["content-type"].startswith("text/javascript")
    assert client.get("/ui/config").json()["limits"] == {
        "scen_pairs_per_map": MAX_SCEN_PAIRS_PER_MAP}
    data = Path(__file__).parent / "data"
    up = client.post("/maps", json={"name": "arena", "format": "movingai", "resolution": 1,
                                    "map": (data / "arena.map").read_text(),
                                    "scen": (data / "arena.map.scen").read_text()})
    assert up.status_code == 201, up.text
    map_id = up.json()["id"]
    (listed,) = client.get("/maps?limit=1000").json()
    assert listed["scen"] == {"pairs": 160, "buckets": {str(b): 10 for b in range(16)}}
    store = client.app.state.core.store
    for choice, names in (
            ({"rows": list(range(160))}, [f"arena#{k}" for k in range(160)]),
            ({"rows": [5, 6, 7]}, ["arena#5", "arena#6", "arena#7"]),
            ({"buckets": [0, 15], "per_bucket": 2}, ["arena#0", "arena#1", "arena#150",
                                                     "arena#151"])):
        r = client.post("/jobs", json={"kind": "map", "planners": ["MFB"], "runs": 1,
                                       "maps": ["mfb-static", {"map": map_id, "scen": choice}]})
        assert r.status_code == 201, r.text
        assert r.json()["runs_total"] == 1 + len(names)
        spec = store.job_spec(r.json()["id"])
        assert [m if isinstance(m, str) else m["name"] for m in spec.maps] == [
            "mfb-static", *names]
        assert spec.buckets == {n: int(n.split("#")[1]) // 10 for n in names}
    r = client.post("/jobs", json={"kind": "map", "planners": ["MFB"], "runs": 1, "maps": [
        "mfb-static", {"map": map_id, "scen": {"rows": [159, 160]}}]})
    assert r.status_code == 422
    assert r.json()["detail"][0]["loc"] == ["body", "maps", 1, "scen", "rows", 1]
