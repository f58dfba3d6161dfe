"""`swarmpath demo` (scripts/demo runs it): with --keep the coordinator and its dashboard stay up
after the jobs until Ctrl-C, and the demo says where every output is (issue 25: it shut the
coordinator down, so the dashboard it advertised could not be visited)."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import httpx

import owned
from test_service_e2e import ENV

WAIT = 600.0  # two tiny jobs through `swarmpath up` on a loaded machine


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def test_demo_keep_leaves_the_dashboard_up_and_lists_its_outputs(tmp_path: Path) -> None:
    out = tmp_path / "out"
    # files, not pipes: a pipe nobody reads fills (the tables, the legends, the coordinator's
    # log after the last line read) and blocks the demo, which then never ends on Ctrl-C
    stdout, stderr = tmp_path / "stdout.txt", tmp_path / "stderr.txt"
    with open(stdout, "w") as o, open(stderr, "w") as e:
        # started with SIGINT ignored, as under a parent that ignores it (nohup, a test runner
        # whose process ignored it once): Ctrl-C must stop the demo all the same
        proc = owned.popen([sys.executable, "-m", "swarmpath.cli", "demo", "--quick", "--keep",
                            "--out", str(out)], env=ENV, stdout=o, stderr=e, text=True,
                           preexec_fn=_ignore_sigint)
    try:
        deadline = time.monotonic() + WAIT
        while time.monotonic() < deadline and proc.poll() is None:
            if "Ctrl-C stops it" in stderr.read_text():
                break
            time.sleep(0.5)
        text = stderr.read_text()
        url = re.search(r"dashboard (http://127\.0\.0\.1:\d+)/", text)
        assert url, text[-3000:]
        page = httpx.get(url.group(1) + "/", timeout=30)  # the dashboard is still there
        assert page.status_code == 200 and "<html" in page.text
        jobs = httpx.get(url.group(1) + "/jobs", timeout=30).json()
        assert len(jobs) == 2 and {j["state"] for j in jobs} == {"done"}
        for job in jobs:  # every output is named, and is where it says
            mcap = out / f"demo-{job['id']}.mcap"
            layout = out / f"demo-{job['id']}.layout.json"
            assert f"job {job['id']}: {mcap}" in text and str(layout) in text
            assert mcap.stat().st_size > 0 and layout.stat().st_size > 0
            assert f"{url.group(1)}/ui/jobs/{job['id']}" in text
        assert str(out / "demo-data") in text and (out / "demo-data" / "swarmpath.sqlite3").exists()
        assert "the summary tables: above" in text
        proc.send_signal(signal.SIGINT)  # Ctrl-C
        try:
            code = proc.wait(120)
        except subprocess.TimeoutExpired:  # say what it was doing: its last lines and up's log
            code = None
        log = out / "demo-up.log"
        assert code == 0, (stderr.read_text()[-3000:],
                           log.read_text(errors="replace")[-3000:] if log.exists() else "")
        try:
            httpx.get(url.group(1) + "/healthz", timeout=5)
            raise AssertionError("the coordinator is still up after Ctrl-C")
        except httpx.TransportError:
            pass
        tables = stdout.read_text()  # the summary tables went to stdout
        assert "ICOOT" in tables and "OMPL-RRTstar" in tables
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(30)
