"""The coordinator's memory hook: off without SWARMPATH_TRACEMALLOC; with it, a loadable
allocation snapshot per ended job."""

from __future__ import annotations

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
