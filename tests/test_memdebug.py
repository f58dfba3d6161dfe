"""The coordinator's memory hook: off without SWARMPATH_TRACEMALLOC; with it, a loadable
allocation snapshot per ended job."""

from __future__ import annotations

import os
import signal
import tracemalloc

from swarmpath.service import memdebug


def test_snapshots_only_when_asked(tmp_path, monkeypatch):
    was = tracemalloc.is_tracing()
    monkeypatch.delenv(memdebug.ENV, raising=False)
    memdebug.dump("job0")
    assert not list(tmp_path.iterdir())
    monkeypatch.setenv(memdebug.ENV, str(tmp_path / "snaps"))
    try:
        memdebug.start()
        assert tracemalloc.is_tracing()
        kept = [bytearray(1000) for _ in range(100)]  # noqa: F841 - an allocation to find
        memdebug.dump("job1")
        (snap,) = (tmp_path / "snaps").iterdir()
        assert snap.name.endswith("-job1.tracemalloc")
        stats = tracemalloc.Snapshot.load(str(snap)).statistics("filename")
        assert any(s.traceback[0].filename == __file__ and s.size >= 100_000 for s in stats)
    finally:
        if not was:
            tracemalloc.stop()


def test_sigusr1_dumps_a_snapshot_in_the_middle_of_a_job(tmp_path, monkeypatch):
    was = tracemalloc.is_tracing()
    before = signal.getsignal(signal.SIGUSR1)
    monkeypatch.delenv(memdebug.ENV, raising=False)
    memdebug.install_signal()
    assert signal.getsignal(signal.SIGUSR1) is before  # untouched without the variable
    monkeypatch.setenv(memdebug.ENV, str(tmp_path / "snaps"))
    try:
        memdebug.start()
        memdebug.install_signal()
        os.kill(os.getpid(), signal.SIGUSR1)  # the handler runs before the next bytecode
        (snap,) = (tmp_path / "snaps").iterdir()
        assert snap.name.endswith("-signal.tracemalloc")
        assert tracemalloc.Snapshot.load(str(snap)).statistics("filename")
    finally:
        signal.signal(signal.SIGUSR1, before)
        if not was:
            tracemalloc.stop()
