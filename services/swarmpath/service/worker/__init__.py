"""The worker: a Zenoh client that pulls leases from the coordinator, runs them, reports results.

Layers, the lower ones usable without the upper ones:

* :func:`execute_lease` - the work itself, a plain function: a benchmark lease is one vectorized
  ``minimize(..., run_ids=lease.runs)`` (split into memory-bounded batches, as ``swarmpath bench``
  does; runs are independent so the numbers are the same), a map lease one
  ``Episode(scenario, planner, seed, run, params)`` per run. Returns the encoded RunResults; a run
  that raises is a ``failed`` result (not retried); cancellation is checked every iteration/step.
* Slots - where leases execute, ``--slots N`` of them: spawned child processes by default (never
  forked: the parent runs Zenoh), or threads (``executor="thread"``, for tests and debugging).
  A child ignores SIGINT (the parent decides), and exits by itself when its parent disappears.
* :class:`Worker` - the protocol (schemas/README.md): liveliness token, pull loop with backoff,
  heartbeats (RunProgress) for running leases, results put with CongestionControl.BLOCK and
  re-sent until acknowledged, ``drop_leases`` and ``Cancel`` honoured, graceful stop on
  SIGTERM/SIGINT: stop pulling, let running leases finish for ``grace_seconds`` (then abort them),
  wait for the acks, undeclare the token (the coordinator requeues whatever was not reported).
"""

from swarmpath.service.worker.execution import (
    BATCH_ELEMENTS,
    Cancelled,
    benchmark_batches,
    execute_lease,
    load_scenario,
)
from swarmpath.service.worker.loop import Worker, _Active, run_worker
from swarmpath.service.worker.packing import (
    BATCH_BYTES,
    RESULT_BYTES,
    fit_result,
    pack_batches,
    pack_lease_columns,
)
from swarmpath.service.worker.settings import WorkerSettings, default_worker_id
from swarmpath.service.worker.slots import NotRun, ProcessSlot, Slot, ThreadSlot

__all__ = [
    "BATCH_BYTES",
    "BATCH_ELEMENTS",
    "RESULT_BYTES",
    "Cancelled",
    "NotRun",
    "ProcessSlot",
    "Slot",
    "ThreadSlot",
    "Worker",
    "WorkerSettings",
    "_Active",
    "benchmark_batches",
    "default_worker_id",
    "execute_lease",
    "fit_result",
    "load_scenario",
    "pack_batches",
    "pack_lease_columns",
    "run_worker",
]
