"""A hostile client on the bus, end to end: a coordinator and a worker as subprocesses, and an
attacker process with the same access to the Zenoh router as the worker (the default `up` bus
before its credential, or a worker login on a farm). It listens to the broadcast progress
messages for lease ids, workers, cells and runs (a stolen lease id), then puts forged results
for them, replays the progress it heard, forges acks that drop the leases and cancels the job.
None of it may change anything: the job stays running, the runs of the leases it stole end with
the worker's results, equal to ``minimize``, nothing forged is stored, no lease dropped (the job,
far longer than the attack, is then cancelled)."""

from __future__ import annotations

import json
import subprocess
import textwrap
from collections.abc import Iterator

import httpx
import pytest

import owned
from swarmpath.optimizers import minimize
from test_service_e2e import ENV, PY, Service, free_port, stop_group

ATTACKER = textwrap.dedent("""
    import json, secrets, sys, time
    import zenoh
    endpoint, job, listen = sys.argv[1], sys.argv[2], float(sys.argv[3])
    conf = zenoh.Config.from_json5(json.dumps({
        "mode": "client", "connect": {"endpoints": [endpoint]},
        "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": False}},
        "transport": {"shared_memory": {"enabled": False}}}))
    s = zenoh.open(conf)
    heard = []
    sub = s.declare_subscriber("swarmpath/progress/*",
                               lambda sample: heard.append(sample.payload.to_bytes()))
    time.sleep(listen)
    sub.undeclare()
    leases = {}
    for raw in heard:
        p = json.loads(raw)
        leases.setdefault(p["lease_id"], p)
    forged = 0
    for lease_id, p in leases.items():
        for proof in (None, secrets.token_hex(32)):
            results = [{"lease_id": lease_id, "job_id": p["job_id"], "cell": p["cell"], "run": r,
                        "worker": p["worker"], "seconds": 0.0, "proof": proof,
                        "metrics": {"best_fitness": -12345.0, "evaluations": 1}}
                       for r in p["runs"]]
            s.put(f"swarmpath/results/{p['job_id']}",
                  json.dumps({"worker": p["worker"], "results": results}))
            forged += len(results)
        drop = [{"lease_id": lease_id, "proof": secrets.token_hex(32)}]
        s.put(f"swarmpath/ack/{p['worker']}", json.dumps({"worker": p["worker"],
                                                          "drop_leases": drop}))
        s.put("swarmpath/cancel", json.dumps({"job_id": job, "leases": drop}))
    for raw in heard:  # replayed progress: renews nothing
        s.put(f"swarmpath/progress/{job}", raw)
    s.put("swarmpath/cancel", json.dumps({"job_id": job}))  # the old, proof-less cancel
    time.sleep(0.5)
    s.close()
    print(json.dumps({"leases": len(leases), "forged": forged, "replayed": len(heard),
                      "runs": sorted({r for p in leases.values() for r in p["runs"]})}))
""")

SPEC = {"kind": "benchmark", "algorithms": ["ICOOT"], "functions": ["F5"], "dims": [10],
        "runs": 240, "agents": 20, "iterations": 2500, "seed": 9}  # far outlasts the attacker


@pytest.fixture
def service(tmp_path) -> Iterator[Service]:
    svc = Service(tmp_path)
    try:
        svc.start_coordinator(lease_seconds=6.0)  # heartbeats every 2 s: progress to steal
        svc.start_worker("w1")
        svc.wait_workers(["w1"])
        yield svc
    finally:
        svc.close()


def metric(svc: Service, name: str) -> float:
    line = next(x for x in svc.get("/metrics").text.splitlines() if x.startswith(name + " "))
    return float(line.split()[1])


def test_forged_results_cancels_drops_and_stolen_lease_ids_change_nothing(service):
    job = service.submit(SPEC)
    service.wait_for(lambda: service.status(job)["state"] == "running", 30, "the job running")
    out = subprocess.run([PY, "-c", ATTACKER, service.zenoh, job, "5"], env=ENV,
                         capture_output=True, text=True, timeout=60, check=True)
    attack = json.loads(out.stdout)
    assert attack["leases"] >= 1 and attack["forged"] >= 1, (attack, out.stderr)
    assert service.status(job)["state"] == "running"  # the forged cancels cancelled nothing

    def stored() -> dict[int, float]:
        return {r["run_id"]: r["best_fitness"] for r in service.runs(job) if r["state"] == "done"}

    # the stolen leases end with the worker's own results (nothing dropped, nothing forged kept)
    service.wait_for(lambda: set(attack["runs"]) <= set(stored()), 300, "the stolen runs done")
    log = service.log("w1")
    assert "ignored a drop of lease" in log  # the forged acks and cancels
    assert "dropping lease" not in log and "coordinator dropped lease" not in log
    assert metric(service, "swarmpath_results_stale_total") >= attack["forged"]
    cancel = service.http_client.delete(f"/jobs/{job}")
    assert cancel.status_code == 200 and cancel.json()["state"] == "cancelled", cancel.text
    done = stored()
    ids = sorted(done)
    direct = minimize("ICOOT", "F5", 10, 20, 2500, seed=9, run_ids=ids).best_fitness.tolist()
    assert [done[r] for r in ids] == direct  # nothing forged stored
    # one /results message per run stored, none twice (the MCAP is written after the store)
    service.wait_for(lambda: sorted(m["run_id"] for m in service.mcap_results(job))
                     == sorted(stored()), 30, "the MCAP holding each stored run once")
    assert service.status(job)["state"] == "cancelled"


STRANGER = textwrap.dedent("""
    import json, sys, zenoh
    endpoint = sys.argv[1]
    conf = {"mode": "client", "connect": {"endpoints": [endpoint], "timeout_ms": 3000},
            "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": False}},
            "transport": {"shared_memory": {"enabled": False}}}
    if len(sys.argv) > 3:
        conf["transport"]["auth"] = {"usrpwd": {"user": sys.argv[2], "password": sys.argv[3]}}
    try:
        s = zenoh.open(zenoh.Config.from_json5(json.dumps(conf)))
    except Exception as exc:
        print(json.dumps({"opened": False, "error": str(exc)[:200]}))
        sys.exit(0)
    heard, relayed = [], []
    sub = s.declare_subscriber("swarmpath/**", lambda sample: heard.append(str(sample.key_expr)))
    listener = zenoh.open(zenoh.Config.from_json5(json.dumps(conf)))  # a second session
    listener.declare_subscriber("swarmpath/cancel", lambda x: relayed.append(str(x.key_expr)))
    import time; time.sleep(1.0)
    mine = list(heard)  # before our own puts (which come back to our own subscriber)
    s.put("swarmpath/cancel", json.dumps({"job_id": "x"}))
    time.sleep(1.0)
    replies = [r for r in s.get("swarmpath/work", payload=b"{}", timeout=2)]
    sub.undeclare(); s.close(); listener.close()
    print(json.dumps({"opened": True, "heard": mine, "relayed": relayed,
                      "replies": len(replies)}))
""")


def test_up_admits_only_its_own_random_login(tmp_path):
    """`swarmpath up` makes a random login for its workers at each start: a process without it
    cannot open a session on the router; its workers finish a job."""

    http, zport = free_port(), free_port()
    log = open(tmp_path / "up.log", "wb")
    proc = owned.popen([PY, "-m", "swarmpath.cli", "up", "--workers", "1", "--http",
                        f"127.0.0.1:{http}", "--zenoh", f"tcp/127.0.0.1:{zport}", "--data",
                        str(tmp_path / "data")], env=ENV, stdout=log, stderr=log)
    try:
        svc = Service(tmp_path)
        svc.http_client = httpx.Client(base_url=f"http://127.0.0.1:{http}", timeout=30.0)
        svc.wait_for(lambda: any(w["alive"] for w in svc.get("/workers").json()), 60, "worker")
        users = (tmp_path / "data" / "zenoh-users.txt")
        assert oct(users.stat().st_mode & 0o777) == "0o600"
        user, password = users.read_text().split()[0].split(":", 1)
        assert len(password) >= 32
        out = subprocess.run([PY, "-c", STRANGER, f"tcp/127.0.0.1:{zport}"], env=ENV,
                             capture_output=True, text=True, timeout=60, check=True)
        assert json.loads(out.stdout)["opened"] is False, out.stdout
        wrong = subprocess.run([PY, "-c", STRANGER, f"tcp/127.0.0.1:{zport}", user, "guess"],
                               env=ENV, capture_output=True, text=True, timeout=60, check=True)
        assert json.loads(wrong.stdout)["opened"] is False, wrong.stdout
        # the workers' login itself may do only what a worker does: it is answered on work, but
        # hears no results or progress of a running job, and its cancel reaches nobody
        r = svc.http_client.post("/jobs", json={**SPEC, "runs": 8, "iterations": 1500})
        job = r.json()["id"]
        svc.wait_for(lambda: svc.status(job)["state"] == "running", 30, "the job running")
        login = subprocess.run([PY, "-c", STRANGER, f"tcp/127.0.0.1:{zport}", user, password],
                               env=ENV, capture_output=True, text=True, timeout=60, check=True)
        seen = json.loads(login.stdout)
        assert seen["opened"] is True and seen["replies"] == 1, login.stdout
        assert seen["heard"] == [] and seen["relayed"] == [], login.stdout
        assert svc.wait_done(job, 180)["runs_done"] == 8
    finally:
        stop_group(proc)
        log.close()
