"""Who may lease under a worker id, and who may enter the worker table (issue 25, failures 3-5):
a liveliness-token flood no longer locks workers out, a login leases only under its own worker
ids (its requests prove the login), and the standalone coordinator makes a login unless told
``--insecure`` (and then says so loudly). In process first, then over Zenoh with subprocesses."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import textwrap
import time
from pathlib import Path

import httpx
import pytest
from fastapi.testclient import TestClient

import owned
from swarmpath.service.coordinator import Coordinator
from swarmpath.service.http.app import create_app
from swarmpath.service.identity import Issuer, id_for, owner, refusal, request_proof
from swarmpath.service.protocol import Lease, LeaseRequest, NoWork, decode_work_reply, encode
from swarmpath.service.settings import CoordinatorSettings
from swarmpath.service.worker import execute_lease, pack_batches
from test_service_e2e import ENV, PY, Service, free_port, stop_group

SPEC = {"kind": "benchmark", "algorithms": ["GWO"], "functions": ["F1"], "dims": [3],
        "runs": 20, "agents": 6, "iterations": 5, "seed": 3}
LOGINS = {"alice": "pw-alice", "bob": "pw-bob", "bob-gpu": "pw-bob-gpu"}


def request(worker: str, login: str = "", password: str | None = None, issued: int = 1,
            proof: str | None = None) -> bytes:
    if proof is None:
        proof = request_proof(password, worker, login, issued) if password else ""
    return encode(LeaseRequest(worker=worker, max_runs=100, login=login, issued=issued,
                               proof=proof))


@pytest.fixture
def core(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    users = tmp_path / "users.txt"
    users.write_text("".join(f"{u}:{p}\n" for u, p in LOGINS.items()))
    app = create_app(CoordinatorSettings(data_dir=tmp_path / "data", dictionary_file=str(users)),
                     use_zenoh=False)
    with TestClient(app) as client:
        client.post("/jobs", json=SPEC).raise_for_status()
        yield app.state.core


def test_worker_ids_belong_to_logins_by_name() -> None:
    assert owner("alice", LOGINS) == "alice" and owner("alice-host-12", LOGINS) == "alice"
    assert owner("bob-gpu-1", LOGINS) == "bob-gpu" and owner("bob-1", LOGINS) == "bob"
    assert owner("alicea", LOGINS) is None and owner("carol-1", LOGINS) is None
    assert id_for("alice", None, "host-7") == "alice-host-7"
    with pytest.raises(ValueError, match="starts with 'alice-'"):
        id_for("alice", "w1", "host-7")
    issued = Issuer()
    values = [issued() for _ in range(1000)]
    assert values == sorted(set(values))
    good = request_proof("pw-bob", "bob-1", "bob", 5)
    assert refusal("bob-1", "bob", 5, good, LOGINS) is None
    assert "requires a login" in refusal("bob-1", "", 5, "", LOGINS)
    assert "unknown login" in refusal("bob-1", "mallory", 5, good, LOGINS)
    assert "does not belong to login 'bob'" in refusal("bob-gpu-1", "bob", 5, good, LOGINS)
    assert "not proven" in refusal("bob-1", "bob", 6, good, LOGINS)  # another issued


def test_a_login_leases_only_under_its_own_worker_ids(core: Coordinator) -> None:
    """The audit's failure 5: bob (a valid login) asked for work as alice's worker (its id is
    public in GET /workers) and its results were stored as alice's. Now the request is refused
    whatever bob sends, and alice's own requests are leased, once each."""
    core.sizer.max_lease_rate = float("inf")  # small leases: work is left for bob's own worker
    core.worker_alive("alice-1")
    forged = [request("alice-1"),  # no login
              request("alice-1", "bob", "pw-bob"),  # bob's valid proof, alice's worker
              request("alice-1", "alice", "pw-bob"),  # alice's login, not her password
              request("alice-1", "alice", proof="0" * 64)]
    for payload in forged:
        reply = decode_work_reply(core.handle_lease_request(payload))
        assert isinstance(reply, NoWork) and reply.reason.startswith("refused: "), reply
    assert core.stats["unauthenticated"] == len(forged)
    assert "swarmpath_lease_requests_unauthenticated_total 4" in core.metrics_text()
    issued = Issuer()
    first = request("alice-1", "alice", "pw-alice", issued())
    lease = decode_work_reply(core.handle_lease_request(first))
    assert isinstance(lease, Lease) and lease.worker == "alice-1"
    replayed = decode_work_reply(core.handle_lease_request(first))  # the same request again
    assert isinstance(replayed, NoWork) and "seen before" in replayed.reason
    for payload in pack_batches("alice-1", [d for _run, d in execute_lease(lease)]):
        core.handle_results(f"swarmpath/results/{lease.job_id}", payload)
    workers = {r.get("worker") for r in core.store.runs(lease.job_id, 100, 0) or []
               if r.get("state") == "done"}
    assert workers == {"alice-1"}
    core.worker_alive("bob-7")  # bob under his own id is a worker like any other
    own = decode_work_reply(core.handle_lease_request(request("bob-7", "bob", "pw-bob", 9)))
    assert isinstance(own, Lease) and own.worker == "bob-7"


def test_a_token_flood_cannot_lock_workers_out(tmp_path: Path,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    """The audit's failure 3: one client declared 1,100 tokens, filling the 1,024-entry table;
    a worker that joined was refused and stayed refused after the flood left (its queries got
    "no liveliness token seen"; the job sat queued). Now flood entries make room for it, leave
    with their tokens, and a worker refused by a table full of real workers is admitted once
    there is room, when it asks for work again."""
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    # small leases (no floor of live slots / lease rate: 1,024 entries would make it the whole
    # job): work is left for the worker admitted later
    app = create_app(CoordinatorSettings(data_dir=tmp_path / "data", max_lease_rate=float("inf")),
                     use_zenoh=False)
    with TestClient(app) as client:
        core: Coordinator = app.state.core
        job = client.post("/jobs", json=SPEC).json()["id"]
        tokens = {f"flood-{i}" for i in range(1100)}
        for token in sorted(tokens):
            core.worker_alive(token)
        assert len(core.worker_table) == 1024
        core.worker_alive("w1")  # joins during the flood
        assert core.is_alive("w1")
        lease = decode_work_reply(core.handle_lease_request(request("w1")))
        assert isinstance(lease, Lease), lease
        for token in tokens:  # the flood is withdrawn
            core.worker_mark_gone(token)
        assert [w["id"] for w in client.get("/workers").json()] == ["w1"]
        for payload in pack_batches("w1", [d for _run, d in execute_lease(lease)]):
            core.handle_results(f"swarmpath/results/{job}", payload)

        # a table full of proven live workers refuses a newcomer, which asks again later
        core.worker_table.max_entries = 3
        for w in ("w2", "w3"):
            core.worker_alive(w)
            decode_work_reply(core.handle_lease_request(request(w)))
        checked: list[str] = []
        core.check_token = checked.append  # the bridge looks the token up; here: by hand
        core.worker_alive("w4")
        assert not core.is_alive("w4") and core.worker_table.refused == 1
        refused = decode_work_reply(core.handle_lease_request(request("w4")))
        assert isinstance(refused, NoWork) and checked == ["w4"]
        core.worker_gone("w3")  # room frees ...
        time.sleep(core.TOKEN_CHECK_SECONDS)
        decode_work_reply(core.handle_lease_request(request("w4")))
        assert checked == ["w4", "w4"]  # ... the next request looks the token up again
        core.worker_alive(checked[-1])  # the token is there: admitted
        assert isinstance(decode_work_reply(core.handle_lease_request(request("w4"))), Lease)


# ----------------------------------------------------------------------- over Zenoh, end to end
STRANGER = textwrap.dedent("""
    import json, sys, zenoh
    endpoint = sys.argv[1]
    conf = {"mode": "client", "connect": {"endpoints": [endpoint], "timeout_ms": 3000},
            "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": False}},
            "transport": {"shared_memory": {"enabled": False}}}
    try:
        s = zenoh.open(zenoh.Config.from_json5(json.dumps(conf)))
    except Exception:
        print(json.dumps({"opened": False}))
        raise SystemExit
    request = json.dumps({"worker": "stranger", "max_runs": 10, "protocol": int(sys.argv[2])})
    tok = s.liveliness().declare_token("swarmpath/workers/stranger")
    import time; time.sleep(1.0)
    replies = [r.ok.payload.to_bytes().decode() for r in
               s.get("swarmpath/work", payload=request, timeout=5) if r.ok is not None]
    print(json.dumps({"opened": True, "replies": replies}))
    tok.undeclare(); s.close()
""")


def stranger(endpoint: str) -> dict:
    from swarmpath.service.protocol import PROTOCOL_VERSION

    out = subprocess.run([PY, "-c", STRANGER, endpoint, str(PROTOCOL_VERSION)], env=ENV,
                         capture_output=True, text=True, timeout=120, check=True)
    return json.loads(out.stdout)


def test_the_standalone_coordinator_makes_a_login_unless_insecure(tmp_path: Path) -> None:
    """The audit's failure 4: `swarmpath coordinator` without --auth-dictionary let any local
    process lease work and store made-up numbers. Now it makes a login (DATA/zenoh-users.txt,
    0600) for workers started with --login-file; a process without it cannot open a session.
    --insecure still runs without one, and warns."""
    svc = Service(tmp_path / "secure", insecure=False)
    try:
        svc.start_coordinator()
        users = svc.data / "zenoh-users.txt"
        assert oct(users.stat().st_mode & 0o777) == "0o600"
        assert "--login-file" in svc.log("coordinator")
        job = svc.submit(SPEC)
        assert stranger(svc.zenoh) == {"opened": False}
        svc.start_worker("local-w1")
        assert svc.wait_done(job, 180)["runs_done"] == SPEC["runs"]
        assert {r["worker"] for r in svc.runs(job)} == {"local-w1"}
    finally:
        svc.close()
    open_ = Service(tmp_path / "insecure", insecure=True)
    try:
        open_.start_coordinator()
        assert "WARNING: INSECURE (--insecure)" in open_.log("coordinator")
        open_.submit(SPEC)
        seen = stranger(open_.zenoh)  # what the audit did: any process leases work
        assert seen["opened"] is True and '"kind":"lease"' in seen["replies"][0].replace(" ", "")
    finally:
        open_.close()


INTRUDER = textwrap.dedent("""
    import json, sys, time, zenoh
    from swarmpath.service.identity import request_proof
    from swarmpath.service.protocol import LeaseRequest, encode
    endpoint, user, password, victim = sys.argv[1:5]
    conf = {"mode": "client", "connect": {"endpoints": [endpoint], "timeout_ms": 3000},
            "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": False}},
            "transport": {"shared_memory": {"enabled": False},
                          "auth": {"usrpwd": {"user": user, "password": password}}}}
    s = zenoh.open(zenoh.Config.from_json5(json.dumps(conf)))
    tokens = [s.liveliness().declare_token(f"swarmpath/workers/flood-{i}") for i in range(1100)]
    time.sleep(2.0)
    def ask(worker, login, proof_key):
        t = time.time_ns()
        proof = request_proof(proof_key, worker, login, t) if proof_key else ""
        payload = encode(LeaseRequest(worker=worker, max_runs=10, login=login, issued=t,
                                      proof=proof))
        return [r.ok.payload.to_bytes().decode() for r in
                s.get("swarmpath/work", payload=payload, timeout=5) if r.ok is not None]
    out = {"as_victim": ask(victim, user, password), "as_victim_no_login": ask(victim, "", ""),
           "flooded": len(tokens)}
    print(json.dumps(out), flush=True)
    sys.stdin.readline()  # keep the flood up until the test says so
    for t in tokens:
        t.undeclare()
    s.close()
""")


def test_under_up_a_login_cannot_speak_for_another_worker_nor_flood_it_out(tmp_path: Path
                                                                            ) -> None:
    """`swarmpath up` with two remote logins. The intruder (a valid login) floods 1,100 tokens
    and asks for work under the local worker's id (public in GET /workers): refused. A remote
    worker joining during the flood is admitted; the flood's entries go with it; every run of
    the job is attributed to a worker of its own login."""
    http, zport = free_port(), free_port()
    extra = tmp_path / "extra.txt"
    extra.write_text("intruder:pw-intruder-1234\nlab:pw-lab-5678\n")
    log = open(tmp_path / "up.log", "wb")
    proc = owned.popen([PY, "-m", "swarmpath.cli", "up", "--workers", "1", "--http",
                        f"127.0.0.1:{http}", "--zenoh", f"tcp/127.0.0.1:{zport}", "--data",
                        str(tmp_path / "data"), "--auth-dictionary", str(extra)],
                       env=ENV, stdout=log, stderr=log)
    svc = Service(tmp_path)
    svc.http_client = httpx.Client(base_url=f"http://127.0.0.1:{http}", timeout=30.0)
    intruder = None
    try:
        svc.wait_for(lambda: any(w["alive"] for w in svc.get("/workers").json()), 90, "worker")
        victim = next(w["id"] for w in svc.get("/workers").json() if w["alive"])
        intruder = owned.popen([PY, "-c", INTRUDER, f"tcp/127.0.0.1:{zport}", "intruder",
                                "pw-intruder-1234", victim], env=ENV, text=True,
                               stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        said = json.loads(intruder.stdout.readline())
        for replies in (said["as_victim"], said["as_victim_no_login"]):
            assert len(replies) == 1 and '"refused: ' in replies[0], replies
        assert "does not belong to login 'intruder'" in said["as_victim"][0]
        lab = owned.popen([PY, "-m", "swarmpath.cli", "worker", "--connect",
                           f"tcp/127.0.0.1:{zport}", "--id", "lab-remote", "--grace", "2"],
                          env={**ENV, "SWARMPATH_ZENOH_USER": "lab",
                               "SWARMPATH_ZENOH_PASSWORD": "pw-lab-5678"},
                          stdout=log, stderr=log)
        svc.workers["lab"] = lab
        svc.wait_for(lambda: any(w["id"] == "lab-remote" and w["alive"]
                                 for w in svc.get("/workers").json()), 90, "lab admitted")
        job = svc.submit(SPEC)
        assert svc.wait_done(job, 180)["runs_done"] == SPEC["runs"]
        assert {r["worker"] for r in svc.runs(job)} <= {victim, "lab-remote"}
        intruder.stdin.write("\n")
        intruder.stdin.flush()
        intruder.wait(30)
        svc.wait_for(lambda: {w["id"] for w in svc.get("/workers").json()}
                     == {victim, "lab-remote"}, 30, "the flood's entries gone")
        metrics = svc.get("/metrics").text
        assert "swarmpath_lease_requests_unauthenticated_total 2" in metrics
    finally:
        for p in (intruder, svc.workers.get("lab")):
            if p is not None and p.poll() is None:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait(10)
        stop_group(proc)
        log.close()
        svc.http_client.close()
