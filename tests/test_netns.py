"""Several hosts on one machine: a worker in a network namespace created here reaches the
coordinator over a veth pair and completes a job.

The test creates a namespace and a veth pair with a private /30 (10.x addresses only on these two
interfaces), named uniquely per run, and deletes them at teardown. The coordinator listens for
Zenoh on the veth address only (its REST API stays on loopback, which the namespaced worker cannot
reach); the worker's Zenoh client connects to that address explicitly, scouting off (as in every
config swarmpath builds). Skipped, with the reason, when namespaces cannot be created.
"""

from __future__ import annotations

import contextlib
import ipaddress
import json
import os
import random
import shutil
import socket
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest

import owned
from swarmpath.optimizers import minimize
from swarmpath.service import zenoh_config
from test_service_e2e import ENV, PY, ROOT, Service, free_port


def ip(*args: str, check: bool = True) -> subprocess.CompletedProcess[str]:
    done = subprocess.run(["ip", *args], capture_output=True, text=True, timeout=10)
    if check and done.returncode != 0:
        raise RuntimeError(f"ip {' '.join(args)}: {done.stderr.strip()}")
    return done


def unused_subnet() -> ipaddress.IPv4Network:
    """A random 10.x.y.z/30 that overlaps no address or route already on this machine."""
    used = []
    for text in (ip("-4", "route").stdout, ip("-4", "addr").stdout):
        for word in text.split():
            with contextlib.suppress(ValueError):
                used.append(ipaddress.ip_network(word, strict=False))
    for _ in range(100):
        a, b, c = random.randint(100, 250), random.randint(0, 255), 4 * random.randint(0, 63)
        net = ipaddress.ip_network(f"10.{a}.{b}.{c}/30")
        if not any(net.overlaps(u) for u in used if u.version == 4 and u.prefixlen > 0):
            return net
    pytest.skip("no unused 10.x /30 found for the veth pair")


class Netns:
    """A namespace ``ns`` holding one end of a veth pair; the other end stays in this one."""

    def __init__(self) -> None:
        tag = f"{os.getpid() % 100000}{random.randint(0, 999):03d}"
        self.ns = f"spw{tag}"
        self.host_if, self.ns_if = f"sph{tag}", f"spn{tag}"  # <= 15 characters
        net = unused_subnet()
        self.host_ip, self.ns_ip = (str(a) for a in list(net.hosts())[:2])
        self.prefix = net.prefixlen

    def create(self) -> None:
        ip("link", "add", self.host_if, "type", "veth", "peer", "name", self.ns_if)
        ip("link", "set", self.ns_if, "netns", self.ns)
        ip("addr", "add", f"{self.host_ip}/{self.prefix}", "dev", self.host_if)
        ip("link", "set", self.host_if, "up")
        ip("-n", self.ns, "addr", "add", f"{self.ns_ip}/{self.prefix}", "dev", self.ns_if)
        ip("-n", self.ns, "link", "set", self.ns_if, "up")
        ip("-n", self.ns, "link", "set", "lo", "up")

    def delete(self) -> None:
        ip("link", "del", self.host_if, check=False)  # deletes both ends
        ip("netns", "del", self.ns, check=False)


@pytest.fixture
def netns() -> Iterator[Netns]:
    if shutil.which("ip") is None:
        pytest.skip("iproute2 (the `ip` command) is not installed")
    net = Netns()
    added = ip("netns", "add", net.ns, check=False)
    if added.returncode != 0:
        pytest.skip(f"`ip netns add` not permitted (euid {os.geteuid()}): "
                    f"{added.stderr.strip()}")
    try:
        net.create()
        yield net
    finally:
        net.delete()


class NamespacedService(Service):
    """The e2e helper, with workers started inside the test's namespace."""

    def __init__(self, tmp: Path, net: Netns):
        super().__init__(tmp)
        self.net = net
        self.zenoh = f"tcp/{net.host_ip}:{free_port()}"

    def _spawn(self, name: str, args: list[str]) -> subprocess.Popen[bytes]:
        if name == "coordinator":
            return super()._spawn(name, args)
        log = open(self.tmp / f"{name}.log", "ab")  # closed by Service.close
        self._logs.append(log)
        # `ip netns exec` execs the command: the pid (and session) are the worker's
        return owned.popen(["ip", "netns", "exec", self.net.ns, PY, "-m", "swarmpath.cli",
                            *args], stdout=log, stderr=log, env=ENV)


def test_worker_in_a_namespace_completes_a_job_over_veth(netns, tmp_path):
    # the namespace sees only its veth end and lo: the coordinator's loopback is out of reach
    reach = ip("netns", "exec", netns.ns, "ip", "-4", "route").stdout
    assert netns.host_ip.rsplit(".", 1)[0] in reach and "default" not in reach

    svc = NamespacedService(tmp_path, netns)
    try:
        svc.start_coordinator()
        zport = int(svc.zenoh.rsplit(":", 1)[1])
        with socket.socket() as s, pytest.raises(OSError):
            s.settimeout(2)
            s.connect(("127.0.0.1", zport))  # Zenoh listens on the veth address only
        svc.start_worker("netns-w1")
        svc.wait_workers(["netns-w1"], timeout=20)
        spec = {"kind": "benchmark", "algorithms": ["GWO"], "functions": ["F1"], "dims": [2],
                "runs": 6, "agents": 5, "iterations": 10, "seed": 3}
        job = svc.submit(spec)
        status = svc.wait_done(job, 20)
        assert status["state"] == "done" and status["runs_done"] == 6, status
        runs = svc.runs(job)
        assert [r["run_id"] for r in runs] == list(range(6))
        assert {r["worker"] for r in runs} == {"netns-w1"}
        pids = ip("netns", "pids", netns.ns).stdout.split()
        assert str(svc.workers["netns-w1"].pid) in pids  # the worker ran inside the namespace
    finally:
        svc.close()


# ------------------------------------------------------------------ mutual TLS + access control
INTRUDER = """
import json, sys, time, zenoh
conf, job = json.loads(sys.argv[1]), sys.argv[2]
try:
    s = zenoh.open(zenoh.Config.from_json5(json.dumps(conf)))
except Exception as exc:
    print(json.dumps({"opened": False, "error": str(exc)[:200]}))
    sys.exit(0)
heard, relayed = [], []
listener = zenoh.open(zenoh.Config.from_json5(json.dumps(conf)))  # a second worker session
listener.declare_subscriber("swarmpath/cancel", lambda x: relayed.append(str(x.key_expr)))
listener.declare_subscriber("swarmpath/ack/intruder", lambda x: relayed.append(str(x.key_expr)))
s.declare_subscriber("swarmpath/progress/*", lambda x: heard.append(str(x.key_expr)))
s.declare_subscriber("swarmpath/results/*", lambda x: heard.append(str(x.key_expr)))
time.sleep(5)
before = list(heard)  # what reached us from others (our own puts come back to us locally)
forged = {"worker": "netns-w1", "results": [
    {"lease_id": "0" * 32, "job_id": job, "cell": "ICOOT/F5/10", "run": r, "worker": "netns-w1",
     "seconds": 0.0, "proof": "0" * 64, "metrics": {"best_fitness": -12345.0}}
    for r in range(40)]}
s.put(f"swarmpath/results/{job}", json.dumps(forged))
s.put(f"swarmpath/progress/{job}", json.dumps({"lease_id": "0" * 32, "job_id": job,
      "worker": "netns-w1", "cell": "ICOOT/F5/10", "runs": [0], "seq": 9, "proof": "0" * 64}))
s.put("swarmpath/cancel", json.dumps({"job_id": job}))
s.put("swarmpath/ack/intruder", json.dumps({"worker": "intruder", "drop_leases": []}))
time.sleep(1)
s.close()
listener.close()
print(json.dumps({"opened": True, "heard": before, "relayed": relayed}))
"""


class TlsService(NamespacedService):
    """The coordinator listens with mutual TLS and access control; the namespaced worker shows
    its certificate (deploy/tls/make-certs.sh made them)."""

    def __init__(self, tmp: Path, net: Netns):
        super().__init__(tmp, net)
        self.insecure = self.login = False  # the certificates are the logins
        self.zenoh = f"tls/{net.host_ip}:{free_port()}"
        self.certs = tmp / "certs"
        subprocess.run([str(ROOT / "deploy" / "tls" / "make-certs.sh"), str(self.certs),
                        net.host_ip, "netns-w1", "intruder"], check=True, capture_output=True)
        c = self.certs
        router = {**zenoh_config.tls_listen(c / "ca.pem", c / "coordinator.pem",
                                            c / "coordinator.key"),
                  "access_control": zenoh_config.worker_access_control(
                      cert_common_names=["netns-w1", "intruder"])}
        (tmp / "router.json").write_text(json.dumps(router))

    def client_conf(self, name: str | None) -> dict:
        c = self.certs
        conf = zenoh_config.client_config(self.zenoh, timeout_ms=3000)
        tls = (zenoh_config.tls_connect(c / "ca.pem", c / f"{name}.pem", c / f"{name}.key")
               if name else {"transport": {"link": {"tls": {"root_ca_certificate":
                                                             str(c / "ca.pem")}}}})
        conf["transport"]["link"] = tls["transport"]["link"]
        return conf

    def _spawn(self, name: str, args: list[str]) -> subprocess.Popen[bytes]:
        if name == "coordinator":
            args = [*args, "--zenoh-config", str(self.tmp / "router.json")]
        else:
            worker = {"transport": self.client_conf(name)["transport"]}
            (self.tmp / f"{name}.json").write_text(json.dumps(worker))
            args = [*args, "--zenoh-config", str(self.tmp / f"{name}.json")]
        return super()._spawn(name, args)

    def intruder(self, name: str | None, job: str) -> dict:
        done = subprocess.run(["ip", "netns", "exec", self.net.ns, PY, "-c", INTRUDER,
                               json.dumps(self.client_conf(name)), job],
                              capture_output=True, text=True, env=ENV, timeout=60, check=True)
        return json.loads(done.stdout)


def metric(svc: Service, name: str) -> float:
    line = next(x for x in svc.get("/metrics").text.splitlines() if x.startswith(name + " "))
    return float(line.split()[1])


def test_mutual_tls_and_access_control_keep_intruders_out(netns, tmp_path):
    """A worker over TLS with its certificate completes a job; a client without a certificate
    cannot connect; a client with a valid worker certificate hears no results or progress of
    others, its cancel and acks are relayed to nobody (access control), and its forged results
    and progress, which a worker login may put, are refused by the lease capabilities."""
    svc = TlsService(tmp_path, netns)
    try:
        svc.start_coordinator(lease_seconds=6.0)  # progress every 2 s: there is traffic to hear
        svc.start_worker("netns-w1")
        svc.wait_workers(["netns-w1"], timeout=30)
        # a job far longer than the intruders (cancelled once they are gone: what is proven of
        # it is that it ran while they listened, not that it ends; the second job ends)
        spec = {"kind": "benchmark", "algorithms": ["ICOOT"], "functions": ["F5"], "dims": [10],
                "runs": 400, "agents": 20, "iterations": 4000, "seed": 3}
        job = svc.submit(spec)
        svc.wait_for(lambda: svc.status(job)["state"] == "running", 30, "the job running")
        assert svc.intruder(None, job)["opened"] is False  # no certificate: no session
        seen = svc.intruder("intruder", job)
        assert seen["opened"] is True and seen["heard"] == [] and seen["relayed"] == [], seen
        assert svc.status(job)["state"] == "running"  # it listened while the job ran
        # the 40 forged results and the forged progress reached the coordinator: refused
        svc.wait_for(lambda: metric(svc, "swarmpath_messages_unproven_total") >= 41
                     and metric(svc, "swarmpath_results_stale_total") >= 40, 30,
                     "the forged messages counted")
        assert metric(svc, "swarmpath_messages_unproven_total") == 41
        assert metric(svc, "swarmpath_results_stale_total") == 40
        assert "dropping lease" not in svc.log("netns-w1")
        cancel = svc.http_client.delete(f"/jobs/{job}")
        assert cancel.status_code == 200 and cancel.json()["state"] == "cancelled", cancel.text
        # what it stored over TLS before the cancel is the runs' own numbers, nothing forged
        stored = {r["run_id"]: r["best_fitness"] for r in svc.runs(job) if r["state"] == "done"}
        if stored:
            ids = sorted(stored)
            direct = minimize("ICOOT", "F5", 10, 20, 4000, seed=3, run_ids=ids)
            assert [stored[r] for r in ids] == direct.best_fitness.tolist()
        # a job through the same TLS worker to its end, run by run equal to minimize
        small = {**spec, "runs": 8, "iterations": 300, "seed": 4}
        job = svc.submit(small)
        status = svc.wait_done(job, 300)
        assert status["state"] == "done" and status["runs_done"] == 8, status
        stored = {r["run_id"]: r["best_fitness"] for r in svc.runs(job)}
        direct = minimize("ICOOT", "F5", 10, 20, 300, seed=4, run_ids=list(range(8)))
        assert [stored[r] for r in range(8)] == direct.best_fitness.tolist()
        assert {r["worker"] for r in svc.runs(job)} == {"netns-w1"}
    finally:
        svc.close()
