"""The service end to end: a coordinator and workers as subprocesses on free loopback ports.

One coordinator (and its data directory) serves the whole module, in this order: results equal a
direct ``minimize``; malformed REST requests; garbage on the Zenoh keys; a worker SIGKILLed while
it holds a lease; a map job; the coordinator SIGKILLed mid-job and restarted on the same data dir.
Every process is started in its own session and killed (with its slot children) at teardown.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import textwrap
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from mcap.reader import make_reader

import owned
from swarmpath.optimizers import minimize

sys.path.insert(0, str(Path(__file__).parent))
from test_mcap_foxglove_reader import accepted, check_common, topics

PY = sys.executable
ROOT = Path(__file__).resolve().parents[1]
ENV = {**os.environ, "PYTHONPATH": str(ROOT / "services"), "PYTHONUNBUFFERED": "1"}
ENV.pop("SWARMPATH_TOKEN", None)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def stop_group(proc: subprocess.Popen[bytes], grace: float = 30.0) -> None:
    """Stop a process started in its own session (``start_new_session=True``) and everything it
    started: SIGTERM to its group, SIGKILL after ``grace`` seconds."""
    if proc.poll() is not None:
        return
    with contextlib.suppress(ProcessLookupError):
        os.killpg(proc.pid, signal.SIGTERM)
    try:
        proc.wait(grace)
    except subprocess.TimeoutExpired:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(10)


class Service:
    """A coordinator and its workers, as subprocesses; logs under ``tmp``."""

    def __init__(self, tmp: Path, insecure: bool = True):
        self.tmp = tmp
        tmp.mkdir(parents=True, exist_ok=True)
        # the coordinator without a Zenoh login (--insecure): these tests put a hostile client
        # on an open bus; tests/test_service_identity.py runs the default, with logins
        self.insecure = insecure
        self.login = not insecure  # workers log in with the login the coordinator made
        self.data = tmp / "data"
        self.http = free_port()
        self.zport = free_port()
        self.url = f"http://127.0.0.1:{self.http}"
        self.zenoh = f"tcp/127.0.0.1:{self.zport}"
        self.coordinator: subprocess.Popen[bytes] | None = None
        self.workers: dict[str, subprocess.Popen[bytes]] = {}
        self.http_client = httpx.Client(base_url=self.url, timeout=30.0)
        self._logs: list[Any] = []
        self.starts = 0

    def _spawn(self, name: str, args: list[str]) -> subprocess.Popen[bytes]:
        log = open(self.tmp / f"{name}.log", "ab")  # closed at teardown
        self._logs.append(log)
        return owned.popen([PY, "-m", "swarmpath.cli", *args], stdout=log, stderr=log,
                           env=ENV)

    def start_coordinator(self, lease_seconds: float = 20.0) -> None:
        self.starts += 1
        self.coordinator = self._spawn("coordinator", [
            "coordinator", "--http", f"127.0.0.1:{self.http}", "--zenoh", self.zenoh,
            "--data", str(self.data), "--lease-seconds", str(lease_seconds),
            *(["--insecure"] if self.insecure else []),
        ])
        self.wait_for(lambda: self.get("/healthz").status_code == 200, 60, "coordinator up")

    def start_worker(self, name: str, *extra: str) -> None:
        login = ["--login-file", str(self.data / "zenoh-users.txt")] if self.login else []
        self.workers[name] = self._spawn(name, [
            "worker", "--connect", self.zenoh, "--id", name, "--grace", "2", *login, *extra,
        ])

    def wait_workers(self, names: list[str], timeout: float = 60.0) -> None:
        def alive() -> bool:
            seen = {w["id"] for w in self.get("/workers").json() if w["alive"]}
            return set(names) <= seen
        self.wait_for(alive, timeout, f"workers {names} alive")

    def get(self, path: str, **kw: Any) -> httpx.Response:
        try:
            return self.http_client.get(path, **kw)
        except httpx.TransportError:
            return httpx.Response(599)

    def submit(self, spec: dict[str, Any]) -> str:
        r = self.http_client.post("/jobs", json=spec)
        assert r.status_code == 201, r.text
        return r.json()["id"]

    def status(self, job: str) -> dict[str, Any]:
        r = self.get(f"/jobs/{job}")
        return r.json() if r.status_code == 200 else {"state": "?", "runs_done": -1}

    def wait_done(self, job: str, timeout: float) -> dict[str, Any]:
        self.wait_for(lambda: self.status(job)["state"] in ("done", "failed", "cancelled"),
                      timeout, f"job {job} finished")
        return self.status(job)

    def wait_for(self, cond: Any, timeout: float, what: str) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.coordinator is not None and self.coordinator.poll() is not None:
                raise AssertionError(f"coordinator exited ({self.coordinator.returncode}) "
                                     f"waiting for {what}:\n{self.log('coordinator')[-3000:]}")
            with contextlib.suppress(httpx.HTTPError, ValueError, KeyError):
                if cond():
                    return
            time.sleep(0.1)
        raise AssertionError(f"timed out waiting for {what}:\n{self.log('coordinator')[-3000:]}")

    def runs(self, job: str) -> list[dict[str, Any]]:
        return self.get(f"/jobs/{job}/runs", params={"limit": 1000}).json()["items"]

    def mcap_results(self, job: str) -> list[dict[str, Any]]:
        r = self.get(f"/jobs/{job}/mcap")
        assert r.status_code == 200, r.text
        reader = make_reader(io.BytesIO(r.content))
        return [json.loads(m.data) for _s, _c, m in reader.iter_messages(topics=["/results"])]

    def log(self, name: str) -> str:
        path = self.tmp / f"{name}.log"
        return path.read_text(errors="replace") if path.exists() else ""

    def kill(self, proc: subprocess.Popen[bytes] | None) -> None:
        if proc is not None and proc.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(10)

    def close(self) -> None:
        for proc in self.workers.values():
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
        for proc in self.workers.values():
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(10)
            self.kill(proc)
        if self.coordinator is not None and self.coordinator.poll() is None:
            self.coordinator.send_signal(signal.SIGTERM)
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.coordinator.wait(15)
        self.kill(self.coordinator)
        self.http_client.close()
        for log in self._logs:
            log.close()


@pytest.fixture(scope="module")
def service(tmp_path_factory) -> Iterator[Service]:
    svc = Service(tmp_path_factory.mktemp("service"))
    try:
        svc.start_worker("w1")  # before the coordinator: workers wait for it
        svc.start_worker("w2")
        svc.start_coordinator()
        svc.wait_workers(["w1", "w2"])
        yield svc
    finally:
        svc.close()


def check_complete(svc: Service, job: str, total: int) -> None:
    """Exactly one result per run, in the store, the summary and the MCAP."""
    runs = svc.runs(job)
    assert [r["run_id"] for r in runs] == list(range(total))
    assert all(r["state"] == "done" for r in runs), [r for r in runs if r["state"] != "done"]
    summary = svc.get(f"/jobs/{job}/summary").json()
    assert sum(row["runs"] for row in summary["rows"]) == total and not summary["partial"]
    ids = [m["run_id"] for m in svc.mcap_results(job)]
    assert sorted(ids) == list(range(total))  # one /results message per run, none twice


BENCH = {"kind": "benchmark", "algorithms": ["GWO", "PSO"], "functions": ["F1", "F9"],
         "dims": [5], "runs": 10, "agents": 12, "iterations": 60, "seed": 11}


def bench_job(service: Service) -> str:
    """The BENCH job (submitted by the first test; again when a test runs alone)."""
    if not hasattr(service, "bench_job"):
        service.bench_job = service.submit(BENCH)
    return service.bench_job


def test_benchmark_results_equal_direct_minimize(service):
    job = bench_job(service)
    status = service.wait_done(job, 60)
    assert status["state"] == "done" and status["runs_done"] == 40
    runs = service.runs(job)
    for a in BENCH["algorithms"]:
        for f in BENCH["functions"]:
            direct = minimize(a, f, 5, 12, 60, runs=10, seed=11)
            got = [r for r in runs if r["algorithm"] == a and r["function"] == f]
            assert [r["run"] for r in got] == list(range(10))
            assert [r["best_fitness"] for r in got] == direct.best_fitness.tolist()
            assert [r["evaluations"] for r in got] == direct.evaluations.tolist()
    one = service.get(f"/jobs/{job}/runs/3").json()
    assert one["curve"] == minimize("GWO", "F1", 5, 12, 60, seed=11, run_ids=[3]).curve[0].tolist()
    check_complete(service, job, 40)
    assert {r["worker"] for r in runs} <= {"w1", "w2"}


def test_mcap_reads_back_with_one_result_per_run(service, tmp_path):
    job = bench_job(service)
    service.wait_done(job, 60)
    r = service.get(f"/jobs/{job}/mcap")
    reader = make_reader(io.BytesIO(r.content))
    summary = reader.get_summary()
    assert summary is not None and summary.statistics.message_count > 0
    topics = {c.topic for c in summary.channels.values()}
    assert {"/results", "/curves"} <= topics
    results = [json.loads(m.data) for _s, _c, m in reader.iter_messages(topics=["/results"])]
    assert len(results) == 40 and len({m["run_id"] for m in results}) == 40
    meta = {m.name: m.metadata for m in reader.iter_metadata()}
    assert json.loads(meta["swarmpath.job"]["spec"])["seed"] == 11
    assert meta["swarmpath.summary"]["state"] == "done"
    passes_foxglove_reader(r.content, tmp_path, {"/results": 40, "/curves": 40})


def passes_foxglove_reader(data: bytes, tmp_path: Path, counts: dict[str, int]) -> None:
    """The served file also passes @mcap/core (when Node.js is here; its own tests need it)."""
    if shutil.which("node") is None:
        return
    path = tmp_path / "served.mcap"
    path.write_bytes(data)
    report = accepted(path)
    check_common(report)
    by_topic = topics(report)
    assert {t: by_topic[t]["messages"] for t in counts} == counts


def test_cli_submit_wait_and_download(service, tmp_path):
    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps({**BENCH, "functions": ["F5"], "runs": 4}))
    env = {**ENV, "SWARMPATH_URL": service.url}
    cli = [PY, "-m", "swarmpath.cli"]
    done = subprocess.run([*cli, "submit", str(spec), "--wait"], env=env, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    job = done.stdout.strip()
    assert "done (8 done, 0 failed)" in done.stderr
    out = tmp_path / "job.mcap"
    got = subprocess.run([*cli, "download", job, "-o", str(out)], env=env, capture_output=True,
                         text=True, timeout=60)
    assert got.returncode == 0, got.stderr
    assert out.read_bytes()[:8] == b"\x89MCAP0\r\n"


def test_malformed_requests_are_422_naming_the_field(service):
    c = service.http_client
    for change, field in (({"dims": [5000]}, "dims"), ({"algorithms": ["NOPE"]}, "algorithms"),
                          ({"runs": 0}, "runs"), ({"agents": 5000}, "agents")):
        r = c.post("/jobs", json={**BENCH, **change})
        assert r.status_code == 422
        assert any(field in d["loc"] for d in r.json()["detail"]), r.json()
    r = c.post("/jobs", content=b"x" * 1_000_001, headers={"content-type": "application/json"})
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["body"]
    assert service.get("/jobs/doesnotexist").status_code == 404


def test_a_request_for_another_host_name_is_refused(service):
    """DNS rebinding (issue 25, failure 6): `swarmpath coordinator` on 127.0.0.1 answers its own
    names only; a page of evil.example rebound to 127.0.0.1 sends ``Host: evil.example``."""
    c = service.http_client
    before = len(c.get("/jobs").json())
    r = c.post("/jobs", json=BENCH, headers={"Host": f"evil.example:{service.http}"})
    assert r.status_code == 400 and "--allowed-host" in r.json()["detail"], r.text
    assert len(c.get("/jobs").json()) == before
    for host in (f"localhost:{service.http}", f"127.0.0.1:{service.http}"):
        assert service.get("/healthz", headers={"Host": host}).status_code == 200
    assert c.get("/").headers["content-security-policy"].startswith("default-src 'self'")


GARBAGE = textwrap.dedent("""
    import json, sys, time, zenoh
    endpoint, job = sys.argv[1], sys.argv[2]
    conf = {"mode": "client", "connect": {"endpoints": [endpoint]}, "listen": {"endpoints": []},
            "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": False}},
            "transport": {"shared_memory": {"enabled": False}}}
    s = zenoh.open(zenoh.Config.from_json5(json.dumps(conf)))
    block = zenoh.CongestionControl.BLOCK
    for key in (f"swarmpath/results/{job}", "swarmpath/results/nojob", f"swarmpath/progress/{job}"):
        for payload in (b"", b"not json", b"\\xff\\xfe", b"[]", b'{"worker": "x"}',
                        b'{"worker": "w9", "results": [{"lease_id": "nope", "job_id": "nojob",'
                        b' "cell": "c", "run": 0, "worker": "w9", "seconds": 0}]}'):
            s.put(key, payload, congestion_control=block)
    replies = list(s.get("swarmpath/work", payload=b"garbage", timeout=5))
    print(replies[0].ok.payload.to_bytes().decode())
    time.sleep(0.5)
    s.close()
""")


def test_garbage_on_the_zenoh_keys_is_logged_and_ignored(service):
    job = bench_job(service)
    service.wait_done(job, 60)
    before = service.status(job)
    out = subprocess.run([PY, "-c", GARBAGE, service.zenoh, job], env=ENV, capture_output=True,
                         timeout=60, check=True)
    reply = json.loads(out.stdout)
    assert reply["kind"] == "no_work" and "malformed" in reply["reason"]
    service.wait_for(lambda: "malformed result batch" in service.log("coordinator"), 10, "log")
    assert "malformed progress" in service.log("coordinator")
    assert service.get("/healthz").json()["status"] == "ok"
    metrics = service.get("/metrics").text
    malformed = next(line for line in metrics.splitlines()
                     if line.startswith("swarmpath_messages_malformed_total"))
    assert int(malformed.split()[1]) >= 10
    assert service.status(job) == before
    # and it still does work
    quick = service.submit({**BENCH, "algorithms": ["PSO"], "functions": ["F1"], "runs": 3})
    assert service.wait_done(quick, 60)["state"] == "done"


def test_sigkill_a_worker_holding_a_lease(service):
    spec = {"kind": "benchmark", "algorithms": ["ICOOT"], "functions": ["F1", "F5"],
            "dims": [10], "runs": 16, "agents": 20, "iterations": 1200, "seed": 5}
    job = service.submit(spec)
    holder: list[str] = []

    def someone_holds() -> bool:
        for w in service.get("/workers").json():
            if w["alive"] and any(r.startswith(job) for r in w["current_runs"]):
                holder.append(w["id"])
                return True
        return False

    service.wait_for(someone_holds, 60, "a lease of the job")
    victim = holder[0]
    service.kill(service.workers[victim])  # SIGKILL, slot process included
    service.wait_for(lambda: not {w["id"]: w for w in service.get("/workers").json()}[victim][
        "alive"], 10, f"{victim} seen gone")
    service.start_worker(victim + "b")
    status = service.wait_done(job, 120)
    assert status["state"] == "done" and status["runs_done"] == 32 and status["runs_failed"] == 0
    check_complete(service, job, 32)
    metrics = service.get("/metrics").text
    requeued = next(line for line in metrics.splitlines()
                    if line.startswith("swarmpath_lease_requeues_total"))
    assert int(requeued.split()[1]) >= 1
    runs = service.runs(job)
    direct = minimize("ICOOT", "F5", 10, 20, 1200, runs=16, seed=5).best_fitness.tolist()
    assert [r["best_fitness"] for r in runs if r["function"] == "F5"] == direct


def test_cancel_a_running_job(service):
    spec = {"kind": "benchmark", "algorithms": ["ICOOT"], "functions": ["F1"], "dims": [10],
            "runs": 64, "agents": 20, "iterations": 5000, "seed": 1}
    job = service.submit(spec)

    def leased() -> bool:
        return any(r.startswith(job) for w in service.get("/workers").json()
                   for r in w["current_runs"])

    service.wait_for(leased, 30, "a lease of the job")
    r = service.http_client.delete(f"/jobs/{job}")
    assert r.status_code == 200 and r.json()["state"] == "cancelled"
    assert service.get(f"/jobs/{job}/mcap").status_code == 200
    service.wait_for(lambda: not leased(), 10, "leases of the cancelled job gone")
    service.wait_for(lambda: any("dropping lease" in service.log(w) for w in service.workers),
                     10, "a worker aborting its runs")
    assert service.status(job)["state"] == "cancelled"


def test_map_job(service, tmp_path):
    from swarmpath.planners import Episode
    from swarmpath.world.presets import get_map

    spec = {"kind": "map", "planners": ["MFB", "OMPL-RRTstar"], "maps": ["mfb-static"],
            "runs": 2, "seed": 3}
    job = service.submit(spec)
    status = service.wait_done(job, 120)
    assert status["state"] == "done" and status["runs_done"] == 4
    runs = service.runs(job)
    assert [(r["planner"], r["map"], r["run"]) for r in runs] == [
        ("MFB", "mfb-static", 0), ("MFB", "mfb-static", 1),
        ("OMPL-RRTstar", "mfb-static", 0), ("OMPL-RRTstar", "mfb-static", 1)]
    direct = Episode(get_map("mfb-static"), "MFB", 3, 1).run()
    one = service.get(f"/jobs/{job}/runs/1").json()
    assert one["length"] == direct.length and one["success"] == direct.success
    assert one["path"] == direct.path
    summary = service.get(f"/jobs/{job}/summary").json()
    assert [row["planner"] for row in summary["rows"]] == ["MFB", "OMPL-RRTstar"]
    r = service.get(f"/jobs/{job}/mcap")
    reader = make_reader(io.BytesIO(r.content))
    schemas = {s.name for s in reader.get_summary().schemas.values()}
    assert {"foxglove.SceneUpdate", "foxglove.PosesInFrame", "foxglove.Grid"} <= schemas
    passes_foxglove_reader(r.content, tmp_path, {"/results": 4})
    check_complete(service, job, 4)


def test_sigkill_the_coordinator_mid_job_and_restart(service):
    spec = {"kind": "benchmark", "algorithms": ["GWO", "ICOOT"], "functions": ["F1", "F9"],
            "dims": [10], "runs": 16, "agents": 20, "iterations": 800, "seed": 9}
    job = service.submit(spec)
    service.wait_for(lambda: 0 < service.status(job)["runs_done"] < 64, 90, "some results")
    service.kill(service.coordinator)
    time.sleep(1.0)
    service.start_coordinator()
    status = service.wait_done(job, 150)
    assert status["state"] == "done" and status["runs_done"] == 64
    check_complete(service, job, 64)
    runs = service.runs(job)
    direct = minimize("ICOOT", "F9", 10, 20, 800, runs=16, seed=9).best_fitness.tolist()
    assert [r["best_fitness"] for r in runs if r["cell"] == "ICOOT/F9/10"] == direct
    assert "restart" in service.log("coordinator")


def test_stacked_leases_through_the_service_equal_minimize_run_by_run(service):
    """Cells of one algorithm with few runs come bundled and run stacked in a slot process (one
    batch: runs of different leases are charged the same share of the batch's seconds); every
    run equals ``minimize`` alone."""
    import math

    from swarmpath.functions import list_functions

    functions = list_functions()
    spec = {"kind": "benchmark", "algorithms": ["PSO"], "functions": functions, "dims": [5],
            "runs": 8, "agents": 10, "iterations": 40, "seed": 21}
    job = service.submit(spec)
    assert service.wait_done(job, 120)["state"] == "done"
    runs = service.runs(job)
    for f in functions:
        direct = minimize("PSO", f, 5, 10, 40, runs=8, seed=21)
        got = [r for r in runs if r["function"] == f]
        assert [r["best_fitness"] for r in got] == direct.best_fitness.tolist()
        assert [r["evaluations"] for r in got] == direct.evaluations.tolist()
    assert any(a["lease_id"] != b["lease_id"] and a["worker"] == b["worker"]
               and math.isclose(a["seconds"], b["seconds"], rel_tol=1e-9)
               for a in runs for b in runs), "no two leases ran in one batch"
    check_complete(service, job, 8 * len(functions))
