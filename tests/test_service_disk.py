"""The coordinator on a full disk, and MCAP files that did not survive a crash whole (issue 25,
failures 7 and 8): a full store answers 507 and leases nothing, says so in /healthz, logs one
line instead of tracebacks, and resumes by itself once there is room; its recorder process does
not die and restart over and over; a finished job's truncated MCAP is rebuilt at start, never
served as it is."""

from __future__ import annotations

import io
import json
import logging
import os
import shutil
import sqlite3
import subprocess
import time
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from mcap.reader import make_reader

import owned
from swarmpath.service.coordinator import Coordinator
from swarmpath.service.http.app import create_app
from swarmpath.service.protocol import Lease, LeaseRequest, NoWork, decode_work_reply, encode
from swarmpath.service.recorder.common import intact
from swarmpath.service.settings import CoordinatorSettings
from swarmpath.service.worker import execute_lease, pack_batches
from test_service_e2e import ENV, PY, Service

SPEC = {"kind": "benchmark", "algorithms": ["GWO"], "functions": ["F1"], "dims": [3],
        "runs": 20, "agents": 6, "iterations": 5, "seed": 3}


class FullDisk:
    """The store's SQLite connection, failing every write with SQLITE_FULL while ``full`` (what
    SQLite reports when the disk of its database or WAL has no room; the real thing is the
    tmpfs test below)."""

    WRITES = ("INSERT", "UPDATE", "DELETE", "REPLACE")

    def __init__(self, db: sqlite3.Connection):
        self.db = db
        self.full = False

    def _check(self, sql: str) -> None:
        if self.full and sql.lstrip().upper().startswith(self.WRITES):
            exc = sqlite3.OperationalError("database or disk is full")
            exc.sqlite_errorcode = 13  # type: ignore[attr-defined]
            raise exc

    def execute(self, sql: str, *args: Any) -> Any:
        self._check(sql)
        return self.db.execute(sql, *args)

    def executemany(self, sql: str, *args: Any) -> Any:
        self._check(sql)
        return self.db.executemany(sql, *args)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.db, name)


def _lease(core: Coordinator, worker: str = "w1") -> Lease | NoWork:
    return decode_work_reply(core.handle_lease_request(
        encode(LeaseRequest(worker=worker, max_runs=5))))


def _send(core: Coordinator, lease: Lease) -> Any:
    acks = [core.handle_results(f"swarmpath/results/{lease.job_id}", payload)
            for payload in pack_batches(lease.worker, [d for _r, d in execute_lease(lease)])]
    return acks


def test_a_full_store_answers_507_leases_nothing_and_resumes_when_there_is_room(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    """The audit's failure 7 (disk full): POST /jobs answered 500 and leasing and results
    logged tracebacks. Now: 507 naming the store, no work handed out, results left
    unacknowledged (the worker sends them again), /healthz "degraded" with the problem, one
    ERROR line and no traceback; once there is room everything goes on by itself."""
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    app = create_app(CoordinatorSettings(data_dir=tmp_path / "data"), use_zenoh=False)
    with TestClient(app) as client:
        core: Coordinator = app.state.core
        job = client.post("/jobs", json=SPEC).json()["id"]
        core.worker_alive("w1")
        held = _lease(core)
        assert isinstance(held, Lease)
        disk = FullDisk(core.store._db)
        core.store._db = disk  # type: ignore[assignment]
        disk.full = True
        caplog.set_level(logging.INFO)
        r = client.post("/jobs", json=SPEC)
        assert r.status_code == 507, r.text
        assert "the store cannot write" in r.json()["detail"] and "nothing was stored" in \
            r.json()["detail"]
        assert r.headers["retry-after"] == "30"
        for _ in range(3):
            reply = _lease(core)
            assert isinstance(reply, NoWork) and "cannot store results" in reply.reason, reply
        assert _send(core, held) == [None]  # not stored, not acknowledged
        core.tick()
        health = client.get("/healthz").json()
        assert health["status"] == "degraded" and health["store"]["writable"] is False
        assert "database or disk is full" in health["store"]["problem"]
        assert not [rec for rec in caplog.records if rec.exc_info], "a traceback was logged"
        assert len([rec for rec in caplog.records if rec.levelno >= logging.ERROR]) == 1
        assert client.get("/jobs").status_code == 200  # reads go on

        disk.full = False  # room again
        assert isinstance(_lease(core), NoWork)  # within FULL_RETRY s of the last attempt
        core._lease_probe -= core.FULL_RETRY
        resent = _send(core, held)  # the worker's re-sent results are stored now
        assert resent[0] is not None and {s for _l, _r, s in resent[0].statuses()} == \
            {"accepted"}
        while isinstance(lease := _lease(core), Lease):
            _send(core, lease)
        assert client.get("/healthz").json()["status"] == "ok"
        assert client.get(f"/jobs/{job}").json()["state"] == "done"
        assert client.post("/jobs", json=SPEC).status_code == 201


def test_a_truncated_mcap_of_a_finished_job_is_rebuilt_at_start(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The audit's failure 8: after a restart the truncated MCAP of a finished job was served
    as it was (200, unreadable). Now the start checks every finished file (magic, footer and
    summary) and rebuilds one that is not whole from the store, as a deleted one is."""
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    settings = CoordinatorSettings(data_dir=tmp_path / "data")
    with TestClient(create_app(settings, use_zenoh=False)) as client:
        core = client.app.state.core  # type: ignore[attr-defined]
        job = client.post("/jobs", json=SPEC).json()["id"]
        core.worker_alive("w1")
        while isinstance(lease := _lease(core), Lease):
            _send(core, lease)
        first = client.get(f"/jobs/{job}/mcap")
        assert first.status_code == 200
    path = core.recorders.path(job)
    assert intact(path)
    for cut in (1, 100, len(first.content) // 2):
        path.write_bytes(first.content[:-cut])
        assert not intact(path)
        with TestClient(create_app(settings, use_zenoh=False)) as client:
            served = client.get(f"/jobs/{job}/mcap")
        assert served.status_code == 200
        reader = make_reader(io.BytesIO(served.content))
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        results = [json.loads(m.data) for _s, _c, m in reader.iter_messages(topics=["/results"])]
        assert sorted(r["run_id"] for r in results) == list(range(SPEC["runs"]))
        assert intact(path)


# ------------------------------------------------------------------- a real disk that fills up
def _unshare_ok() -> str | None:
    if shutil.which("unshare") is None:
        return "util-linux's unshare is not installed"
    probe = subprocess.run(["unshare", "-Urm", "sh", "-c", "mount -t tmpfs tmpfs /mnt"],
                           capture_output=True, text=True)
    if probe.returncode != 0:
        return f"cannot mount a tmpfs in a user namespace here: {probe.stderr.strip()[:200]}"
    return None


class TmpfsService(Service):
    """A coordinator whose data directory is a small tmpfs of its own (a user and mount
    namespace: nothing to clean up), reachable from here through /proc/PID/root."""

    def __init__(self, tmp: Path, size: str):
        super().__init__(tmp)
        self.size = size

    def _spawn(self, name: str, args: list[str]) -> Any:
        if name != "coordinator":
            return super()._spawn(name, args)
        self.data.mkdir(parents=True, exist_ok=True)
        script = (f'mount -t tmpfs -o size={self.size} tmpfs "{self.data}" && exec "{PY}" -m '
                  f'swarmpath.cli "$@"')
        log = open(self.tmp / f"{name}.log", "ab")  # closed at teardown
        self._logs.append(log)
        return owned.popen(["unshare", "-Urm", "sh", "-c", script, "sh", *args],
                           stdout=log, stderr=log, env=ENV)

    def inside(self, relative: str) -> Path:
        """A path of the coordinator's data directory as its mount namespace sees it."""
        assert self.coordinator is not None
        return Path(f"/proc/{self.coordinator.pid}/root") / str(self.data).lstrip("/") / \
            relative


def test_a_coordinator_on_a_full_tmpfs_waits_and_resumes(tmp_path: Path) -> None:
    """A real full disk under `swarmpath coordinator` (its recorder process included) while a
    worker runs a job: 507 for a new job, /healthz degraded, the recorder process is never
    restarted (it was seven times); room freed, the job completes with every run once in the
    store and in a whole MCAP."""
    reason = _unshare_ok()
    if reason is not None:
        pytest.skip(reason)
    svc = TmpfsService(tmp_path, "24m")
    try:
        svc.start_coordinator()
        spec = {**SPEC, "runs": 400, "iterations": 400}
        job = svc.submit(spec)
        svc.start_worker("w1")
        svc.wait_for(lambda: svc.status(job)["runs_done"] > 0, 120, "first results")
        filler = svc.inside("filler")
        with open(filler, "wb") as f:  # fill the tmpfs to the last block
            try:
                while True:
                    f.write(b"\0" * 65536)
                    f.flush()
            except OSError:
                pass
        svc.wait_for(lambda: svc.get("/healthz").json()["status"] == "degraded", 120,
                     "the store noticing the full disk")
        r = svc.http_client.post("/jobs", json=SPEC)
        assert r.status_code == 507, r.text
        time.sleep(5)  # the worker goes on asking and sending while the disk is full
        assert svc.status(job)["state"] == "running"
        os.unlink(filler)
        done = svc.wait_done(job, 300)
        assert done["state"] == "done" and done["runs_done"] == spec["runs"]
        assert svc.get("/healthz").json()["status"] == "ok"
        results = svc.mcap_results(job)
        assert sorted(m["run_id"] for m in results) == list(range(spec["runs"]))
        log = svc.log("coordinator")
        assert "the recorder process is gone" not in log, log[-3000:]
        assert "Traceback" not in log, log[-3000:]
    finally:
        svc.close()
