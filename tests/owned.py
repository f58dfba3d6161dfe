"""Processes a test starts die with the test run, even when pytest itself is killed (issue 25
failure 10: a killed run left the network-namespace test's worker alive, retrying forever).

``popen(cmd, **kwargs)`` is ``subprocess.Popen`` in a new session (its own process group, which
the test stops as before) that is also registered with a reaper: one small process per pytest
process, started on first use, reading the registered groups on its stdin. When pytest exits
normally it says so and the reaper leaves; when the pipe closes without that (pytest SIGKILLed,
killed by a signal, crashed) the reaper SIGKILLs every registered group still there. A group is
recognised by its leader's start time, so a reused pid is never hit. Workers started by a
registered ``swarmpath up`` and slots of a registered worker follow their own parents
(``--exit-with-parent``, the slots' parent sentinel).
"""

from __future__ import annotations

import atexit
import subprocess
import sys
import threading
from typing import Any

#: The reaper: lines "PGID STARTTIME" register a group, "bye" ends it quietly; end of input
#: without "bye" kills the registered groups that still exist.
REAPER = r"""
import os, signal, sys

def stat(pid):
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return fields[2], fields[3], fields[19]  # pgrp, session, starttime

def main():
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C on pytest reaches us too: wait for EOF
    groups = {}
    for line in sys.stdin:
        if line.strip() == "bye":
            return
        pgid, start = line.split()
        groups[int(pgid)] = start
    for pgid, start in groups.items():
        leader = stat(pgid)
        if leader is not None and leader[2] == start:
            os.killpg(pgid, signal.SIGKILL)
            continue
        for name in os.listdir("/proc"):  # the leader is gone: members of its own session
            if name.isdigit() and (s := stat(int(name))) and s[0] == s[1] == str(pgid):
                os.kill(int(name), signal.SIGKILL)

main()
"""

_lock = threading.Lock()
_reaper: subprocess.Popen[str] | None = None


def _start_time(pid: int) -> str:
    with open(f"/proc/{pid}/stat") as f:
        return f.read().rsplit(")", 1)[1].split()[19]


def _bye() -> None:
    if _reaper is not None and _reaper.poll() is None:
        try:
            _reaper.stdin.write("bye\n")  # type: ignore[union-attr]
            _reaper.stdin.close()  # type: ignore[union-attr]
        except OSError:
            pass
        _reaper.wait(10)


def register(pid: int) -> None:
    """Have the reaper kill the process group ``pid`` (a session leader) if pytest dies."""
    global _reaper
    with _lock:
        if _reaper is None or _reaper.poll() is not None:
            _reaper = subprocess.Popen([sys.executable, "-c", REAPER], stdin=subprocess.PIPE,
                                       text=True, start_new_session=True)
            atexit.register(_bye)
        try:
            start = _start_time(pid)
        except OSError:  # it has ended already
            return
        _reaper.stdin.write(f"{pid} {start}\n")  # type: ignore[union-attr]
        _reaper.stdin.flush()  # type: ignore[union-attr]


def popen(cmd: Any, **kwargs: Any) -> subprocess.Popen[Any]:
    """``subprocess.Popen`` in its own session, killed with its group if pytest dies."""
    kwargs.setdefault("start_new_session", True)
    proc: subprocess.Popen[Any] = subprocess.Popen(cmd, **kwargs)
    register(proc.pid)
    return proc
