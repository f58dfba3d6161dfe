"""The worker's pulling side: lease requests with backoff and prefetch, granted leases held
until a slot is free, scenarios by reference resolved (cached or fetched) before they run."""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Sequence
from typing import Any

from swarmpath.service.identity import Issuer, request_proof
from swarmpath.service.protocol import (
    MAX_BUNDLE_LEASES,
    PROTOCOL_VERSION,
    Lease,
    LeaseBundle,
    LeaseRequest,
    NoWork,
    decode_work_reply,
    encode,
)
from swarmpath.service.scenarios import ByteLRU, ScenarioUnavailable, resolve
from swarmpath.service.worker.execution import failed_lease
from swarmpath.service.worker.extensions import (
    Capabilities,
    ExtensionUnavailable,
    check_pins,
)
from swarmpath.service.worker.reporting import Reporting, _Active
from swarmpath.service.worker.slots import Slot

log = logging.getLogger("swarmpath.worker")


def _version() -> str:
    try:
        from swarmpath import __version__
    except ImportError:  # pragma: no cover
        return ""
    return __version__


#: A wake hint ends the wait after an ``empty`` reply, but never sooner than this after it: a
#: forged hint (on a bus without access control) cannot make a worker ask more often.
HINT_MIN_WAIT = 0.25


class Pulling(Reporting):
    """Mixin of :class:`~swarmpath.service.worker.loop.Worker`: how it gets work. The state it
    uses is created by ``Worker.__init__``; ``_dispatch`` (start queued groups) is the Worker's."""

    host: str
    _platform: Any
    _slots: list[Slot]
    _querier: Any
    scenarios: ByteLRU
    _issued: Issuer
    _hinted: Any  # threading.Event: a wake hint arrived since the last lease request
    capabilities: Capabilities

    def _wants_work(self) -> bool:
        """Pull while fewer groups are held (running or queued) than ready slots + prefetch
        (nothing before a slot is ready: work is not taken before it can start)."""
        ready = [slot for slot in self._slots if slot.ready]
        if not ready:
            return False
        running = sum(1 for slot in ready if slot.busy)
        return running + len(self._queue) < len(ready) + max(0, self.settings.prefetch)

    def request(self) -> bytes:
        """A lease request; with a login, proven by its password (service/identity.py)."""
        login, issued, proof = "", 0, ""
        user, password = self.settings.user, self.settings.password
        if user and password:
            login, issued = user, self._issued()
            proof = request_proof(password, self.id, login, issued)
        return encode(LeaseRequest(
            worker=self.id, max_runs=self.settings.max_runs,
            max_leases=max(1, min(self.settings.max_leases, MAX_BUNDLE_LEASES)),
            host=self.host, pid=os.getpid(), slots=len(self._slots), version=_version(),
            protocol=PROTOCOL_VERSION, platform=self._platform, login=login, issued=issued,
            proof=proof, extensions=self.capabilities.advertisement(),
        ))

    def _ask(self) -> Lease | LeaseBundle | NoWork | None:
        """One lease request; None when nobody answered."""
        replies = list(self._querier.get(payload=self.request()))
        for reply in replies:
            ok = reply.ok
            if ok is None:
                err = reply.err
                log.warning("lease request failed: %s",
                            err.payload.to_bytes()[:200] if err is not None else "?")
                continue
            try:
                return decode_work_reply(ok.payload.to_bytes())
            except Exception as exc:
                log.warning("ignored a malformed lease reply: %s", " ".join(str(exc).split())[:200])
        return None

    def _pull_loop(self) -> None:
        """Ask for work whenever fewer groups are held than slots + prefetch: with prefetch the
        next group is already here when a slot finishes, so no slot waits for a round trip."""
        backoff = 0.0
        while not self._stop.is_set():
            with self._wake:
                while not self._stop.is_set() and not self._wants_work():
                    self._wake.wait(0.5)
            if self._stop.is_set():
                return
            self._hinted.clear()  # a hint from now on answers this request's "empty"
            try:
                reply = self._ask()
            except Exception as exc:
                log.warning("lease request failed: %s", exc)
                reply = None
            if reply is None:
                backoff = min(self.settings.max_backoff, max(1.0, backoff * 2))
                if backoff <= 1.0:
                    log.warning("no coordinator answers on %s; retrying", self.keys.work)
                self._stop.wait(backoff)
                continue
            if backoff:
                log.info("coordinator reachable again")
                backoff = 0.0
                self._resend_all()
            if isinstance(reply, NoWork):
                if reply.reason.startswith("busy"):  # behind on storing: our results wait
                    self._last_busy = time.monotonic()
                if reply.reason == "empty":
                    self._await_work(reply.retry_after)
                else:
                    self._stop.wait(reply.retry_after)
                continue
            self._take(reply.leases if isinstance(reply, LeaseBundle) else [reply])

    def _await_work(self, retry_after: float) -> None:
        """After an ``empty`` reply: wait ``retry_after`` s, or until the coordinator's wake
        hint (work appeared; one that came while the request was on its way counts), but at
        least HINT_MIN_WAIT."""
        if self._stop.wait(min(retry_after, HINT_MIN_WAIT)):
            return
        self._hinted.wait(max(0.0, retry_after - HINT_MIN_WAIT))

    def _on_wake(self, _sample: Any) -> None:
        """A wake hint (its payload is not read)."""
        self._hinted.set()

    def _take(self, leases: Sequence[Lease]) -> None:
        """Hold a group of granted leases and start it as soon as a slot is free."""
        mine = [lease for lease in leases if lease.worker == self.id]
        if len(mine) < len(leases):  # pragma: no cover - we asked for ourselves
            log.warning("ignored %d leases granted to another worker", len(leases) - len(mine))
        mine = self._with_scenarios(self._with_code(mine))
        if not mine:
            return
        with self._lock:
            now = time.monotonic()
            for lease in mine:
                self._active[lease.lease_id] = _Active(lease, None, now, now)
                log.debug("lease %s: %s runs %s", lease.lease_id, lease.cell, lease.runs)
            self._queue.append(mine)
        self._dispatch()

    def _with_code(self, leases: Sequence[Lease]) -> list[Lease]:
        """The leases whose pinned extensions this worker has; the others are not held (they
        expire and go to another worker: never failed for want of code)."""
        out = []
        for lease in leases:
            try:
                check_pins(lease.pins, lease.cell)
            except ExtensionUnavailable as exc:
                log.warning("lease %s not run: %s", lease.lease_id, exc)
                self.capabilities.refuse(lease.pins, str(exc))
                continue
            out.append(lease)
        return out

    def _with_scenarios(self, leases: Sequence[Lease]) -> list[Lease]:
        """The leases with their scenarios by reference in place (cached or fetched); a lease
        whose scenario is refused or wrong is reported at once, every run failed with the reason;
        one nobody answered for is left to expire (its runs are leased again)."""
        out: list[Lease] = []
        for lease in leases:
            spec = lease.spec
            ref = getattr(spec, "scenario_ref", None)
            if ref is None:
                out.append(lease)
                continue
            try:
                out.append(resolve(lease, self.keys.scenario(ref.sha256), self._fetch,
                                   self.scenarios))
            except ScenarioUnavailable as exc:
                if exc.transient:  # not reported: the lease expires and its runs go to others
                    log.warning("lease %s (%s) left: %s", lease.lease_id, lease.cell, exc)
                    continue
                log.error("lease %s (%s): %s", lease.lease_id, lease.cell, exc)
                self._publish_results(lease, failed_lease(lease, str(exc)))
        return out

    def _fetch(self, key: str, payload: bytes) -> bytes:
        """One query to the coordinator; its reply payload, or an error with its reason."""
        replies = list(self._session.get(key, payload=payload,
                                         timeout=self.settings.query_timeout))
        reason = "no reply from the coordinator"
        for reply in replies:
            if reply.ok is not None:
                return bytes(reply.ok.payload.to_bytes())
            if reply.err is not None:
                reason = "refused: " + reply.err.payload.to_bytes()[:300].decode(errors="replace")
        raise (TimeoutError if not replies else RuntimeError)(reason)

    def _start(self, lease: Lease) -> None:
        """Run one lease (as a group of one)."""
        self._take([lease])
