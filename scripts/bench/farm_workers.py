#!/usr/bin/env python3
"""Simulated workers of the farm simulator (scripts/bench/farm.py starts this as a subprocess).

    farm_workers.py --connect tcp/127.0.0.1:PORT --count N --id-prefix sim-0 [--slots S]
                    [--run-ms MS] [--max-runs R] [--max-leases L] [--stats FILE]

Each simulated worker is the real :class:`swarmpath.service.worker.Worker` (its own Zenoh client
session with the login from ``SWARMPATH_ZENOH_USER`` / ``SWARMPATH_ZENOH_PASSWORD``, liveliness
token, lease queries, heartbeats with their proofs, result batches put until acknowledged, drops
and cancels honoured) whose slots do not compute: a slot holds a group of leases for
``run-ms`` per run, then hands back each run's result built from a *template*: a real result of
the same cell spec computed once by :func:`swarmpath.service.worker.execute_lease` (curve of
``iterations`` points, best position and metrics; a map run's path and metrics), with the lease's
identity put in and encoded by the worker's own :func:`~swarmpath.service.worker.fit_result`;
the worker puts them as it puts real ones (columnar frames proven with the lease's capability).
Nothing of the protocol is re-implemented here.

The process runs until SIGTERM/SIGINT (or ``--seconds``), stops its workers gracefully, and writes
its measurements as JSON to ``--stats`` (or stdout): per worker the runs and leases done, lease
round trips (query to reply) and ack latencies (put of a result to its ack), in milliseconds.
"""

from __future__ import annotations

import argparse
import heapq
import json
import logging
import os
import random
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "services"))

from swarmpath.service.capability import new_capability
from swarmpath.service.protocol import (
    Ack,
    BenchmarkCell,
    Lease,
    LeaseBundle,
    MapCell,
    NoWork,
    RunResult,
    decode,
)
from swarmpath.service.result_frame import as_dict, decode_record
from swarmpath.service.worker import (
    Slot,
    Worker,
    WorkerSettings,
    execute_lease,
    fit_result,
)
from swarmpath.service.worker.slots import Outcomes

log = logging.getLogger("farm")

#: Real runs computed per cell spec for the templates (runs r use template r % pool).
POOL = 4
MAP_POOL = 1  # a map episode can take seconds


class Templates:
    """Real results per cell spec, computed once (thread-safe), reused for every simulated run."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._by_spec: dict[str, list[RunResult]] = {}

    def get(self, spec: BenchmarkCell | MapCell) -> list[RunResult]:
        key = spec.model_dump_json()
        with self._lock:
            pool = self._by_spec.get(key)
            if pool is None:
                n = POOL if isinstance(spec, BenchmarkCell) else MAP_POOL
                lease = Lease(
                    lease_id="template", worker="template", job_id="template", cell=spec.key,
                    cell_index=0, runs_per_cell=n, seed=0, runs=list(range(n)), spec=spec,
                    deadline=0.0, lease_seconds=1.0, heartbeat_seconds=1.0,
                    capability=new_capability())
                pool = [RunResult(**as_dict(decode_record(data)))
                        for _run, data in execute_lease(lease)]
                pool = [r.model_copy(update={"proof": None}) for r in pool]
                self._by_spec[key] = pool
            return pool


TEMPLATES = Templates()


def simulated_results(
    lease: Lease, seconds: float, wrong_key: bool = False
) -> list[tuple[int, bytes]]:
    """The lease's results, as the worker's execute_lease returns them (run, encoded result);
    ``wrong_key``: proven with a made-up capability instead of the lease's (a negative control:
    the coordinator must never accept them)."""
    pool = TEMPLATES.get(lease.spec)
    key = new_capability() if wrong_key else lease.capability
    out = []
    for run in lease.runs:
        template = pool[run % len(pool)]
        update: dict[str, Any] = {
            "lease_id": lease.lease_id, "job_id": lease.job_id, "cell": lease.cell,
            "run": run, "worker": lease.worker, "seconds": seconds,
        }
        update.update(_varied(template, lease.cell_index * lease.runs_per_cell + run))
        result = template.model_copy(update=update)
        out.append((run, fit_result(result, capability=key)))
    return out


def _varied(template: RunResult, run_id: int) -> dict[str, Any]:
    """The template's numbers scaled by a factor 1 + O(1e-6) unique to the run: every run's
    curve (and path times) differs from the others in its digits as real runs do (so the store
    and the MCAP compress them as they compress real runs), shape and monotonicity unchanged."""
    factor = 1.0 + ((run_id * 2654435761) % 1_000_003 + 1) * 1e-12
    out: dict[str, Any] = {}
    if template.curve is not None:
        out["curve"] = (np.asarray(template.curve) * factor).tolist()
        if "best_fitness" in template.metrics:
            out["metrics"] = {**template.metrics,
                              "best_fitness": float(template.curve[-1]) * factor}
    if template.path is not None:
        path = np.asarray(template.path)
        path[:, 2] *= factor
        out["path"] = [tuple(p) for p in path.tolist()]
    return out


class Clock:
    """One thread per process finishing the simulated slots' groups when their time is up."""

    def __init__(self) -> None:
        self._heap: list[tuple[float, int, Callable[[], None]]] = []
        self._cv = threading.Condition()
        self._n = 0
        threading.Thread(target=self._loop, name="farm-clock", daemon=True).start()

    def at(self, when: float, fn: Callable[[], None]) -> None:
        with self._cv:
            self._n += 1
            heapq.heappush(self._heap, (when, self._n, fn))
            self._cv.notify()

    def _loop(self) -> None:
        while True:
            with self._cv:
                while not self._heap or self._heap[0][0] > time.monotonic():
                    self._cv.wait(None if not self._heap else
                                  max(0.0, self._heap[0][0] - time.monotonic()))
                _when, _n, fn = heapq.heappop(self._heap)
            try:
                fn()
            except Exception:  # pragma: no cover - logged, the clock goes on
                log.exception("a simulated slot failed")


CLOCK: Clock | None = None


class SimSlot(Slot):
    """A slot that computes nothing: a group of leases takes ``run_seconds`` per run, then its
    results are the templates' (see the module docstring). Cancelled leases report Cancelled."""

    def __init__(self, index: int, on_done: Callable[[Slot, Outcomes], None],
                 run_seconds: float, wrong_key: bool = False, jitter: float = 0.0,
                 seed: int = 0):
        super().__init__(index, on_done)
        self.run_seconds = run_seconds
        self.wrong_key = wrong_key
        self.jitter = jitter  # a group takes run_seconds x runs x U(1 - jitter, 1 + jitter)
        self._rng = random.Random(seed)
        self._cancelled: set[str] = set()

    def submit(self, leases: Sequence[Lease]) -> None:
        group = list(leases)
        self.leases = group
        self._cancelled = set()
        runs = sum(len(lease.runs) for lease in group)
        assert CLOCK is not None
        spread = 1.0 + self.jitter * (2.0 * self._rng.random() - 1.0)
        CLOCK.at(time.monotonic() + runs * self.run_seconds * spread,
                 lambda: self._finish(group))

    def _finish(self, group: list[Lease]) -> None:
        from swarmpath.service.worker import Cancelled

        outcomes: Outcomes = []
        for lease in group:
            if lease.lease_id in self._cancelled:
                outcomes.append((lease, Cancelled(lease.lease_id)))
            else:
                outcomes.append((lease, simulated_results(lease, self.run_seconds,
                                                                  self.wrong_key)))
        self.leases = []
        self.on_done(self, outcomes)

    def cancel(self, lease_id: str | None = None) -> None:
        self._cancelled.update(lease.lease_id for lease in self.leases
                               if lease_id is None or lease.lease_id == lease_id)


class SimWorker(Worker):
    """The real worker with simulated slots, measuring lease round trips and ack latencies."""

    def __init__(self, settings: WorkerSettings, run_seconds: float, wrong_key: bool = False,
                 jitter: float = 0.0):
        super().__init__(settings)
        self.run_seconds = run_seconds
        self.wrong_key = wrong_key
        self.jitter = jitter
        self.lease_rtt_ms: list[float] = []
        self.ack_ms: list[float] = []
        self.no_work = 0
        self.leases_got = 0

    def new_slot(self, index: int) -> Slot:
        return SimSlot(index, self._on_slot_done, self.run_seconds, self.wrong_key,
                       self.jitter, hash((self.id, index)))

    def _ask(self) -> Lease | LeaseBundle | NoWork | None:
        started = time.perf_counter()
        reply = super()._ask()
        if reply is not None:
            self.lease_rtt_ms.append((time.perf_counter() - started) * 1e3)
            if isinstance(reply, NoWork):
                self.no_work += 1
            else:
                self.leases_got += len(reply.leases) if isinstance(reply, LeaseBundle) else 1
        return reply

    def _publish_many(self, items: Sequence[tuple[Lease, list[tuple[int, bytes]]]]) -> None:
        """With ``wrong_key`` the worker's frames are proven with a made-up capability (its
        records already are): the negative control reaches the coordinator's frame check."""
        if self.wrong_key:
            items = [(lease.model_copy(update={"capability": new_capability()}), results)
                     for lease, results in items]
        super()._publish_many(items)

    def _on_ack(self, sample: Any) -> None:
        now = time.monotonic()
        try:
            ack = decode(Ack, sample.payload.to_bytes())
        except Exception:
            ack = None
        if ack is not None:
            with self._lock:
                for lease_id, run, _status in ack.statuses():
                    entry = self._pending.get((lease_id, run))
                    if entry is not None and entry.sent:
                        self.ack_ms.append((now - entry.sent) * 1e3)
        super()._on_ack(sample)

    def stats(self) -> dict[str, Any]:
        return {"id": self.id, "runs_done": self.runs_done, "leases_done": self.leases_done,
                "leases_got": self.leases_got, "no_work": self.no_work,
                "lease_rtt_ms": [round(x, 3) for x in self.lease_rtt_ms],
                "ack_ms": [round(x, 3) for x in self.ack_ms]}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--connect", required=True)
    ap.add_argument("--count", type=int, default=1)
    ap.add_argument("--id-prefix", default="sim")
    ap.add_argument("--prefix", default="swarmpath")
    ap.add_argument("--slots", type=int, default=1)
    ap.add_argument("--run-ms", type=float, default=0.0)
    ap.add_argument("--max-runs", type=int, default=1000)
    ap.add_argument("--max-leases", type=int, default=32)
    ap.add_argument("--seconds", type=float, default=600.0, help="stop after this long at most")
    ap.add_argument("--run-jitter", type=float, default=0.0,
                    help="a group's time varies by this fraction either way (uniform)")
    ap.add_argument("--wrong-capability", action="store_true",
                    help="prove results with a made-up key (a negative control)")
    ap.add_argument("--stats", type=Path)
    ap.add_argument("--log-level", default="warning")
    args = ap.parse_args()
    logging.basicConfig(level=args.log_level.upper(), stream=sys.stderr,
                        format="%(asctime)s farm-workers %(levelname)s %(name)s: %(message)s")
    global CLOCK
    CLOCK = Clock()
    user = os.environ.get("SWARMPATH_ZENOH_USER")
    password = os.environ.get("SWARMPATH_ZENOH_PASSWORD")
    workers = [SimWorker(WorkerSettings(
        connect=[args.connect], prefix=args.prefix, slots=args.slots,
        worker_id=f"{args.id_prefix}-{i}", max_runs=args.max_runs, max_leases=args.max_leases,
        executor="thread", user=user, password=password, grace_seconds=5.0, ack_timeout=5.0,
    ), args.run_ms / 1e3, args.wrong_capability, args.run_jitter) for i in range(args.count)]
    done = threading.Event()

    def stop(_signum: int = 0, _frame: Any = None) -> None:
        done.set()

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    threads = [threading.Thread(target=w.run, name=f"worker-{w.id}", daemon=True)
               for w in workers]
    for t in threads:
        t.start()
    done.wait(args.seconds)
    for w in workers:
        w.stop()
    for t in threads:
        t.join(15.0)
    text = json.dumps({"pid": os.getpid(), "workers": [w.stats() for w in workers]})
    if args.stats:
        args.stats.write_text(text)
    else:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
