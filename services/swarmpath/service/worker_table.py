"""The coordinator's table of workers, bounded whatever the bus says.

An entry is created only by a worker's liveliness token (Zenoh delivers tokens only from
sessions the router admitted, i.e. with a login when authentication is on); any other message
naming a worker (a lease request, results, progress) only refreshes an existing entry, so made-up
ids cost nothing. A worker whose token went away stays listed for ``forget_seconds`` (its last
state is still worth showing), then its entry is pruned. The table holds at most ``max_entries``
workers: when full, the longest-gone entry makes room; when every entry is alive the newcomer is
refused (it gets no leases) and ``refused`` counts it (``swarmpath_workers_refused_total``).
Thread-safe."""

from __future__ import annotations

import threading
from dataclasses import dataclass, field, replace

MAX_SLOTS = 1024  # slots a worker may claim (the lease sizer sums them)


@dataclass
class WorkerEntry:
    host: str = ""
    pid: int = 0
    slots: int = 1
    alive: bool = True
    last_seen: float = 0.0
    gone_at: float | None = None
    extra: dict[str, str] = field(default_factory=dict)
    platform: dict[str, str] = field(default_factory=dict)


class WorkerTable:
    def __init__(self, max_entries: int = 1024, forget_seconds: float = 600.0):
        if max_entries < 1:
            raise ValueError("max_entries must be at least 1")
        self.max_entries = int(max_entries)
        self.forget_seconds = float(forget_seconds)
        self.refused = 0
        self._entries: dict[str, WorkerEntry] = {}
        self._lock = threading.Lock()

    def __len__(self) -> int:
        with self._lock:
            return len(self._entries)

    def alive(self, worker: str, now: float) -> bool:
        """A liveliness token appeared. False when the table is full of live workers."""
        with self._lock:
            entry = self._entries.get(worker)
            if entry is None:
                if len(self._entries) >= self.max_entries and not self._evict_one():
                    self.refused += 1
                    return False
                entry = self._entries[worker] = WorkerEntry()
            entry.alive, entry.gone_at, entry.last_seen = True, None, now
            return True

    def _evict_one(self) -> bool:
        gone = [(e.gone_at or 0.0, w) for w, e in self._entries.items() if not e.alive]
        if not gone:
            return False
        del self._entries[min(gone)[1]]
        return True

    def gone(self, worker: str, now: float) -> None:
        with self._lock:
            entry = self._entries.get(worker)
            if entry is not None and entry.alive:
                entry.alive, entry.gone_at = False, now

    def seen(self, worker: str, now: float, host: str = "", pid: int = 0, slots: int = 0,
             platform: dict[str, str] | None = None) -> None:
        """A message of a known worker: refresh it (unknown ids are ignored). ``platform`` is
        already bounded (protocol.LeaseRequest validates it)."""
        with self._lock:
            entry = self._entries.get(worker)
            if entry is None:
                return
            entry.last_seen = max(entry.last_seen, now)
            if host:
                entry.host = host[:255]
            if pid:
                entry.pid = int(pid)
            if slots:
                entry.slots = max(1, min(int(slots), MAX_SLOTS))
            if platform:
                entry.platform = dict(platform)

    def platform(self, worker: str) -> dict[str, str]:
        """The numeric platform a worker last reported (empty if none or unknown)."""
        with self._lock:
            entry = self._entries.get(worker)
            return dict(entry.platform) if entry is not None else {}

    def is_alive(self, worker: str) -> bool:
        with self._lock:
            entry = self._entries.get(worker)
            return entry is not None and entry.alive

    def alive_count(self) -> int:
        with self._lock:
            return sum(1 for e in self._entries.values() if e.alive)

    def alive_slots(self) -> int:
        with self._lock:
            return sum(e.slots for e in self._entries.values() if e.alive)

    def snapshot(self) -> dict[str, WorkerEntry]:
        with self._lock:
            return {w: replace(e, platform=dict(e.platform)) for w, e in self._entries.items()}

    def prune(self, now: float) -> int:
        """Forget workers gone for longer than forget_seconds. Returns how many."""
        with self._lock:
            old = [w for w, e in self._entries.items()
                   if not e.alive and (e.gone_at or 0.0) < now - self.forget_seconds]
            for w in old:
                del self._entries[w]
            return len(old)
