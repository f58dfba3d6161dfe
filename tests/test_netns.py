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
import os
import random
import shutil
import socket
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest

from test_service_e2e import ENV, PY, Service, free_port


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
        return subprocess.Popen(["ip", "netns", "exec", self.net.ns, PY, "-m", "swarmpath.cli",
                                 *args], stdout=log, stderr=log, env=ENV, start_new_session=True)


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
