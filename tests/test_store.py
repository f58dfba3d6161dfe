"""The SQLite job store: leasing, fencing, requeues, cancellation, crash safety, summaries."""

from __future__ import annotations

import csv
import io
import json
import os
import signal
import subprocess
import sys
import textwrap
import threading
from pathlib import Path

import pytest

from swarmpath.evidence.stats import describe, rank
from swarmpath.optimizers import minimize
from swarmpath.service.capability import progress_proof, result_proof
from swarmpath.service.protocol import Lease, MapJobSpec, RunResult, parse_job_spec
from swarmpath.service.store import Store, StoreError
from swarmpath.service.store import base as store_base

SPEC = {
    "kind": "benchmark", "algorithms": ["GWO", "PSO"], "functions": ["F1", "F9"], "dims": [4],
    "runs": 5, "agents": 6, "iterations": 8, "seed": 7,
}
T0 = 1_000_000.0


@pytest.fixture
def store(tmp_path):
    s = Store(tmp_path / "data")
    yield s
    s.close()


def signed(lease: Lease, result: RunResult) -> RunResult:
    """The result with its proof (the HMAC a worker makes with the lease's capability)."""
    return result.model_copy(update={"proof": result_proof(lease.capability, result)})


def beat(store: Store, lease: Lease, worker: str, seq: int = 1, **kw):
    """A proven heartbeat (progress message number ``seq``) of ``lease`` by ``worker``."""
    return store.heartbeat(lease.lease_id, worker, seq=seq,
                           proof=progress_proof(lease.capability, lease.lease_id, seq), **kw)


def execute(lease: Lease, worker: str | None = None, cpu: bool = True) -> list[RunResult]:
    """What a worker does with a benchmark lease (``cpu=False``: as a worker from before CPU
    times were sent)."""
    c = lease.spec
    res = minimize(c.algorithm, c.function, c.dim, c.agents, c.iterations, seed=lease.seed,
                   params=c.params, transform=c.transform, run_ids=lease.runs)
    return [
        signed(lease, RunResult(
            lease_id=lease.lease_id, job_id=lease.job_id, cell=lease.cell, run=r,
            worker=worker or lease.worker, seconds=res.seconds / len(lease.runs),
            cpu_seconds=res.cpu_seconds / len(lease.runs) if cpu else None,
            metrics={"best_fitness": float(res.best_fitness[i]),
                     "evaluations": int(res.evaluations[i])},
            curve=res.curve[i].tolist(), best_position=res.best_position[i].tolist(),
        ))
        for i, r in enumerate(lease.runs)
    ]


def drain(store: Store, worker: str = "w1", max_runs: int = 3, now: float = T0) -> int:
    n = 0
    while (lease := store.lease(worker, max_runs, now=now)) is not None:
        statuses = store.accept_results(execute(lease), now=now)
        assert set(statuses) == {"accepted"}
        n += len(statuses)
    return n


def direct_values(spec: dict) -> dict[tuple[str, str, int], list[float]]:
    out = {}
    for a in spec["algorithms"]:
        for f in spec["functions"]:
            for d in spec["dims"]:
                res = minimize(a, f, d, spec["agents"], spec["iterations"], runs=spec["runs"],
                               seed=spec["seed"])
                out[(a, f, d)] = res.best_fitness.tolist()
    return out


def check_summary_against(summary: dict, spec: dict) -> None:
    values = direct_values(spec)
    rows = {(r["algorithm"], r["function"], r["dim"]): r for r in summary["rows"]}
    assert set(rows) == set(values)
    for key, vals in values.items():
        expect = describe(vals)
        for stat in ("min", "max", "avg", "std", "median"):
            assert rows[key][stat] == pytest.approx(expect[stat], rel=1e-12, abs=0)
        assert rows[key]["runs"] == len(vals)
    for f in spec["functions"]:
        for d in spec["dims"]:
            ranks = rank({a: describe(values[(a, f, d)])["avg"] for a in spec["algorithms"]})
            for a in spec["algorithms"]:
                assert rows[(a, f, d)]["rank"] == ranks[a]


# ------------------------------------------------------------------------------------ basics
def test_create_job_and_status(store):
    job = store.create_job(parse_job_spec(SPEC), now=T0)
    st = store.job_status(job)
    assert (st.state, st.runs_total, st.runs_done, st.runs_failed) == ("queued", 20, 0, 0)
    assert st.created == T0 and st.started is None
    assert store.job_status("nope") is None
    assert [c["key"] for c in store.cells(job)] == ["GWO/F1/4", "GWO/F9/4", "PSO/F1/4",
                                                    "PSO/F9/4"]
    assert store.job_spec(job).functions == ["F1", "F9"]
    assert store.queue_depth() == 20
    assert [j.id for j in store.list_jobs()] == [job]
    assert store.list_jobs("done") == []
    with pytest.raises(ValueError):
        store.list_jobs("bogus")


def test_a_whole_job_runs_to_done_with_exact_statistics(store):
    job = store.create_job(SPEC, now=T0)
    assert drain(store) == 20
    st = store.job_status(job)
    assert (st.state, st.runs_done, st.finished) == ("done", 20, T0)
    summary = store.summary(job)
    assert summary["partial"] is False
    check_summary_against(summary, SPEC)
    rows = list(csv.DictReader(io.StringIO(store.summary_csv(job))))
    assert len(rows) == 4 and float(rows[0]["avg"]) == summary["rows"][0]["avg"]
    assert store.lease("w1", 5, now=T0) is None
    assert store.queue_depth() == 0


def test_lease_is_several_runs_of_one_cell(store):
    store.create_job(SPEC, now=T0)
    lease = store.lease("w1", 3, now=T0, lease_seconds=30)
    assert (lease.cell, lease.runs, lease.cell_index, lease.runs_per_cell) == (
        "GWO/F1/4", [0, 1, 2], 0, 5
    )
    assert lease.deadline == T0 + 30 and lease.heartbeat_seconds == 10
    assert lease.seed == 7 and lease.spec.agents == 6
    nxt = store.lease("w1", 3, now=T0)
    assert (nxt.cell, nxt.runs) == ("GWO/F1/4", [3, 4])  # never crosses a cell
    assert store.job_status(lease.job_id).state == "running"


def test_results_equal_a_direct_minimize_run_for_run(store):
    job = store.create_job(SPEC, now=T0)
    drain(store, max_runs=2)
    direct = direct_values(SPEC)
    for item in store.runs(job, limit=100):
        key = (item["algorithm"], item["function"], item["dim"])
        assert item["best_fitness"] == direct[key][item["run"]]


# ------------------------------------------------------------------------------------ fencing
def test_duplicate_results_are_ignored(store):
    job = store.create_job(SPEC, now=T0)
    lease = store.lease("w1", 2, now=T0)
    results = execute(lease)
    assert store.accept_results(results, now=T0) == ["accepted", "accepted"]
    assert store.accept_results(results, now=T0) == ["duplicate", "duplicate"]
    assert store.job_status(job).runs_done == 2
    assert store.counters()["duplicates"] == 2


def test_the_lease_run_cache_stays_bounded_within_one_job(store, monkeypatch):
    """Every granted lease's run set is cached for fencing; a job of many leases must not grow
    the cache past its bound (a lease whose set was dropped is still fenced from its row)."""
    monkeypatch.setattr(store_base, "LEASE_RUNS_CACHE", 3)
    store.create_job(SPEC, now=T0)
    leases = []
    while (lease := store.lease("w1", 1, now=T0)) is not None:
        leases.append(lease)
        assert len(store._lease_runs) <= 3
    assert len(leases) == 20
    assert leases[0].lease_id not in store._lease_runs
    first = execute(leases[0])
    assert store.accept_results(first, now=T0) == ["accepted"]
    wrong_run = first[0].model_copy(update={"run": leases[1].runs[0]})
    assert store.accept_results([signed(leases[0], wrong_run)], now=T0) == ["stale"]
    for lease in leases[1:]:
        assert store.accept_results(execute(lease), now=T0) == ["accepted"]
        assert len(store._lease_runs) <= 3


def test_stale_results_are_rejected(store):
    job = store.create_job(SPEC, now=T0)
    lease = store.lease("w1", 2, now=T0)
    good = execute(lease)[0]

    def changed(**update):  # a well-signed result that fencing must still refuse
        return signed(lease, good.model_copy(update=update))

    assert store.accept_result(changed(lease_id="unknown"), T0) == "stale"
    assert store.accept_result(changed(worker="w2"), T0) == "stale"
    assert store.accept_result(changed(run=4), T0) == "stale"  # not leased
    assert store.accept_result(changed(cell="PSO/F1/4"), T0) == "stale"
    assert store.accept_result(changed(job_id="other"), T0) == "stale"
    assert store.job_status(job).runs_done == 0
    assert store.accept_result(good, T0) == "accepted"
    assert store.counters()["stale"] == 5


def test_results_without_the_lease_capability_are_stale(store):
    """A forged result (no proof, a proof made with another secret, or a proven result altered
    after signing) is never stored, even naming the right lease, worker and run."""
    job = store.create_job(SPEC, now=T0)
    lease = store.lease("w1", 2, now=T0)
    assert len(lease.capability) == 64 and lease.capability != store.lease("w1", 1).capability
    good = execute(lease)[0]
    forged_value = good.model_copy(update={"metrics": {**good.metrics,
                                                       "best_fitness": -12345.0}})
    other_secret = good.model_copy(update={"proof": result_proof("0" * 64, good)})
    for forged in (good.model_copy(update={"proof": None}), other_secret, forged_value):
        assert store.accept_result(forged, T0) == "stale"
    assert store.job_status(job).runs_done == 0 and store.counters()["stale"] == 3
    assert store.accept_result(good, T0) == "accepted"
    assert store.run(job, good.run)["best_fitness"] == good.metrics["best_fitness"]


def test_heartbeat_needs_the_proof_and_a_fresh_seq(store):
    store.create_job(SPEC, now=T0)
    lease = store.lease("w1", 2, now=T0, lease_seconds=10)
    assert beat(store, lease, "w1", 1, now=T0 + 5, lease_seconds=10) == "active"
    # a replayed message (same seq) and one with a lower seq renew nothing
    assert beat(store, lease, "w1", 1, now=T0 + 9, lease_seconds=10) == "unknown"
    proof = progress_proof("f" * 64, lease.lease_id, 7)  # made without the capability
    assert store.heartbeat(lease.lease_id, "w1", now=T0 + 9, lease_seconds=10, seq=7,
                           proof=proof) == "unknown"
    assert store.requeue_expired(now=T0 + 16) == 2  # expired at T0 + 15


def test_requeue_on_expiry_and_late_result_of_the_old_lease(store):
    job = store.create_job({**SPEC, "runs": 3}, now=T0)
    old = store.lease("w1", 3, now=T0, lease_seconds=10)
    late = execute(old)
    assert store.requeue_expired(now=T0 + 5) == 0  # not yet
    assert store.requeue_expired(now=T0 + 11) == 3
    assert beat(store, old, "w1", now=T0 + 11) == "expired"
    new = store.lease("w2", 5, now=T0 + 12)
    assert (new.cell, new.runs) == (old.cell, old.runs)  # requeued runs first
    # the old worker's late result for run 0 arrives first: accepted once (runs are deterministic)
    assert store.accept_result(late[0], now=T0 + 13) == "accepted"
    statuses = store.accept_results(execute(new), now=T0 + 14)
    assert statuses == ["duplicate", "accepted", "accepted"]
    assert store.accept_results(late[1:], now=T0 + 15) == ["duplicate", "duplicate"]
    st = store.job_status(job)
    assert st.runs_done == 3
    assert store.active_leases() == []  # the new lease completed
    assert store.counters()["requeued_runs"] == 3


def test_expired_lease_only_requeues_runs_without_results(store):
    store.create_job(SPEC, now=T0)
    lease = store.lease("w1", 3, now=T0, lease_seconds=10)
    results = execute(lease)
    store.accept_result(results[0], now=T0 + 1)
    assert store.requeue_expired(now=T0 + 20) == 2
    again = store.lease("w2", 5, now=T0 + 21)
    assert again.runs == [1, 2]


def test_heartbeat_extends_the_deadline(store):
    store.create_job(SPEC, now=T0)
    lease = store.lease("w1", 2, now=T0, lease_seconds=10)
    assert beat(store, lease, "w1", now=T0 + 8, lease_seconds=10) == "active"
    assert store.requeue_expired(now=T0 + 15) == 0
    assert store.requeue_expired(now=T0 + 19) == 2
    nope = lease.model_copy(update={"lease_id": "nope"})
    assert beat(store, nope, "w1", 2, now=T0) == "unknown"
    assert beat(store, lease, "w2", 3, now=T0) == "unknown"


def test_requeue_on_worker_loss(store):
    job = store.create_job(SPEC, now=T0)
    a = store.lease("w1", 2, now=T0, lease_seconds=1000)
    b = store.lease("w2", 2, now=T0, lease_seconds=1000)
    activity = store.worker_activity()
    assert activity["w1"]["current_runs"] == [f"{job}:0", f"{job}:1"]
    assert store.requeue_worker("w1", now=T0 + 1) == 2
    assert store.requeue_worker("w1", now=T0 + 1) == 0
    assert [x["lease_id"] for x in store.active_leases()] == [b.lease_id]
    c = store.lease("w3", 5, now=T0 + 2)
    assert c.runs == a.runs
    assert beat(store, a, "w1", now=T0 + 2) == "released"


def test_release_returns_a_lease(store):
    store.create_job(SPEC, now=T0)
    a = store.lease("w1", 2, now=T0)
    assert store.release(a.lease_id, "w2", now=T0) == 0  # not its lease
    assert store.release(a.lease_id, "w1", now=T0) == 2
    assert store.lease("w1", 5, now=T0).runs == [0, 1]


def test_cancel(store):
    job = store.create_job(SPEC, now=T0)
    lease = store.lease("w1", 2, now=T0, lease_seconds=5)
    results = execute(lease)
    store.accept_result(results[0], now=T0)
    store.requeue_expired(now=T0 + 10)  # run 1 requeued
    assert store.cancel(job, now=T0 + 11) == "cancelled"
    assert store.lease("w1", 5, now=T0 + 12) is None  # never leases cancelled jobs
    assert store.accept_result(results[1], now=T0 + 12) == "stale"
    st = store.job_status(job)
    assert (st.state, st.runs_done, st.finished) == ("cancelled", 1, T0 + 11)
    assert store.cancel(job) == "cancelled"
    assert store.cancel("nope") is None
    assert store.queue_depth() == 0
    states = {i["state"] for i in store.runs(job, limit=100)}
    assert states == {"done", "cancelled"}
    assert store.summary(job)["partial"] is True


def test_cancel_of_a_finished_job_changes_nothing(store):
    job = store.create_job({**SPEC, "runs": 1}, now=T0)
    drain(store)
    assert store.cancel(job) == "done"


def test_failed_runs(store):
    job = store.create_job({**SPEC, "algorithms": ["GWO"], "functions": ["F1"], "runs": 2}, T0)
    lease = store.lease("w1", 2, now=T0)
    ok, bad = execute(lease)
    bad = signed(lease, bad.model_copy(update={"status": "failed", "failure": "boom",
                                               "metrics": {}, "curve": None,
                                               "best_position": None}))
    assert store.accept_results([ok, bad], now=T0) == ["accepted", "accepted"]
    st = store.job_status(job)
    assert (st.state, st.runs_done, st.runs_failed) == ("done", 1, 1)
    item = store.run(job, 1)
    assert (item["state"], item["failure"]) == ("failed", "boom")
    row = store.summary(job)["rows"][0]
    assert (row["runs"], row["failed"]) == (1, 1)


def test_a_job_whose_runs_all_fail_is_failed(store):
    job = store.create_job({**SPEC, "algorithms": ["GWO"], "functions": ["F1"], "runs": 1}, T0)
    lease = store.lease("w1", 1, now=T0)
    r = signed(lease, execute(lease)[0].model_copy(update={"status": "failed", "failure": "x"}))
    store.accept_result(r, now=T0)
    assert store.job_status(job).state == "failed"
    row = store.summary(job)["rows"][0]
    assert row["avg"] is None and row["rank"] is None


# --------------------------------------------------------------------------------- scheduling
def test_fair_across_jobs_and_fifo(store):
    a = store.create_job(SPEC, now=T0)
    b = store.create_job(SPEC, now=T0 + 1)
    order = [store.lease("w", 1, now=T0).job_id for _ in range(6)]
    assert order == [a, b, a, b, a, b]
    c = store.create_job(SPEC, now=T0 + 2)  # a new job gets the next turn
    assert store.lease("w", 1, now=T0).job_id == c


def test_finished_jobs_leave_the_rotation(store):
    small = store.create_job({**SPEC, "algorithms": ["GWO"], "functions": ["F1"], "runs": 1}, T0)
    big = store.create_job(SPEC, now=T0)
    first = store.lease("w", 5, now=T0)
    assert first.job_id == small
    store.accept_results(execute(first), now=T0)
    assert {store.lease("w", 1, now=T0).job_id for _ in range(3)} == {big}


# ---------------------------------------------------------------------------------- run views
def test_runs_pages_and_single_run(store):
    job = store.create_job(SPEC, now=T0)
    lease = store.lease("w1", 2, now=T0)
    store.accept_result(execute(lease)[0], now=T0)
    page = store.runs(job, limit=4, offset=0)
    assert [i["run_id"] for i in page] == [0, 1, 2, 3]
    assert [i["state"] for i in page] == ["done", "leased", "queued", "queued"]
    assert page[0]["worker"] == "w1" and page[1]["worker"] == "w1" and page[2]["worker"] is None
    assert page[0]["algorithm"] == "GWO" and page[0]["function"] == "F1" and page[0]["dim"] == 4
    assert isinstance(page[0]["best_fitness"], float) and page[0]["evaluations"] > 0
    assert "best_fitness" not in page[1]
    tail = store.runs(job, limit=10, offset=15)
    assert [i["run_id"] for i in tail] == [15, 16, 17, 18, 19]
    assert (tail[0]["cell"], tail[0]["run"]) == ("PSO/F9/4", 0)
    assert store.runs(job, limit=10, offset=20) == []
    assert store.runs("nope") is None
    one = store.run(job, 0)
    assert len(one["curve"]) == 8 and len(one["best_position"]) == 4
    assert one["curve"][-1] == one["best_fitness"]
    assert store.run(job, 1)["state"] == "leased" and "curve" not in store.run(job, 1)
    assert store.run(job, 20) is None and store.run("nope", 0) is None


def test_partial_summary_while_running(store):
    job = store.create_job(SPEC, now=T0)
    lease = store.lease("w1", 3, now=T0)
    store.accept_results(execute(lease), now=T0)
    s = store.summary(job)
    assert s["partial"] is True and s["state"] == "running"
    rows = s["rows"]
    assert rows[0]["runs"] == 3 and rows[0]["rank"] == 1
    assert rows[1]["runs"] == 0 and rows[1]["avg"] is None


@pytest.mark.parametrize("transform", ["none", "shift"])
def test_summary_flags_origin_suspect_cells_of_untransformed_jobs(store, transform):
    """HPO's hunter rule reaches exact zeros on plain F1 (optimum at the origin), not on F5."""
    spec = {**SPEC, "algorithms": ["HPO"], "functions": ["F1", "F5"], "dims": [10], "runs": 2,
            "agents": 20, "iterations": 300, "transform": transform}
    job = store.create_job(spec, now=T0)
    drain(store)
    flags = {r["function"]: r["origin_suspect"] for r in store.summary(job)["rows"]}
    assert flags == ({"F1": True, "F5": False} if transform == "none" else
                     {"F1": None, "F5": None})


def test_map_summary(store):
    spec = MapJobSpec.model_construct(kind="map", planners=["A", "B"], maps=["m"], runs=3,
                                      seed=1, params={})
    job = store.create_job(spec, now=T0)
    metrics = {
        "A": [{"success": True, "length": 10.0, "error": 0.1, "seconds": 1.0, "gap": 0.1,
               "collisions": 0, "min_clearance": 0.4},
              {"success": True, "length": 12.0, "error": 0.2, "seconds": 2.0, "gap": 0.3,
               "collisions": 0, "min_clearance": 0.25},
              {"success": False, "length": 3.0, "error": 5.0, "seconds": 3.0, "gap": None,
               "collisions": 3, "robot_driven_contacts": 1, "obstacle_driven_contacts": 2,
               "min_clearance": -0.05}],
        "B": [{"success": True, "length": 11.0, "error": 0.0, "seconds": 0.5, "gap": None,
               "collisions": 0}] * 3,
    }
    while (lease := store.lease("w", 3, now=T0)) is not None:
        planner = lease.spec.planner
        store.accept_results([
            signed(lease, RunResult(
                lease_id=lease.lease_id, job_id=job, cell=lease.cell, run=r, worker="w",
                seconds=1.0, metrics=metrics[planner][r], path=[(0.0, 0.0, 0.0), (1.0, 1.0, 1.0)]))
            for r in lease.runs
        ], now=T0)
    s = store.summary(job)
    assert s["state"] == "done" and s["columns"][:2] == ["planner", "map"]
    a, b = s["rows"]
    assert a["success_rate"] == pytest.approx(2 / 3)
    assert a["length_mean"] == pytest.approx(11.0)
    assert a["length_std"] == pytest.approx(describe([10.0, 12.0])["std"])
    assert a["error_mean"] == pytest.approx((0.1 + 0.2 + 5.0) / 3)
    assert a["seconds_mean"] == pytest.approx(2.0)
    assert a["gap_mean"] == pytest.approx(0.2)
    assert a["collisions"] == 3
    assert (a["robot_driven_contacts"], a["obstacle_driven_contacts"]) == (1, 2)
    assert (b["robot_driven_contacts"], b["obstacle_driven_contacts"]) == (0, 0)
    # the least clearance over every run, the failed one too (plan's "Clearance min")
    assert a["min_clearance"] == -0.05 and b["min_clearance"] is None
    assert b["success_rate"] == 1.0 and b["gap_mean"] is None and b["length_std"] == 0.0
    item = store.run(job, 0)
    assert item["planner"] == "A" and item["map"] == "m" and item["length"] == 10.0
    assert item["bucket"] is None  # the map has no MovingAI bucket
    assert item["path"] == [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]
    # a map without a MovingAI bucket: the column is empty, and the summary has no curve
    assert "planner,map,bucket,runs" in store.summary_csv(job)
    assert a["bucket"] is None and s["buckets"] == []


def test_non_finite_values_are_json_safe(store):
    job = store.create_job({**SPEC, "algorithms": ["GWO"], "functions": ["F1"], "runs": 2}, T0)
    lease = store.lease("w", 2, now=T0)
    inf = {"best_fitness": float("inf")}
    rs = [signed(lease, r.model_copy(update={"metrics": {**r.metrics, **inf}}))
          for r in execute(lease)]
    store.accept_results(rs, now=T0)
    row = store.summary(job)["rows"][0]
    assert row["avg"] == "inf" and row["std"] == 0.0
    json.dumps(store.summary(job), allow_nan=False)
    json.dumps(store.runs(job), allow_nan=False)


# --------------------------------------------------------------------------------- concurrency
def test_threads_share_a_store(store):
    job = store.create_job({**SPEC, "runs": 25}, now=T0)
    errors = []

    def worker(name: str) -> None:
        try:
            while (lease := store.lease(name, 4, now=T0)) is not None:
                results = execute(lease)
                store.accept_results(results, now=T0)
                store.accept_results(results[:1], now=T0)  # a retry: duplicate
        except Exception as exc:  # pragma: no cover - reported below
            errors.append(exc)

    threads = [threading.Thread(target=worker, args=(f"w{i}",)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    assert not errors
    st = store.job_status(job)
    assert (st.state, st.runs_done) == ("done", 100)
    assert len(store.runs(job, limit=1000)) == 100


# --------------------------------------------------------------------------------- durability
CRASHER = textwrap.dedent(
    """
    import os, signal, sys, json
    from swarmpath.service.store import Store
    sys.path.insert(0, {tests!r})
    from test_store import SPEC, T0, execute
    store = Store({data!r})
    job = store.create_job(SPEC, now=T0)
    first = store.lease("w1", 3, now=T0, lease_seconds=10)
    store.accept_results(execute(first), now=T0)          # acknowledged: must survive
    second = store.lease("w1", 2, now=T0, lease_seconds=10)  # outstanding at the crash
    unacked = execute(second)
    with open({out!r}, "w") as f:
        json.dump({{"job": job, "late": [r.model_dump_json() for r in unacked]}}, f)
    os.kill(os.getpid(), signal.SIGKILL)                     # no close, no cleanup
    """
)


def test_crash_and_reopen_loses_nothing_and_duplicates_nothing(tmp_path):
    data, out = tmp_path / "data", tmp_path / "out.json"
    code = CRASHER.format(tests=str(Path(__file__).parent), data=str(data), out=str(out))
    proc = subprocess.run([sys.executable, "-c", code], timeout=120, capture_output=True)
    assert proc.returncode == -signal.SIGKILL, proc.stderr.decode()[-2000:]
    info = json.loads(out.read_text())
    job = info["job"]
    with Store(data) as store:
        st = store.job_status(job)
        assert (st.state, st.runs_total, st.runs_done) == ("running", 20, 3)
        # the outstanding lease is requeued only once its deadline passes
        assert store.requeue_expired(now=T0 + 5) == 0
        fresh = store.lease("w2", 3, now=T0 + 5)
        assert fresh.cell == "GWO/F9/4"
        store.accept_results(execute(fresh), now=T0 + 5)
        assert store.requeue_expired(now=T0 + 11) == 2
        # a late result of the pre-crash lease is still accepted once
        late = [RunResult.model_validate_json(r) for r in info["late"]]
        assert store.accept_result(late[0], now=T0 + 12) == "accepted"
        drain(store, "w2", now=T0 + 12)
        assert store.accept_results(late, now=T0 + 13) == ["duplicate", "duplicate"]
        st = store.job_status(job)
        assert (st.state, st.runs_done, st.runs_failed) == ("done", 20, 0)
        assert len(store.runs(job, limit=1000)) == 20
        assert sum(1 for _ in store.iter_run_records(job)) == 20
        check_summary_against(store.summary(job), SPEC)


def test_reopen_keeps_everything(tmp_path):
    with Store(tmp_path) as s:
        job = s.create_job(SPEC, now=T0)
        drain(s)
        before = s.summary(job)
    with Store(tmp_path) as s:
        assert s.summary(job) == before
        assert s.counters()["results_accepted"] == 20


def test_schema_version_is_checked(tmp_path):
    Store(tmp_path).close()
    import sqlite3

    db = sqlite3.connect(tmp_path / "swarmpath.sqlite3")
    db.execute("UPDATE meta SET value = '999' WHERE key = 'schema_version'")
    db.commit()
    db.close()
    with pytest.raises(StoreError, match="schema version 999"):
        Store(tmp_path)


def test_wal_mode_and_data_dir(tmp_path):
    with Store(tmp_path / "nested" / "dir") as s:
        mode = s._db.execute("PRAGMA journal_mode").fetchone()[0]
        assert mode == "wal"
        assert s.path.exists() and os.path.dirname(s.path).endswith("dir")


# ------------------------------------------------------------------- bundles, series, durability
def test_lease_many_packs_leases_until_the_sizer_says_stop(store):
    store.create_job({**SPEC, "runs": 1}, now=T0)  # four cells of one run
    seen = []

    def runs_for(spec, remaining, bundle):
        seen.append((spec.key, remaining, len(bundle)))
        return 0 if len(bundle) == 3 else 5

    leases = store.lease_many("w1", 100, now=T0, max_leases=10, runs_for=runs_for)
    assert [lease.runs for lease in leases] == [[0], [0], [0]]
    assert [lease.cell_index for lease in leases] == [0, 1, 2]
    assert [s[1:] for s in seen] == [(4, 0), (3, 1), (2, 2), (1, 3)]
    assert len({lease.lease_id for lease in leases}) == 3
    rest = store.lease_many("w2", 100, now=T0, max_leases=10)
    assert [(lease.cell_index, lease.runs) for lease in rest] == [(3, [0])]
    for lease in leases + rest:
        assert set(store.accept_results(execute(lease), now=T0)) == {"accepted"}
    assert store.job_status(leases[0].job_id).state == "done"


def test_relaxed_lease_commits_survive_reopening(tmp_path):
    s = Store(tmp_path / "d")
    job = s.create_job(SPEC, now=T0)
    lease = s.lease("w1", 2, now=T0)
    beat(s, lease, "w1", now=T0 + 1, lease_seconds=100)
    s.close()
    again = Store(tmp_path / "d")
    assert [x["lease_id"] for x in again.active_leases()] == [lease.lease_id]
    assert again.active_leases()[0]["deadline"] == T0 + 101
    assert again.accept_results(execute(lease), now=T0) == ["accepted", "accepted"]
    assert again.job_status(job).runs_done == 2
    assert again._db.execute("PRAGMA synchronous").fetchone()[0] == 2  # FULL again
    again.close()


def test_series_are_stored_exactly_and_old_rows_still_read(store):
    import zlib

    from swarmpath.service.store import decode_series, encode_series

    series = {"curve": [3.0, float("inf"), 1e-300, 0.1], "best_position": None,
              "path": [(0.0, 1.0, 2.0), (3.5, 4.25, 5.0)]}
    blob = encode_series(series)
    assert blob is not None and blob.startswith(b"SPS2")
    expected = {"curve": [3.0, float("inf"), 1e-300, 0.1],
                "path": [[0.0, 1.0, 2.0], [3.5, 4.25, 5.0]]}
    assert decode_series(blob) == expected
    assert decode_series(b"SPS1" + zlib.compress(blob[4:], 1)) == expected  # the zlib form
    other = encode_series({"curve": [1.0, 2.0, 3.0], "best_position": [0.5, -0.5]})
    for _ in range(2):  # layouts alternately (each read is told by its own header)
        assert decode_series(other) == {"curve": [1.0, 2.0, 3.0], "best_position": [0.5, -0.5]}
        assert decode_series(blob) == expected
    assert encode_series({"curve": None}) is None and decode_series(None) == {}
    legacy = zlib.compress(json.dumps({"curve": [1.5, 2.5]}).encode(), 1)
    assert decode_series(legacy) == {"curve": [1.5, 2.5]}
    job = store.create_job(SPEC, now=T0)
    lease = store.lease("w1", 2, now=T0)
    results = execute(lease)
    store.accept_results(results, now=T0)
    item = store.run(job, results[1].run)
    assert item["curve"] == results[1].curve and item["best_position"] == results[1].best_position


def test_run_records_of_interleaved_jobs_in_acceptance_order(store):
    """Two jobs' results stored alternately: each job's records, and only its, in the order
    they were accepted, from the start or after a position, across read batches."""
    jobs = [store.create_job(SPEC, now=T0), store.create_job({**SPEC, "seed": 8}, now=T0)]
    leases: dict[str, list] = {job: [] for job in jobs}
    while (lease := store.lease("w1", 3, now=T0)) is not None:  # all of both jobs, held
        leases[lease.job_id].append(lease)
    order: dict[str, list[int]] = {job: [] for job in jobs}
    marks: list[tuple[int, dict[str, int]]] = []  # (position, results of each job before it)
    for pair in zip(*leases.values(), strict=True):  # stored alternately
        for lease in pair:
            store.accept_results(execute(lease), T0)
            order[lease.job_id] += lease.run_ids()
        marks.append((store.last_result_rowid(), {job: len(order[job]) for job in jobs}))
    for job in jobs:
        records = list(store.iter_run_records(job, batch=4))
        got = [r["run_id"] for r in records]
        assert got == order[job] and len(got) == 20
        for record in records[:3]:  # the same record as one read alone
            alone = store.run_record(job, record["run_id"])
            assert alone is not None and alone.keys() == record.keys()
            assert {k: v for k, v in alone.items() if k != "curve"} == \
                {k: v for k, v in record.items() if k != "curve"}
            assert alone["curve"].tolist() == record["curve"].tolist()
        position, before = marks[2]
        tail = [r["run_id"] for r in store.iter_run_records(job, batch=4, after=position)]
        assert tail == order[job][before[job]:] and 0 < len(tail) < 20
        upto, until = marks[5]  # from one position up to a later one
        part = [r["run_id"] for r in store.iter_run_records(job, batch=4, after=position,
                                                             upto=upto)]
        assert part == order[job][before[job]:until[job]] and 0 < len(part) < len(tail)
