"""Processes end with whoever started them (issue 25 failure 10): a worker's slots when the worker
is SIGKILLed, idle or busy; the processes a test starts when pytest itself is killed."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

import owned

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent
GONE_WITHIN = 120.0  # a bound for a hang, not a speed claim (speed: scripts/bench/slot_orphans.py)


def alive(pid: int) -> bool:
    """Running (a zombie has ended: it only waits for its parent to read its status)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def wait_gone(pids: list[int]) -> list[int]:
    deadline = time.monotonic() + GONE_WITHIN
    while any(alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    return [p for p in pids if alive(p)]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="prctl subreaper: Linux only")
def test_slots_leave_at_once_when_their_worker_is_killed():
    """An idle slot whose worker died left through a normal interpreter shutdown (exit 0, 1.1-1.5
    s later on a busy machine); now it exits at once (status 3) from its wait for work, and a
    busy one from its parent-sentinel watch instead of a 0.5 s poll."""
    done = subprocess.run([sys.executable, str(ROOT / "scripts" / "bench" / "slot_orphans.py"),
                           "--trials", "1", "--json"], capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    rows = json.loads(done.stdout)
    assert sorted(r["state"] for r in rows) == ["busy", "busy", "idle", "idle"]
    assert [r["exit"] for r in rows] == [3, 3, 3, 3], rows


INNER = """
import sys, time
sys.path.insert(0, {tests!r})
import owned

def test_starts_a_server_and_hangs(tmp_path):
    proc = owned.popen(["sh", "-c", "sleep 600 & echo $! > {out}/child; wait"])
    with open({out!r} + "/leader.tmp", "w") as f:
        f.write(str(proc.pid))
    import os
    os.rename({out!r} + "/leader.tmp", {out!r} + "/leader")
    time.sleep(600)
"""


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc")
@pytest.mark.parametrize("how", [signal.SIGKILL, signal.SIGTERM], ids=["SIGKILL", "SIGTERM"])
def test_a_test_started_process_dies_when_pytest_is_killed(tmp_path, how):
    """A test run killed mid-test (SIGKILL: no cleanup of any kind runs) leaves nothing behind:
    neither the process the test started nor that process's own child."""
    test_file = tmp_path / "test_inner.py"
    test_file.write_text(textwrap.dedent(INNER.format(tests=str(TESTS), out=str(tmp_path))))
    inner = owned.popen([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                         "-p", "no:xdist", str(test_file)], cwd=tmp_path,
                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    pids: list[int] = []
    try:
        deadline = time.monotonic() + GONE_WITHIN
        started = lambda: (tmp_path / "leader").exists() and (tmp_path / "child").exists()  # noqa: E731
        while not started() and inner.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)  # a bound on the wait, not a claim about speed
        assert started() and inner.poll() is None, "the inner test never started its processes"
        time.sleep(0.2)  # the child's pid file is written by the shell: let it finish the line
        pids = [int((tmp_path / name).read_text()) for name in ("leader", "child")]
        assert all(alive(p) for p in pids)
        inner.send_signal(how)
        inner.wait(60)
        assert wait_gone(pids) == [], "left behind by the killed test run"
    finally:
        if inner.poll() is None:
            inner.kill()
            inner.wait(30)
        for pid in pids:
            if alive(pid):
                os.kill(pid, signal.SIGKILL)


def test_tests_start_long_lived_processes_through_owned_popen():
    """Every test that starts a process it does not wait for uses owned.popen (so a killed run
    cleans it up); subprocess.run and friends wait for theirs (each with a timeout)."""
    direct = {}
    for path in TESTS.glob("test_*.py"):
        text = path.read_text(encoding="utf-8")
        hits = [m.start() for m in re.finditer(r"subprocess\.Popen\(", text)]
        if hits:
            direct[path.name] = len(hits)
    assert direct == {}, f"subprocess.Popen outside owned.popen: {direct}"
