"""Zenoh session configurations of the coordinator (a router) and the workers (clients).

Plain functions building JSON-able dicts (testable without a network), and :func:`to_zenoh` to turn
one into a ``zenoh.Config``. Every config built here has multicast and gossip scouting disabled and
explicit endpoints: a swarmpath process never discovers, or is discovered by, anything it was not
told about. Shared memory is off unless asked for (it is Zenoh's default in 1.x: messages of 3 KB
and more would go through files in /dev/shm, which containers and CI often restrict).

Authentication for several hosts (Zenoh's user/password scheme): the coordinator's router gets a
``dictionary_file`` with one ``user:password`` line per allowed worker; workers give ``user`` and
``password``. A worker with a wrong or missing password cannot open its session.
"""

from __future__ import annotations

import copy
import json
import re
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

DEFAULT_ZENOH = "tcp/127.0.0.1:7447"

# <protocol>/<address>, e.g. tcp/127.0.0.1:7447, tcp/[::1]:7447, tls/host.example:7447
_ENDPOINT_RE = re.compile(r"^(tcp|udp|tls|quic|ws|unixsock-stream)/[^\s/][^\s]*$")


def check_endpoint(endpoint: str) -> str:
    """An explicit Zenoh locator such as ``tcp/127.0.0.1:7447``; ValueError otherwise."""
    endpoint = endpoint.strip()
    if not _ENDPOINT_RE.match(endpoint):
        raise ValueError(
            f"{endpoint!r} is not a Zenoh endpoint like tcp/127.0.0.1:7447 (protocol/host:port)"
        )
    if endpoint.split("/", 1)[0] in ("tcp", "udp", "tls", "quic", "ws"):
        host_port = endpoint.split("/", 1)[1].split("#", 1)[0].split("?", 1)[0]
        host, sep, port = host_port.rpartition(":")
        if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
            raise ValueError(f"{endpoint!r} needs a host and a port in 1-65535 (tcp/HOST:PORT)")
    return endpoint


def _endpoints(endpoints: str | Iterable[str]) -> list[str]:
    items = [endpoints] if isinstance(endpoints, str) else list(endpoints)
    out = [check_endpoint(e) for e in items if e.strip()]
    if not out:
        raise ValueError("at least one endpoint is needed")
    return out


def _base(mode: str, shm: bool) -> dict[str, Any]:
    return {
        "mode": mode,
        "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": False}},
        "transport": {"shared_memory": {"enabled": bool(shm)}},
    }


def _merge(into: dict[str, Any], extra: Mapping[str, Any]) -> dict[str, Any]:
    for key, value in extra.items():
        if isinstance(value, Mapping) and isinstance(into.get(key), dict):
            _merge(into[key], value)
        else:
            into[key] = copy.deepcopy(value)
    return into


def _force_no_scouting(conf: dict[str, Any]) -> dict[str, Any]:
    """Whatever ``extra`` said: scouting stays off (a hard rule of this project)."""
    scouting = conf.setdefault("scouting", {})
    scouting.setdefault("multicast", {})["enabled"] = False
    scouting.setdefault("gossip", {})["enabled"] = False
    return conf


def router_config(
    listen: str | Iterable[str] = DEFAULT_ZENOH,
    *,
    shm: bool = False,
    dictionary_file: str | Path | None = None,
    user: str | None = None,
    password: str | None = None,
    extra: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """The coordinator: a Zenoh router listening on ``listen``, connecting nowhere.

    ``dictionary_file``: enable user/password authentication of the clients (a text file of
    ``user:password`` lines). ``user``/``password``: the router's own credentials (needed only when
    it connects to other authenticated routers; Zenoh accepts them alongside the dictionary)."""
    conf = _base("router", shm)
    conf["listen"] = {"endpoints": _endpoints(listen)}
    conf["connect"] = {"endpoints": []}
    usrpwd: dict[str, Any] = {}
    if dictionary_file is not None:
        path = Path(dictionary_file)
        if not path.is_file():
            raise ValueError(f"dictionary file {str(path)!r} does not exist")
        usrpwd["dictionary_file"] = str(path.resolve())
    if user is not None or password is not None:
        if not user or not password:
            raise ValueError("user and password go together")
        usrpwd.update(user=user, password=password)
    if usrpwd:
        conf["transport"]["auth"] = {"usrpwd": usrpwd}
    if extra:
        _merge(conf, extra)
    return _force_no_scouting(conf)


def client_config(
    connect: str | Iterable[str] = DEFAULT_ZENOH,
    *,
    shm: bool = False,
    user: str | None = None,
    password: str | None = None,
    timeout_ms: int = 2000,
    extra: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """A worker: a Zenoh client connecting to the coordinator's router at ``connect``.

    ``timeout_ms``: how long ``open()`` retries before failing (the worker retries opening by
    itself, so it can be started before the coordinator). ``user``/``password``: credentials for
    a router with user/password authentication."""
    conf = _base("client", shm)
    conf["connect"] = {"endpoints": _endpoints(connect), "timeout_ms": int(timeout_ms)}
    conf["listen"] = {"endpoints": []}
    if user is not None or password is not None:
        if not user or not password:
            raise ValueError("user and password go together")
        conf["transport"]["auth"] = {"usrpwd": {"user": user, "password": password}}
    if extra:
        _merge(conf, extra)
    return _force_no_scouting(conf)


def load_extra(path: str | Path | None) -> dict[str, Any] | None:
    """A JSON (or JSON5 without comments) file of extra Zenoh settings merged into a config."""
    if path is None:
        return None
    text = Path(path).read_text(encoding="utf-8")
    obj = json.loads(text)
    if not isinstance(obj, dict):
        raise ValueError(f"{path}: a Zenoh config must be a JSON object")
    return obj


def to_zenoh(conf: Mapping[str, Any]) -> Any:
    """A ``zenoh.Config`` from a dict built above (imports zenoh lazily)."""
    import zenoh

    return zenoh.Config.from_json5(json.dumps(conf))


def describe(conf: Mapping[str, Any]) -> str:
    """One line for logs, without secrets."""
    mode = conf.get("mode")
    ends = (conf.get("listen") if mode == "router" else conf.get("connect")) or {}
    auth = "usrpwd" if conf.get("transport", {}).get("auth") else "no auth"
    transport = conf.get("transport", {})
    shm = "shm on" if transport.get("shared_memory", {}).get("enabled") else "shm off"
    verb = "listening on" if mode == "router" else "connecting to"
    return f"zenoh {mode} {verb} {', '.join(ends.get('endpoints', []))} ({auth}, {shm})"


# ------------------------------------------------------------------------------ access control
def worker_access_control(
    prefix: str = "swarmpath",
    *,
    usernames: Iterable[str] = (),
    cert_common_names: Iterable[str] = (),
) -> dict[str, Any]:
    """Zenoh ``access_control`` for the coordinator's router: everything is denied unless a rule
    allows it, and the rules allow the worker logins (``usernames`` of usrpwd, or the
    ``cert_common_names`` of their TLS client certificates) exactly what a worker does:

    * send: put results and progress, query ``work``, declare its liveliness token, subscribe to
      its acks, to cancels and to wake hints;
    * receive: acks, cancels and wake hints, replies to its lease queries.

    The coordinator is the router itself (its own session is not a remote subject), so only it
    puts acks, cancels and wake hints, answers ``work`` and sees results and progress: a worker
    login cannot put on ``<prefix>/cancel``, ``<prefix>/wake`` or ``<prefix>/ack/*``, declare a
    ``work`` queryable, or subscribe to other workers' results and progress."""
    users, names = list(usernames), list(cert_common_names)
    if not users and not names:
        raise ValueError("access control needs worker usernames or certificate common names")
    p = prefix

    def rule(rid: str, flow: str, messages: list[str], keys: list[str]) -> dict[str, Any]:
        return {"id": rid, "permission": "allow", "flows": [flow], "messages": messages,
                "key_exprs": keys}

    rules = [
        rule("worker-puts", "ingress", ["put"], [f"{p}/results/*", f"{p}/progress/*"]),
        rule("worker-asks", "ingress", ["query"], [f"{p}/work"]),
        rule("worker-token", "ingress", ["liveliness_token"], [f"{p}/workers/*"]),
        rule("worker-listens", "ingress", ["declare_subscriber"],
             [f"{p}/ack/*", f"{p}/cancel", f"{p}/wake"]),
        rule("worker-hears", "egress", ["put"], [f"{p}/ack/*", f"{p}/cancel", f"{p}/wake"]),
        rule("worker-answered", "egress", ["reply"], [f"{p}/work"]),
        rule("worker-sees-work", "egress", ["declare_queryable"], [f"{p}/work"]),
    ]
    subject: dict[str, Any] = {"id": "workers"}
    if users:
        subject["usernames"] = users
    if names:
        subject["cert_common_names"] = names
    return {
        "enabled": True, "default_permission": "deny", "rules": rules, "subjects": [subject],
        "policies": [{"id": "workers", "rules": [r["id"] for r in rules],
                      "subjects": ["workers"]}],
    }


def tls_listen(ca: str | Path, certificate: str | Path, key: str | Path) -> dict[str, Any]:
    """Router side of mutual TLS: its certificate, and client certificates required (signed by
    ``ca``). Merge into a router config as ``extra`` (listen on ``tls/HOST:PORT``)."""
    return {"transport": {"link": {"tls": {
        "root_ca_certificate": str(ca), "listen_certificate": str(certificate),
        "listen_private_key": str(key), "enable_mtls": True,
    }}}}


def tls_connect(ca: str | Path, certificate: str | Path, key: str | Path) -> dict[str, Any]:
    """Client side of mutual TLS: the router is checked against ``ca`` (and its name against the
    endpoint's host), and the client shows its own certificate."""
    return {"transport": {"link": {"tls": {
        "root_ca_certificate": str(ca), "connect_certificate": str(certificate),
        "connect_private_key": str(key), "enable_mtls": True, "verify_name_on_connect": True,
    }}}}
