"""The coordinator's side of its workers (a mixin of
:class:`~swarmpath.service.coordinator.Coordinator`): the worker table fed by liveliness tokens
(:mod:`~swarmpath.service.worker_table`), the token look-ups that admit a worker refused while the
table was full, who may speak for a worker id (logins, :mod:`~swarmpath.service.identity`), and
the workers' status for ``GET /workers``."""

from __future__ import annotations

import logging
import threading
import time
from collections import Counter, OrderedDict
from collections.abc import Callable
from typing import Any

from swarmpath.service.identity import read_logins, refusal
from swarmpath.service.protocol import LeaseRequest, WorkerStatus
from swarmpath.service.settings import CoordinatorSettings
from swarmpath.service.util import short as _short
from swarmpath.service.worker_table import WorkerTable

log = logging.getLogger("swarmpath.coordinator")


class WorkerAdmission:
    """See the module docstring; the coordinator provides ``settings``, ``store``, ``stats`` and
    ``_lock``."""

    settings: CoordinatorSettings
    store: Any
    stats: Counter[str]
    _lock: threading.Lock

    def _init_admission(self, settings: CoordinatorSettings) -> None:
        self.worker_table = WorkerTable(settings.max_workers, settings.forget_workers_seconds)
        # looks a worker's liveliness token up; the answer comes as worker_alive (the bridge)
        self.check_token: Callable[[str], None] = lambda worker: None
        self._token_checks: OrderedDict[str, float] = OrderedDict()
        self._checks_in = [0, 0]  # (second, token lookups in it)
        # logins that may speak for workers (service/identity.py); none: nothing is checked
        self.logins = read_logins(settings.dictionary_file) if settings.dictionary_file else {}

    def _request_refusal(self, req: LeaseRequest) -> str | None:
        """Why a lease request may not speak for its worker id (None: it may): with logins, a
        proof of the login owning the id, newer than that worker's last request."""
        if not self.logins:
            return None
        refused = refusal(req.worker, req.login, req.issued, req.proof, self.logins)
        if refused is None and not self.worker_table.fresh(req.worker, req.issued):
            refused = "a lease request of this worker seen before (replayed?)"
        if refused is not None:
            self.stats["unauthenticated"] += 1
            n = self.stats["unauthenticated"]
            if n in (1, 10, 100) or n % 1000 == 0:
                log.warning("refused a lease request for worker %s: %s (%d so far)",
                            _short(req.worker, 128), refused, n)
        return refused

    def _seen(self, worker: str, now: float, **info: Any) -> None:
        self.worker_table.seen(worker, now, **info)

    def worker_alive(self, worker: str, now: float | None = None) -> None:
        """A liveliness token appeared (or was there when we started)."""
        now = time.time() if now is None else now
        if self.worker_table.alive(worker, now):
            log.info("worker %s is alive", worker)
        elif self.worker_table.refused == 1 or self.worker_table.refused % 1000 == 0:
            log.warning("worker table full (%d live workers): %s refused (%d so far)",
                        self.worker_table.max_entries, worker, self.worker_table.refused)

    def worker_mark_gone(self, worker: str) -> None:
        """Liveliness lost: first half, instant (no store access; safe in a callback)."""
        self.worker_table.gone(worker, time.time())

    def worker_gone(self, worker: str, now: float | None = None) -> int:
        """Liveliness lost: requeue the worker's unfinished runs at once."""
        self.worker_mark_gone(worker)
        n = self.store.requeue_worker(worker, now)
        log.info("worker %s is gone%s", worker, f"; {n} runs requeued" if n else "")
        return n

    def is_alive(self, worker: str) -> bool:
        return self.worker_table.is_alive(worker)

    #: A lease request of a worker without a table entry (its token was refused while the table
    #: was full, or its entry made room for others) has its token looked up, at most once per
    #: worker per TOKEN_CHECK_SECONDS and TOKEN_CHECKS_PER_SECOND in all, so that it is admitted
    #: once there is room.
    TOKEN_CHECK_SECONDS = 2.0
    TOKEN_CHECKS_PER_SECOND = 20
    _TOKEN_CHECKS_KEPT = 4096

    def _check_token(self, worker: str, now: float) -> None:
        with self._lock:
            last = self._token_checks.get(worker)
            if last is not None and now - last < self.TOKEN_CHECK_SECONDS:
                return
            second = int(now)
            if self._checks_in[0] != second:
                self._checks_in = [second, 0]
            if self._checks_in[1] >= self.TOKEN_CHECKS_PER_SECOND:
                return
            self._checks_in[1] += 1
            self._token_checks[worker] = now
            self._token_checks.move_to_end(worker)
            while len(self._token_checks) > self._TOKEN_CHECKS_KEPT:
                self._token_checks.popitem(last=False)
        try:
            self.check_token(worker)
        except Exception:
            log.exception("looking up the liveliness token of %s failed", _short(worker, 128))

    def workers(self) -> list[WorkerStatus]:
        """The workers of the table, and any other worker holding a lease (e.g. one of a previous
        coordinator's life that has not reconnected yet)."""
        activity = self.store.worker_activity()
        known = self.worker_table.snapshot()
        out = []
        for worker in sorted(set(known) | set(activity)):
            entry = known.get(worker)
            act = activity.get(worker, {})
            current = act.get("current_runs", [])
            if entry is None and not current:
                continue  # a worker of the past with nothing leased
            out.append(WorkerStatus(
                id=worker, host=entry.host if entry else "", pid=entry.pid if entry else 0,
                slots=entry.slots if entry else 1, current_runs=current,
                runs_done=int(act.get("runs_done", 0)),
                last_seen=entry.last_seen if entry else 0.0, alive=bool(entry and entry.alive),
                platform=entry.platform if entry else {},
            ))
        return out
