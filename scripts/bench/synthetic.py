"""An in-process coordinator (REST only, on a free loopback port) and synthetic benchmark results
handed to its own result handler, so that the store, the aggregates and the exports see the real
path without running any optimizer (used by dashboard.py and exports.py).

Each run's curve is a random monotone best-so-far curve (as a worker's), its result encoded and
proven with its lease's capability, packed into batches as a worker sends them.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from service import free_port  # scripts/bench/service.py


def synthetic_results(lease: Any, rng: np.random.Generator, iterations: int,
                      evaluations: int) -> list[bytes]:
    """Encoded RunResults of a lease (with their proofs): monotone best-so-far curves of
    ``iterations`` values, ``evaluations`` reported per run."""
    from swarmpath.service.protocol import RunResult
    from swarmpath.service.worker.packing import fit_result

    n = len(lease.runs)
    steps = rng.exponential(0.02, size=(n, iterations))
    curves = 10.0 ** (4.0 - np.cumsum(steps, axis=1) * rng.uniform(0.2, 2.0, size=(n, 1)))
    out = []
    for i, run in enumerate(lease.runs):
        curve = np.minimum.accumulate(curves[i])
        out.append(fit_result(RunResult(
            lease_id=lease.lease_id, job_id=lease.job_id, cell=lease.cell, run=run,
            worker=lease.worker, seconds=0.001,
            metrics={"best_fitness": float(curve[-1]), "evaluations": evaluations},
            curve=curve.tolist(), best_position=rng.uniform(-1, 1, 30).tolist()),
            capability=lease.capability))
    return out


def fill(core: Any, spec: dict[str, Any], evaluations: int,
         on_progress: Callable[[int, int, float], None] | None = None) -> tuple[str, Any]:
    """Submit ``spec`` to ``core`` (a coordinator) and feed it synthetic results for every run,
    leased as worker "bench" (seed 1). ``on_progress(runs stored, runs total, seconds)`` after
    each round of leases. Returns the job id and its final status (the caller checks it)."""
    from swarmpath.service.protocol import (
        Lease,
        LeaseBundle,
        LeaseRequest,
        decode_work_reply,
        encode,
        parse_job_spec,
    )
    from swarmpath.service.worker import pack_lease_columns

    status = core.submit(parse_job_spec(spec))
    rng = np.random.default_rng(1)
    core.worker_alive("bench")
    done, t0 = 0, time.perf_counter()
    while True:
        reply = decode_work_reply(core.handle_lease_request(
            encode(LeaseRequest(worker="bench", max_runs=1000, max_leases=8))))
        leases = [reply] if isinstance(reply, Lease) else (
            reply.leases if isinstance(reply, LeaseBundle) else [])
        if not leases:
            break
        for lease in leases:
            results = synthetic_results(lease, rng, spec["iterations"], evaluations)
            core.handle_result_batches([(f"swarmpath/results/{lease.job_id}", p)
                                        for p in pack_lease_columns(
                                            "bench", [(lease.lease_id, lease.capability, d)
                                                      for d in results])])
            done += len(lease.runs)
        if on_progress is not None:
            on_progress(done, status.runs_total, time.perf_counter() - t0)
    return status.id, core.store.job_status(status.id)


def start_server(app: Any) -> tuple[Any, threading.Thread, str]:
    """Serve ``app`` with uvicorn on a free 127.0.0.1 port in a daemon thread; (server, thread,
    base URL) once it is listening. Stop it with ``server.should_exit = True`` and a join."""
    import uvicorn

    port = free_port()
    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning",
                                           timeout_graceful_shutdown=2))
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    while not server.started:
        time.sleep(0.05)
    return server, thread, f"http://127.0.0.1:{port}"
