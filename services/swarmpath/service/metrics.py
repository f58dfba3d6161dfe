"""The coordinator's Prometheus metrics (``GET /metrics``)."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from swarmpath.service.coordinator import Coordinator


def metrics_text(core: Coordinator, now: float | None = None) -> str:
    """The coordinator's metrics in the Prometheus text exposition format (version 0.0.4)."""
    now = time.time() if now is None else now
    counters = core.store.counters()
    alive = core.worker_table.alive_count()
    active = core.store.active_leases()
    lines: list[str] = []

    def metric(name: str, kind: str, help_: str, value: float) -> None:
        lines.append(f"# HELP {name} {help_}")
        lines.append(f"# TYPE {name} {kind}")
        lines.append(f"{name} {value:g}" if isinstance(value, float) else f"{name} {value}")

    metric("swarmpath_queue_depth", "gauge",
           "Runs waiting to be leased (never leased, or requeued).", core.store.queue_depth())
    metric("swarmpath_runs_leased", "gauge", "Runs in active leases.",
           sum(len(x["runs"]) for x in active))
    metric("swarmpath_leases_active", "gauge", "Active leases.", len(active))
    metric("swarmpath_runs_per_second", "gauge",
           "Results accepted per second over the last minute.",
           round(core.runs_per_second(now), 3))
    metric("swarmpath_workers", "gauge", "Workers with a live liveliness token.", alive)
    metric("swarmpath_worker_table_entries", "gauge",
           f"Entries of the worker table (live and recently gone; at most "
           f"{core.worker_table.max_entries}).", len(core.worker_table))
    metric("swarmpath_workers_refused_total", "counter",
           "Liveliness tokens refused because the worker table was full of live workers.",
           core.worker_table.refused)
    metric("swarmpath_jobs_active", "gauge", "Queued or running jobs.",
           len(core.store.unfinished_jobs()))
    metric("swarmpath_lease_requeues_total", "counter",
           "Runs requeued because their lease expired or their worker vanished.",
           counters.get("requeued_runs", 0))
    metric("swarmpath_leases_total", "counter", "Leases granted.", counters.get("leases", 0))
    metric("swarmpath_results_accepted_total", "counter", "Results stored.",
           counters.get("results_accepted", 0))
    metric("swarmpath_results_duplicate_total", "counter", "Duplicate results ignored.",
           counters.get("duplicates", 0) + core.stats["duplicates_fast"])
    metric("swarmpath_results_stale_total", "counter",
           "Stale results rejected (fencing, or no valid proof of their lease's capability).",
           counters.get("stale", 0) + core.stats["unproven_results"])
    metric("swarmpath_messages_unproven_total", "counter",
           "Results and progress without a valid proof of their lease's capability (forged, "
           "replayed or of unknown leases) since this process started.", core.stats["unproven"])
    metric("swarmpath_messages_overload_total", "counter",
           "Lease queries and result/progress messages dropped because the coordinator's input "
           "queues were full (since this process started).", core.stats["overload"])
    metric("swarmpath_lease_requests_busy_total", "counter",
           "Lease requests answered no_work because results waited to be stored beyond the "
           "back-pressure bound (since this process started).", core.stats["busy"])
    metric("swarmpath_lease_requests_unauthenticated_total", "counter",
           "Lease requests refused because no valid proof of the login owning their worker id "
           "came with them (service/identity.py; since this process started).",
           core.stats["unauthenticated"])
    metric("swarmpath_messages_malformed_total", "counter",
           "Malformed messages dropped since this process started.", core.stats["malformed"])
    return "\n".join(lines) + "\n"
