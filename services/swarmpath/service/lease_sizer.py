"""Lease sizing: how many runs of a cell make one lease (learned run costs, guided
self-scheduling near the end of a job)."""

from __future__ import annotations

import math
import threading
from collections.abc import Iterable, Sequence

from swarmpath.service.protocol import BenchmarkCell, Lease, MapCell


class LeaseSizer:
    """How many runs of a cell make about ``target_seconds`` of work.

    The cost of a run is learned from the results (``RunResult.seconds``, the run's share of its
    vectorized batch), per cell spec, as an exponential moving average; a cell without a result
    yet takes the average of its *family* (the benchmark cells that differ only in the function:
    the ones a worker stacks into one batch, see :mod:`swarmpath.service.worker.stacking`), and
    before any result of the family a rough prior is used (benchmark: from agents x iterations x
    dim; map: 5 s, i.e. one run). Without the family's average every cell of a study with few
    runs per cell would be leased at the prior, which is many times the real cost at the ICOOT
    paper's Table 2 setting, and bundles would hold one or two cells: nothing to stack.
    Benchmark leases get at least ``min_runs`` runs: runs of one cell are computed vectorized and a
    batch of one is several times slower per run than a batch of 30.

    Near the end of a job the target shrinks (guided self-scheduling): a lease takes at most
    ``remaining / (2 * slots)`` of the job's unleased work, ``slots`` being the slots of the live
    workers, so the last leases are small and no worker is left computing a big one alone while
    the others idle. A bundle (several leases in one reply) is filled until its leases' estimated
    seconds reach that target.

    The tail rule never takes a lease below ``slots / max_lease_rate`` seconds of work (nor above
    the target): the farm as a whole then asks for at most about ``max_lease_rate`` leases per
    second. A lease costs the coordinator about a millisecond of CPU whatever its size (the
    grant's transaction, its result message, its ack); without the floor a farm of K slots on a
    job of cheap runs was granted leases of ``remaining / 2K`` runs, so the leases (and the
    coordinator's CPU per run) grew with K: 28 leases at 2 workers, 989 at 200 on the same
    10,000 runs of 3.5 ms (scripts/bench/farm.py, docs/benchmarks.md). With the floor the
    workers left without a lease near the end of a job are the ones that would have cost more to
    serve than they computed."""

    MAP_PRIOR_SECONDS = 5.0
    MAX_ESTIMATES = 100_000  # cell and family costs kept (specs come from users)

    def __init__(self, target_seconds: float = 10.0, min_runs: int = 8, alpha: float = 0.3,
                 max_lease_rate: float = 100.0):
        self.target_seconds = float(target_seconds)
        self.max_lease_rate = float(max_lease_rate)
        self.min_runs = max(1, int(min_runs))
        self.alpha = alpha
        self.slots = 1  # slots of the live workers (the coordinator keeps it current)
        self._estimates: dict[str, float] = {}
        self._lock = threading.Lock()

    @staticmethod
    def cost_key(spec: BenchmarkCell | MapCell) -> str:
        return spec.model_dump_json()

    @staticmethod
    def family_key(spec: BenchmarkCell | MapCell) -> str | None:
        if not isinstance(spec, BenchmarkCell):
            return None
        return "family:" + spec.model_dump_json(exclude={"function"})

    @classmethod
    def prior(cls, spec: BenchmarkCell | MapCell) -> float:
        if isinstance(spec, BenchmarkCell):
            return spec.iterations * spec.agents * (2.5e-6 + 5e-7 * spec.dim)
        return cls.MAP_PRIOR_SECONDS

    def estimate(self, spec: BenchmarkCell | MapCell) -> float:
        family = self.family_key(spec)
        with self._lock:
            est = self._estimates.get(self.cost_key(spec))
            if est is None and family is not None:
                est = self._estimates.get(family)
        return self.prior(spec) if est is None else est

    def runs_for(
        self,
        spec: BenchmarkCell | MapCell,
        remaining: int | None = None,
        bundle: Sequence[Lease] = (),
    ) -> int:
        """Runs of a lease of ``spec``; 0 when ``bundle`` (the leases already in this reply)
        holds enough work. ``remaining``: the job's runs not leased yet (None: no tail rule)."""
        est = max(self.estimate(spec), 1e-6)
        budget = self.target_seconds
        if remaining is not None:
            slots = max(1, self.slots)
            floor = min(budget, slots / self.max_lease_rate)
            budget = max(floor, min(budget, remaining * est / (2 * slots)))
        if bundle:
            budget -= sum(len(lease.runs) * max(self.estimate(lease.spec), 1e-6)
                          for lease in bundle)
            if budget <= 0:
                return 0
        low = self.min_runs if isinstance(spec, BenchmarkCell) else 1
        return max(low, int(budget / est))

    def observe(self, spec: BenchmarkCell | MapCell, seconds_per_run: float) -> None:
        self.observe_many(spec, [seconds_per_run])

    def observe_many(self, spec: BenchmarkCell | MapCell, seconds: Iterable[float]) -> None:
        """Runs of one cell spec, in order (the same estimates as :meth:`observe` for each; the
        spec's keys are made once)."""
        keys = [k for k in (self.cost_key(spec), self.family_key(spec)) if k is not None]
        with self._lock:
            if len(self._estimates) + len(keys) > self.MAX_ESTIMATES and \
                    any(k not in self._estimates for k in keys):
                self._estimates.clear()  # bounded: costs are learnt again from the next results
            for seconds_per_run in seconds:
                if not (seconds_per_run > 0 and math.isfinite(seconds_per_run)):
                    continue
                for key in keys:
                    old = self._estimates.get(key)
                    self._estimates[key] = (
                        seconds_per_run if old is None
                        else old + self.alpha * (seconds_per_run - old)
                    )

