"""The HTTP side against a hostile browser (issue 25, failure 6): a Host header that is not one
of the coordinator's names is refused (a DNS-rebinding page is same-origin with whatever its
name resolves to, and the default configuration has no token), and every answer carries
X-Frame-Options / CSP frame-ancestors, X-Content-Type-Options and a Content-Security-Policy."""

from __future__ import annotations

from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from swarmpath.service.http.app import create_app
from swarmpath.service.http.middleware import (
    DASHBOARD_CSP,
    DATA_CSP,
    DOCS_CSP,
    allowed_hosts,
    host_name,
)
from swarmpath.service.settings import CoordinatorSettings

SPEC = {"kind": "benchmark", "algorithms": ["GWO"], "functions": ["F1"], "dims": [2],
        "runs": 2, "agents": 6, "iterations": 5, "seed": 1}


@pytest.fixture
def app(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    return create_app(CoordinatorSettings(data_dir=tmp_path / "data",
                                          allowed_hosts=allowed_hosts("127.0.0.1")),
                      use_zenoh=False)


def test_the_names_a_coordinator_answers() -> None:
    assert host_name("[::1]:8000") == "::1" and host_name("LocalHost.:80") == "localhost"
    assert host_name("evil.example") == "evil.example"
    assert allowed_hosts("127.0.0.1") == ["localhost", "127.0.0.1", "::1"]
    assert allowed_hosts("10.0.0.5") == ["localhost", "127.0.0.1", "::1", "10.0.0.5"]
    assert allowed_hosts("0.0.0.0", ["lab.example:8000"]) == [
        "localhost", "127.0.0.1", "::1", "*ip", "lab.example"]


def test_a_foreign_host_is_refused_before_anything_happens(app) -> None:
    with TestClient(app, base_url="http://127.0.0.1:8000") as client:
        core = app.state.core
        for host in ("evil.example", "evil.example:8000", "127.0.0.1.evil.example",
                     "localhost.evil.example", "10.0.0.9"):
            r = client.post("/jobs", json=SPEC, headers={"Host": host})
            assert r.status_code == 400, (host, r.text)
            assert "--allowed-host" in r.json()["detail"] and "SWARMPATH_ALLOWED_HOSTS" in \
                r.json()["detail"]
            assert r.headers["x-frame-options"] == "DENY"  # refusals carry the headers too
            assert client.get("/", headers={"Host": host}).status_code == 400
        assert core.store.list_jobs() == []  # nothing was created
        for host in ("127.0.0.1:8000", "localhost:8000", "[::1]:8000", "LOCALHOST"):
            r = client.post("/jobs", json=SPEC, headers={"Host": host})
            assert r.status_code == 201, (host, r.text)


def test_a_coordinator_on_every_interface_answers_addresses_and_named_hosts(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    names = allowed_hosts("0.0.0.0", ["lab.example"])
    app = create_app(CoordinatorSettings(data_dir=tmp_path / "data", allowed_hosts=names),
                     use_zenoh=False)
    with TestClient(app, base_url="http://10.1.2.3:8000") as client:
        for host, status in (("10.1.2.3:8000", 200), ("[fe80::1]", 200), ("lab.example", 200),
                             ("evil.example", 400), ("lab.example.evil.example", 400)):
            assert client.get("/healthz", headers={"Host": host}).status_code == status, host
    anything = create_app(CoordinatorSettings(data_dir=tmp_path / "any",
                                              allowed_hosts=allowed_hosts("0.0.0.0", ["*"])),
                          use_zenoh=False)
    with TestClient(anything) as client:
        assert client.get("/healthz", headers={"Host": "any.example"}).status_code == 200


def test_every_answer_carries_the_security_headers(app) -> None:
    with TestClient(app, base_url="http://127.0.0.1:8000") as client:
        answers = {"/": DASHBOARD_CSP, "/ui/submit": DASHBOARD_CSP, "/jobs": DATA_CSP,
                   "/static/common.js": DATA_CSP, "/openapi.json": DATA_CSP,
                   "/docs": DOCS_CSP, "/nowhere": DATA_CSP}
        for path, csp in answers.items():
            r = client.get(path)
            assert r.headers["content-security-policy"] == csp, path
            assert r.headers["x-frame-options"] == "DENY"
            assert r.headers["x-content-type-options"] == "nosniff"
            assert r.headers["referrer-policy"] == "no-referrer"
        assert "frame-ancestors 'none'" in DASHBOARD_CSP and "frame-ancestors 'none'" in DATA_CSP
        assert "'unsafe-inline'" not in DASHBOARD_CSP
        big = client.post("/jobs", content=b"x" * 1_100_000,  # refused by the body limit
                          headers={"content-type": "application/json"})
        assert big.status_code == 422 and big.headers["x-frame-options"] == "DENY"
