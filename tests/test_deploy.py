"""deploy/: the Zenoh configs disable scouting and name their endpoints; the systemd units use
only options the CLI accepts."""

from __future__ import annotations

import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from swarmpath.service import zenoh_config

ROOT = Path(__file__).resolve().parents[1]
DEPLOY = ROOT / "deploy"
ENV = {**os.environ, "PYTHONPATH": str(ROOT / "services"), "COLUMNS": "200", "NO_COLOR": "1"}


def load_json5(name: str) -> dict:
    """The deploy configs are JSON-compatible JSON5 (no comments), so ``json`` reads them."""
    return json.loads((DEPLOY / "zenoh" / name).read_text(encoding="utf-8"))


def assert_no_scouting(conf: dict) -> None:
    assert conf["scouting"]["multicast"]["enabled"] is False
    assert conf["scouting"]["gossip"]["enabled"] is False
    assert conf["transport"]["shared_memory"]["enabled"] is False


def test_coordinator_config_is_an_explicit_authenticated_router():
    conf = load_json5("coordinator.json5")
    assert conf["mode"] == "router"
    assert_no_scouting(conf)
    listen = conf["listen"]["endpoints"]
    assert listen and all(zenoh_config.check_endpoint(e) == e for e in listen)
    assert conf["connect"]["endpoints"] == []
    assert conf["transport"]["auth"]["usrpwd"]["dictionary_file"].startswith("/")


def test_worker_config_is_an_explicit_authenticated_client():
    conf = load_json5("worker.json5")
    assert conf["mode"] == "client"
    assert_no_scouting(conf)
    connect = conf["connect"]["endpoints"]
    assert connect and all(zenoh_config.check_endpoint(e) == e for e in connect)
    assert conf["listen"]["endpoints"] == []
    usrpwd = conf["transport"]["auth"]["usrpwd"]
    assert usrpwd["user"] and usrpwd["password"]


def test_configs_match_what_the_code_builds(tmp_path):
    """The files document the code's configs: same keys and values but the placeholders."""
    users = tmp_path / "users.txt"
    users.write_text("w:pw\n")
    built = zenoh_config.router_config("tcp/0.0.0.0:7447", dictionary_file=users)
    built["transport"]["auth"]["usrpwd"]["dictionary_file"] = "/etc/swarmpath/zenoh-users.txt"
    assert load_json5("coordinator.json5") == built
    built = zenoh_config.client_config("tcp/COORDINATOR_HOST:7447", user="WORKER_USER",
                                       password="WORKER_PASSWORD")
    assert load_json5("worker.json5") == built


def test_security_extras_match_the_builders():
    """access-control.json5 (usrpwd logins), coordinator-tls.json5 and worker-tls.json5 (mutual
    TLS, certificates from deploy/tls/make-certs.sh) are --zenoh-config files: exactly what
    zenoh_config builds, with placeholder names and paths."""
    tls = "/etc/swarmpath/tls/"
    assert load_json5("access-control.json5") == {"access_control": zenoh_config.
        worker_access_control(usernames=["lab-worker-1", "lab-worker-2"])}
    router = zenoh_config.tls_listen(tls + "ca.pem", tls + "coordinator.pem",
                                     tls + "coordinator.key")
    router["access_control"] = zenoh_config.worker_access_control(
        cert_common_names=["worker-1", "worker-2"])
    assert load_json5("coordinator-tls.json5") == router
    assert load_json5("worker-tls.json5") == zenoh_config.tls_connect(
        tls + "ca.pem", tls + "WORKER.pem", tls + "WORKER.key")
    acl = load_json5("coordinator-tls.json5")["access_control"]
    assert acl["default_permission"] == "deny"
    allowed = {(r["flows"][0], m, k) for r in acl["rules"] for m in r["messages"]
               for k in r["key_exprs"]}
    assert ("ingress", "put", "swarmpath/cancel") not in allowed  # only the coordinator
    assert ("ingress", "put", "swarmpath/wake") not in allowed
    assert ("egress", "put", "swarmpath/wake") in allowed  # workers hear the coordinator's
    assert not any(flow == "ingress" and k.startswith("swarmpath/ack")
                   and m in ("put", "delete") for flow, m, k in allowed)


def test_configs_are_accepted_by_zenoh():
    pytest.importorskip("zenoh")
    for name in ("coordinator.json5", "worker.json5", "access-control.json5"):
        conf = load_json5(name)
        if name == "access-control.json5":
            conf = zenoh_config.router_config("tcp/127.0.0.1:7447", extra=conf)
        zenoh_config.to_zenoh(conf)  # parses; opens nothing


def exec_start(unit: str) -> list[str]:
    text = (DEPLOY / "systemd" / unit).read_text(encoding="utf-8")
    lines = [ln for ln in text.splitlines() if ln.startswith("ExecStart=")]
    assert len(lines) == 1, unit
    assert "Restart=on-failure" in text.splitlines()
    assert "KillSignal=SIGTERM" in text.splitlines()
    assert any(ln.startswith("EnvironmentFile=") for ln in text.splitlines())
    return shlex.split(lines[0].removeprefix("ExecStart="))


def cli_help(command: str) -> str:
    done = subprocess.run([sys.executable, "-m", "swarmpath.cli", command, "--help"], env=ENV,
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return done.stdout


@pytest.mark.parametrize("unit,command", [("swarmpath-coordinator.service", "coordinator"),
                                          ("swarmpath-worker@.service", "worker")])
def test_systemd_exec_start_uses_real_cli_options(unit, command):
    argv = exec_start(unit)
    assert argv[0].endswith("/swarmpath") and argv[1] == command
    options = [a for a in argv[2:] if a.startswith("--")]
    assert options
    accepted = set(re.findall(r"--[a-z][a-z-]*", cli_help(command)))
    unknown = [o for o in options if o not in accepted]
    assert not unknown, f"{unit}: {unknown} not in `swarmpath {command} --help`"
    if command == "worker":
        assert "--password" not in options  # the password comes from the EnvironmentFile
        assert "--connect" in options
    else:
        assert {"--zenoh", "--auth-dictionary", "--data"} <= set(options)


def test_compose_commands_use_real_cli_options():
    yaml = pytest.importorskip("yaml")
    compose = yaml.safe_load((DEPLOY / "compose.yaml").read_text(encoding="utf-8"))
    for name, service in compose["services"].items():
        argv = shlex.split(service["command"])
        accepted = set(re.findall(r"--[a-z][a-z-]*", cli_help(argv[0])))
        unknown = [a for a in argv[1:] if a.startswith("--") and a not in accepted]
        assert not unknown, f"compose {name}: {unknown}"
        assert service["stop_signal"] == "SIGTERM"
