"""A hostile client on the bus, end to end: a coordinator and a worker as subprocesses, and an
attacker process with the same access to the Zenoh router as the worker (the default `up` bus
before its credential, or a worker login on a farm). It listens to the broadcast progress
messages for lease ids, workers, cells and runs (a stolen lease id), then puts forged results
for them, replays the progress it heard, forges acks that drop the leases and cancels the job.
None of it may change anything: the job ends with every run equal to ``minimize``, nothing
forged stored, no lease dropped."""

from __future__ import annotations

import json
import subprocess
import textwrap
from collections.abc import Iterator

import pytest

from swarmpath.optimizers import minimize
from test_service_e2e import ENV, PY, Service, check_complete

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
    print(json.dumps({"leases": len(leases), "forged": forged, "replayed": len(heard)}))
""")

SPEC = {"kind": "benchmark", "algorithms": ["ICOOT"], "functions": ["F5"], "dims": [10],
        "runs": 24, "agents": 20, "iterations": 2500, "seed": 9}


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
    status = service.wait_done(job, 240)
    assert status["state"] == "done" and status["runs_done"] == 24, status
    check_complete(service, job, 24)
    direct = minimize("ICOOT", "F5", 10, 20, 2500, runs=24, seed=9).best_fitness.tolist()
    assert [r["best_fitness"] for r in service.runs(job)] == direct  # nothing forged stored
    assert metric(service, "swarmpath_results_stale_total") >= attack["forged"]
    log = service.log("w1")
    assert "ignored a drop of lease" in log  # the forged acks and cancels
    assert "dropping lease" not in log and "coordinator dropped lease" not in log
