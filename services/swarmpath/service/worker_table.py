"""The coordinator's table of workers, bounded whatever the bus says.

An entry is created only by a worker's liveliness token (Zenoh delivers tokens only from
sessions the router admitted, i.e. with a login when authentication is on); any other message
naming a worker (a lease request, results, progress) only refreshes an existing entry, so made-up
ids cost nothing. An entry is *proven* once the worker made a valid lease request (with logins:
one proven by the login that owns its id, service/identity.py); a token alone proves nothing.

The table holds at most ``max_entries`` workers. When it is full a newcomer's token takes the
place of the longest-gone entry, else of the oldest unproven one (a token flood is unproven: it
cannot lock real workers out, issue 25); only when every entry is a proven live worker is the
newcomer refused (it gets no leases) and ``refused`` counts it
(``swarmpath_workers_refused_total``). A refused worker is admitted when it asks for work again
and there is room (the coordinator then looks its token up).
A token that leaves takes an unproven entry with it at once; a proven worker whose token went
away stays listed for ``forget_seconds`` (its last state is still worth showing), then its entry
is pruned. Thread-safe."""

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
    proven: bool = False  # a valid lease request was seen (a token alone proves nothing)
    issued: int = 0  # the last accepted lease request's ``issued`` (replays are refused)
    #: what its lease requests advertised (swarmpath.plugins.pins; bounded by the protocol),
    #: None when they advertised nothing
    extensions: dict[str, str] | None = None


class WorkerTable:
    def __init__(self, max_entries: int = 1024, forget_seconds: float = 600.0):
        if max_entries < 1:
            raise ValueError("max_entries must be at least 1")
        self.max_entries = int(max_entries)
        self.forget_seconds = float(forget_seconds)
        self.refused = 0
        self._entries: dict[str, WorkerEntry] = {}
        self._lock = threading.Lock()
        # (live workers, their slots), asked by every lease request: counted again only after
        # a change (None), not over the whole table per request
        self._live: tuple[int, int] | None = None

    def __len__(self) -> int:
        with self._lock:
            return len(self._entries)

    def alive(self, worker: str, now: float) -> bool:
        """A liveliness token appeared. False when the table is full of proven live workers."""
        with self._lock:
            entry = self._entries.get(worker)
            if entry is None:
                if len(self._entries) >= self.max_entries and not self._evict_one():
                    self.refused += 1
                    return False
                entry = self._entries[worker] = WorkerEntry()
            entry.alive, entry.gone_at, entry.last_seen = True, None, now
            self._live = None
            return True

    def _evict_one(self) -> bool:
        """Make room: the longest-gone entry out, else the oldest unproven live one."""
        gone = [(e.gone_at or 0.0, w) for w, e in self._entries.items() if not e.alive]
        if not gone:
            gone = [(e.last_seen, w) for w, e in self._entries.items() if not e.proven]
        if not gone:
            return False
        del self._entries[min(gone)[1]]
        self._live = None
        return True

    def gone(self, worker: str, now: float) -> None:
        with self._lock:
            entry = self._entries.get(worker)
            if entry is None or not entry.alive:
                return
            self._live = None
            if not entry.proven:  # a token that never asked for work leaves no trace
                del self._entries[worker]
                return
            entry.alive, entry.gone_at = False, now

    def fresh(self, worker: str, issued: int) -> bool:
        """Whether a lease request's ``issued`` is newer than the last one accepted for this
        worker (then it is remembered); an unknown worker has none."""
        with self._lock:
            entry = self._entries.get(worker)
            if entry is None:
                return True
            if issued <= entry.issued:
                return False
            entry.issued = issued
            return True

    def seen(self, worker: str, now: float, host: str = "", pid: int = 0, slots: int = 0,
             platform: dict[str, str] | None = None, proven: bool = False,
             extensions: dict[str, str] | object | None = ...) -> None:
        """A message of a known worker: refresh it (unknown ids are ignored). ``platform`` is
        already bounded (protocol.LeaseRequest validates it); ``proven``: a valid lease
        request."""
        with self._lock:
            entry = self._entries.get(worker)
            if entry is None:
                return
            entry.proven = entry.proven or proven
            entry.last_seen = max(entry.last_seen, now)
            if host:
                entry.host = host[:255]
            if pid:
                entry.pid = int(pid)
            if slots:
                slots = max(1, min(int(slots), MAX_SLOTS))
                if slots != entry.slots:
                    entry.slots, self._live = slots, None
            if platform:
                entry.platform = dict(platform)
            if extensions is not ...:  # only lease requests say what a worker runs
                entry.extensions = None if extensions is None else dict(
                    extensions)  # type: ignore[call-overload]

    def alive_extensions(self) -> dict[str, dict[str, str] | None]:
        """What each live, proven worker advertised (None: nothing)."""
        with self._lock:
            return {w: e.extensions for w, e in self._entries.items() if e.alive and e.proven}

    def platform(self, worker: str) -> dict[str, str]:
        """The numeric platform a worker last reported (empty if none or unknown)."""
        with self._lock:
            entry = self._entries.get(worker)
            return dict(entry.platform) if entry is not None else {}

    def is_alive(self, worker: str) -> bool:
        with self._lock:
            entry = self._entries.get(worker)
            return entry is not None and entry.alive

    def _live_counts(self) -> tuple[int, int]:
        if self._live is None:
            live = [e.slots for e in self._entries.values() if e.alive]
            self._live = (len(live), sum(live))
        return self._live

    def alive_count(self) -> int:
        with self._lock:
            return self._live_counts()[0]

    def alive_slots(self) -> int:
        with self._lock:
            return self._live_counts()[1]

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
