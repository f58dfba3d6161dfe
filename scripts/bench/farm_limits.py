#!/usr/bin/env python3
"""What limits one coordinator, each piece in isolation (the inputs of docs/scale.md).

    .venv/bin/python scripts/bench/farm_limits.py [--runs 5000] [--iterations 500]
                                                  [--zenoh-messages 20000]

Results are what farm.py's simulated workers send: Table-2-sized benchmark runs (GWO, 2 dims,
2 agents, ``--iterations`` points per curve) built from a real run by
``farm_workers.simulated_results``, proven with their lease's capability and packed into
columnar result frames by the worker's own ``pack_lease_columns``; leases come from the coordinator
core's ``handle_lease_request``. No network except in the last row. The coordinator core runs
in this process on a fresh data directory (SQLite ``synchronous=FULL`` as in production); each
row times one piece over the same results (CPU seconds of this process per run, and wall):

* decode + proof: the coordinator's decoding of each result frame and the HMAC check of every
  result;
* SQLite: ``Store.accept_columns`` in groups of 64 frames (one transaction and fsync each);
* MCAP: the recorder writing each accepted run (``Coordinator._record``: /results and /curves
  messages, 1 MiB zstd chunks);
* dashboard: the live aggregates (``Dashboard.observe``);
* whole intake: ``Coordinator.handle_result_batches`` (all of the above and the acks) on a
  second, identical job;
* per message: a progress message renewing a lease (``handle_progress``: decode, proof,
  one SQLite transaction), a lease request granting one 8-run lease, and one answered
  ``no_work`` (what idle workers cost);
* Zenoh router: a router session and a client session in this process, the client putting
  payloads of the results' batch size with congestion control BLOCK to a subscriber of the
  router session that only counts them (messages/s and MB/s through loopback TCP).

Markdown on stdout.
"""

from __future__ import annotations

import argparse
import socket
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "services"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from farm_workers import simulated_results

from swarmpath.service.capability import progress_proof
from swarmpath.service.coordinator import Coordinator, CoordinatorSettings
from swarmpath.service.protocol import (
    BenchmarkJobSpec,
    Lease,
    LeaseBundle,
    LeaseRequest,
    RunProgress,
    decode_work_reply,
    encode,
)
from swarmpath.service.worker import pack_lease_columns

GROUP = 64  # result batches per transaction, as the bridge groups them


def timed(fn: Callable[[], Any]) -> tuple[float, float]:
    """(CPU seconds of this process, wall seconds) of fn()."""
    c0, w0 = time.process_time(), time.perf_counter()
    fn()
    return time.process_time() - c0, time.perf_counter() - w0


def lease_all(core: Coordinator, worker: str) -> list[Lease]:
    leases: list[Lease] = []
    while True:
        reply = decode_work_reply(core.handle_lease_request(encode(LeaseRequest(
            worker=worker, max_runs=1000, max_leases=64))))
        if isinstance(reply, LeaseBundle):
            leases += reply.leases
        elif isinstance(reply, Lease):
            leases.append(reply)
        else:
            return leases


def payloads(leases: list[Lease], worker: str) -> list[bytes]:
    data = [(lease.lease_id, lease.capability, d) for lease in leases
            for _run, d in simulated_results(lease, 0.003)]
    return pack_lease_columns(worker, data)


def coordinator_pieces(
    args: argparse.Namespace, tmp: Path, per_message: list[tuple[str, float, float, int]],
) -> list[tuple[str, float, float]]:
    core = Coordinator(CoordinatorSettings(data_dir=tmp / "store"))
    spec = BenchmarkJobSpec(kind="benchmark", algorithms=["GWO"], functions=["F1"], dims=[2],
                            runs=args.runs, agents=2, iterations=args.iterations)
    rows = []
    try:
        core.worker_alive("w1")
        job_a = core.submit(spec).id
        batches_a = payloads(lease_all(core, "w1"), "w1")
        job_b = core.submit(spec).id
        batches_b = payloads(lease_all(core, "w1"), "w1")
        core.submit(spec)  # a job of small leases (8 runs each) to renew
        target = core.sizer.target_seconds
        core.sizer.target_seconds = 1e-6
        leases_c = lease_all(core, "w1")
        core.sizer.target_seconds = target
        messages = [(core.keys.progress(lease.job_id), encode(RunProgress(
            lease_id=lease.lease_id, job_id=lease.job_id, worker="w1", cell=lease.cell,
            runs=lease.runs, seq=seq, proof=progress_proof(lease.capability, lease.lease_id, seq),
        ))) for seq in (1, 2) for lease in leases_c]
        key_b = core.keys.results(job_b)
        key_a = core.keys.results(job_a)
        decoded: list[Any] = []

        def decode_all() -> None:
            for p in batches_a:
                item = core._decode_batch(key_a, p)
                assert item is not None and all(c.capability for c in item[1])
                decoded.extend(item[1])

        rows.append(("decode + proof", *timed(decode_all)))

        def store_all() -> None:
            for i in range(0, len(decoded), GROUP):
                statuses = core.store.accept_columns(decoded[i:i + GROUP], time.time())
                assert {s for one in statuses for s in one} == {"accepted"}

        rows.append(("SQLite (accept_columns, FULL)", *timed(store_all)))
        every = [(c, list(range(len(c.runs)))) for c in decoded]
        rows.append(("MCAP (recorder)", *timed(lambda: core._record(job_a, every,
                                                                      time.time()))))
        rows.append(("dashboard aggregates", *timed(
            lambda: core.dashboard.observe_runs(job_a, [
                (c.cell, c.runs[k], c.status[k] == "ok", c.metrics[k], c.array("curve", k),
                 c.array("path", k), (c.seconds[k], c.cpu(k))) for c, ks in every for k in ks],
                time.time()))))

        def progress_all() -> None:
            for key, payload in messages:
                core.handle_progress(key, payload)

        cpu, wall = timed(progress_all)
        per_message.append(("progress message (lease renewal)", cpu, wall, len(messages)))
        core.submit(spec)
        requests = [0]

        def lease_requests() -> None:
            for _ in range(200):
                reply = core.handle_lease_request(encode(LeaseRequest(
                    worker="w1", max_runs=8, max_leases=1)))
                requests[0] += 1
                assert b'"lease"' in reply

        cpu, wall = timed(lease_requests)
        per_message.append(("lease request (one 8-run lease)", cpu, wall, requests[0]))
        lease_all(core, "w1")

        def empty_requests() -> None:
            for _ in range(200):
                reply = core.handle_lease_request(encode(LeaseRequest(worker="w1")))
                assert b'"no_work"' in reply

        cpu, wall = timed(empty_requests)
        per_message.append(("lease request answered no_work (nothing to lease)", cpu, wall, 200))

        def intake_all() -> None:
            for i in range(0, len(batches_b), GROUP):
                core.handle_result_batches([(key_b, p) for p in batches_b[i:i + GROUP]],
                                           parse_acks=False)

        rows.append(("whole intake (handle_result_batches)", *timed(intake_all)))
        status = core.store.job_status(job_b)
        assert status is not None and status.runs_done == args.runs, status
    finally:
        core.close()
    return rows


def zenoh_router(messages: int, size: int) -> tuple[float, float]:
    """(messages/s, MB/s) from a client session to a subscriber of a router session."""
    import zenoh

    from swarmpath.service.zenoh_config import client_config, router_config, to_zenoh

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    endpoint = f"tcp/127.0.0.1:{port}"
    router = zenoh.open(to_zenoh(router_config([endpoint])))
    got = [0]
    done = threading.Event()

    def count(_sample: Any) -> None:
        got[0] += 1
        if got[0] >= messages:
            done.set()

    sub = router.declare_subscriber("farm/limits/*", count)
    client = zenoh.open(to_zenoh(client_config([endpoint])))
    payload = b"x" * size
    try:
        time.sleep(0.5)
        started = time.perf_counter()
        for i in range(messages):
            client.put(f"farm/limits/{i % 8}", payload,
                       congestion_control=zenoh.CongestionControl.BLOCK)
        done.wait(120)
        wall = time.perf_counter() - started
    finally:
        sub.undeclare()
        client.close()
        router.close()
    return got[0] / wall, got[0] * size / wall / 1e6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5000)
    ap.add_argument("--iterations", type=int, default=500)
    ap.add_argument("--zenoh-messages", type=int, default=20000)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="farm-limits-") as tmp:
        per_message: list[tuple[str, float, float, int]] = []
        rows = coordinator_pieces(args, Path(tmp), per_message)
    print(f"{args.runs} runs, {args.iterations}-point curves\n")
    print("| piece | CPU ms/run | wall ms/run | runs/s of one core (CPU) |")
    print("|---|---|---|---|")
    for name, cpu, wall in rows:
        print(f"| {name} | {cpu * 1e3 / args.runs:.4f} | {wall * 1e3 / args.runs:.4f} | "
              f"{args.runs / cpu if cpu else float('inf'):,.0f} |")
    print("\n| message (count) | CPU ms each | wall ms each | per second of one core (CPU) |")
    print("|---|---|---|---|")
    for name, cpu, wall, n in per_message:
        print(f"| {name} ({n}) | {cpu * 1e3 / n:.4f} | {wall * 1e3 / n:.4f} | {n / cpu:,.0f} |")
    print("\n| Zenoh payload | messages/s | MB/s |")
    print("|---|---|---|")
    for size in (10_000, 512_000):
        n = args.zenoh_messages if size < 100_000 else max(200, args.zenoh_messages // 50)
        rate, mbs = zenoh_router(n, size)
        print(f"| {size:,} B | {rate:,.0f} | {mbs:,.0f} |")


if __name__ == "__main__":
    main()
