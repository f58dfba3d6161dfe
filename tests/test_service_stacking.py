"""Worker-side stacking: the benchmark leases of a bundle that differ only in their function run as
one ``minimize_many`` batch, each lease keeping its own numbers, proofs, progress and
cancellation; the lease sizer shares a learned cost within a family of stackable cells."""

from __future__ import annotations

import threading
import time

import pytest
from fastapi.testclient import TestClient

from swarmpath.optimizers import minimize
from swarmpath.optimizers.api import CHUNK_ELEMENTS
from swarmpath.service.capability import new_capability
from swarmpath.service.coordinator import Coordinator, CoordinatorSettings, LeaseSizer, create_app
from swarmpath.service.protocol import (
    BenchmarkCell,
    Lease,
    LeaseBundle,
    LeaseRequest,
    MapCell,
    RunResult,
    decode_work_reply,
    encode,
)
from swarmpath.service.result_frame import as_dict, decode_record, record_ok
from swarmpath.service.worker import Cancelled, ThreadSlot, pack_batches
from swarmpath.service.worker.stacking import (
    STACK_ELEMENTS,
    execute_stack,
    plan_stacks,
    stacked_outcomes,
)

PSO = BenchmarkCell(algorithm="PSO", function="F1", dim=3, agents=6, iterations=12)


def lease(spec: BenchmarkCell | MapCell, runs: list[int], lease_id: str, job: str = "j1",
          seed: int = 4) -> Lease:
    return Lease(lease_id=lease_id, worker="w1", job_id=job, cell=spec.key, cell_index=0,
                 runs_per_cell=10, seed=seed, runs=runs, spec=spec, deadline=0.0,
                 lease_seconds=30.0, heartbeat_seconds=10.0, capability=new_capability())


def fn(spec: BenchmarkCell, function: str, **changes: object) -> BenchmarkCell:
    return spec.model_copy(update={"function": function, **changes})


def decoded(outcome: list[tuple[int, bytes]]) -> list[RunResult]:
    return [RunResult(**as_dict(decode_record(data))) for _run, data in outcome]


def proven(capability: str, outcome: list[tuple[int, bytes]]) -> list[bool]:
    return [record_ok(capability, decode_record(data)) for _run, data in outcome]


def test_leases_differing_only_in_the_function_share_a_stack():
    group = [
        lease(PSO, [0, 1], "a"),
        lease(fn(PSO, "F9"), [0, 1], "b"),
        lease(fn(PSO, "F1", algorithm="GWO"), [0], "c"),  # another algorithm
        lease(fn(PSO, "F7"), [2], "d"),
        lease(fn(PSO, "F2", dim=4), [0], "e"),  # another dim
        lease(fn(PSO, "F3"), [0], "f", job="j2"),  # another job
        lease(fn(PSO, "F3"), [0], "g", seed=5),  # another seed
        lease(fn(PSO, "F3", params={"w": 0.5}), [0], "h"),  # other params
        lease(fn(PSO, "F3", transform="shift"), [0], "i"),  # another transform
        lease(MapCell(planner="MFB", map="mfb-static"), [0], "m"),  # a map lease runs alone
        lease(fn(PSO, "F1", algorithm="GWO"), [1], "k"),
        lease(fn(PSO, "F3", backend="numba"), [0], "n"),  # another backend
    ]
    assert plan_stacks(group) == [[0, 1, 3], [2, 10], [4], [5], [6], [7], [8], [9], [11]]
    # a stack holds at most `limit` coordinates per population (runs x agents x dim): by
    # default one chunk of minimize
    assert STACK_ELEMENTS == CHUNK_ELEMENTS
    wide = fn(PSO, "F1", dim=30, agents=30)  # 27,000 coordinates per lease of 30 runs
    group30 = [lease(fn(wide, f), list(range(30)), f) for f in ("F1", "F2", "F3", "F4", "F5")]
    assert plan_stacks(group30) == [[0, 1, 2], [3, 4]]

    assert plan_stacks(group[:2] + group[3:4], limit=4 * 6 * 3) == [[0, 1], [2]]
    assert plan_stacks([lease(PSO, list(range(5)), "big")], limit=4 * 6 * 3) == [[0]]


def test_a_stack_gives_each_lease_the_numbers_of_minimize_and_its_own_proofs():
    spec = fn(PSO, "F1", transform="shift")
    group = [lease(spec, [3, 0], "a"), lease(fn(spec, "F7"), [1, 2], "b"),
             lease(fn(spec, "F9"), [5], "c"), lease(spec, [7], "d")]
    steps: list[int] = []
    outcomes = execute_stack(group, [lambda: False] * 4, steps.append)
    assert steps == list(range(1, 13))  # one batch: progress once per iteration
    for one, outcome in zip(group, outcomes, strict=True):
        assert isinstance(outcome, list)
        results = decoded(outcome)
        direct = minimize("PSO", one.spec.function, 3, 6, 12, seed=4, transform="shift",
                          run_ids=one.runs)
        assert [r.run for r in results] == one.runs
        assert [r.metrics["best_fitness"] for r in results] == direct.best_fitness.tolist()
        assert [r.curve for r in results] == direct.curve.tolist()
        assert [r.best_position for r in results] == direct.best_position.tolist()
        assert all(r.lease_id == one.lease_id and r.cell == one.cell for r in results)
        assert all(proven(one.capability, outcome))
        other = group[(group.index(one) + 1) % 4]
        assert not any(proven(other.capability, outcome))


def test_cancelling_one_lease_of_a_stack_and_then_all():
    group = [lease(PSO, [0], "a"), lease(fn(PSO, "F9"), [0], "b")]
    outcomes = execute_stack(group, [lambda: True, lambda: False])
    assert isinstance(outcomes[0], Cancelled) and isinstance(outcomes[1], list)
    assert [r.run for r in decoded(outcomes[1])] == [0]
    steps: list[int] = []
    flags = [threading.Event(), threading.Event()]

    def progress(n: int) -> None:
        steps.append(n)
        if n == 3:
            flags[0].set()
        if n == 5:
            flags[1].set()

    outcomes = execute_stack(group, [f.is_set for f in flags], progress)
    assert all(isinstance(o, Cancelled) for o in outcomes)
    assert steps[-1] == 5  # stopped at the iteration where the last lease was cancelled


def test_a_failing_stack_is_run_lease_by_lease(monkeypatch):
    import swarmpath.optimizers as optimizers

    def broken(*_args: object, **_kw: object) -> None:
        raise RuntimeError("stacking broke")

    monkeypatch.setattr(optimizers, "minimize_many", broken)
    group = [lease(PSO, [0, 1], "a"), lease(fn(PSO, "F9"), [2], "b")]
    outcomes = execute_stack(group, [lambda: False] * 2)
    for one, outcome in zip(group, outcomes, strict=True):
        assert isinstance(outcome, list)
        direct = minimize("PSO", one.spec.function, 3, 6, 12, seed=4, run_ids=one.runs)
        got = decoded(outcome)
        assert [r.metrics["best_fitness"] for r in got] == direct.best_fitness.tolist()


def test_a_thread_slot_reports_progress_for_every_lease_of_the_running_stack():
    done = threading.Event()
    seen: list[tuple[str, object]] = []

    def on_done(_slot: object, outcomes: list[tuple[Lease, object]]) -> None:
        seen.extend((one.lease_id, outcome) for one, outcome in outcomes)
        done.set()

    slot = ThreadSlot(0, on_done)
    long = fn(PSO, "F1", dim=2, agents=5, iterations=100_000)
    group = [lease(long, [0], "a"), lease(fn(long, "F9"), [0], "b"), lease(PSO, [0], "c")]
    slot.submit(group)
    deadline = time.monotonic() + 30
    while slot.iteration("a") < 5 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert slot.iteration("a") >= 5 and slot.iteration("b") >= 5
    assert slot.iteration("c") == 0  # waits for the next stack
    slot.cancel("a")
    slot.cancel("b")
    assert done.wait(30)
    by_id = dict(seen)
    assert isinstance(by_id["a"], Cancelled) and isinstance(by_id["b"], Cancelled)
    assert [r.run for r in decoded(by_id["c"])] == [0]  # type: ignore[arg-type]
    slot.close()


# ----------------------------------------------------- through the coordinator (no network)
SPEC = {"kind": "benchmark", "algorithms": ["GWO", "PSO"], "functions": ["F1", "F7", "F9", "F12"],
        "dims": [3], "runs": 6, "agents": 6, "iterations": 12, "seed": 8}


@pytest.fixture
def core(tmp_path, monkeypatch):
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    app = create_app(CoordinatorSettings(data_dir=tmp_path / "data"), use_zenoh=False)
    with TestClient(app) as client:
        app.state.core.publish = lambda _key, _payload: None
        yield app.state.core, client


def test_stacked_bundles_through_the_coordinator_equal_minimize_run_by_run(core):
    coordinator, client = core
    assert isinstance(coordinator, Coordinator)
    job = client.post("/jobs", json=SPEC).json()["id"]
    coordinator.worker_alive("w1")
    request = encode(LeaseRequest(worker="w1", max_runs=1000, max_leases=32, slots=1))
    stacked = 0
    while isinstance(reply := decode_work_reply(coordinator.handle_lease_request(request)),
                     LeaseBundle):
        group = reply.leases
        stacked = max(stacked, *(len(s) for s in plan_stacks(group)))
        outcomes = dict(stacked_outcomes(group, [lambda: False] * len(group)))
        results = [data for i in range(len(group)) for _run, data in outcomes[i]]
        if len(group) > 1:  # a result claimed for another lease of the stack is refused
            forged = results[0].replace(group[0].lease_id.encode(), group[1].lease_id.encode())
            assert forged != results[0]
            ack = coordinator.handle_results(
                f"swarmpath/results/{job}", pack_batches("w1", [forged])[0])
            assert ack is not None and [s for _l, _r, s in ack.statuses()] == ["stale"]
        for payload in pack_batches("w1", results):
            ack = coordinator.handle_results(f"swarmpath/results/{job}", payload)
            assert ack is not None and {s for _l, _r, s in ack.statuses()} == {"accepted"}
    assert stacked >= 3  # bundles hold several cells of one algorithm: they ran stacked
    assert client.get(f"/jobs/{job}").json()["state"] == "done"
    items = client.get(f"/jobs/{job}/runs", params={"limit": 100}).json()["items"]
    for a in SPEC["algorithms"]:
        for f in SPEC["functions"]:
            direct = minimize(a, f, 3, 6, 12, runs=6, seed=8)
            got = [i for i in items if i["algorithm"] == a and i["function"] == f]
            assert [i["run"] for i in got] == list(range(6))
            assert [i["best_fitness"] for i in got] == direct.best_fitness.tolist()


def test_a_cell_without_results_takes_its_familys_cost():
    sizer = LeaseSizer(target_seconds=10.0, min_runs=8)
    f1 = BenchmarkCell(algorithm="PSO", function="F1", dim=30, agents=30, iterations=500)
    f2, gwo = fn(f1, "F2"), fn(f1, "F1", algorithm="GWO")
    assert sizer.estimate(f2) == sizer.prior(f2)
    sizer.observe(f1, 0.01)
    assert sizer.estimate(f2) == 0.01 and sizer.runs_for(f2) == 1000
    assert sizer.estimate(gwo) == sizer.prior(gwo)  # another family
    sizer.observe(f2, 0.02)
    assert sizer.estimate(f2) == 0.02 and sizer.estimate(f1) == 0.01
    assert sizer.estimate(fn(f1, "F3")) == pytest.approx(0.013)  # the family's moving average


def test_no_stacking_runs_every_lease_alone():
    group = [lease(PSO, [0], "a"), lease(fn(PSO, "F9"), [1], "b")]
    for stacking, stacks in ((True, [[0, 1]]), (False, [[0], [1]])):
        seen: list[list[int]] = []
        got = dict(stacked_outcomes(group, [lambda: False] * 2, seen.append, stacking=stacking))
        assert seen == stacks
        for i, one in enumerate(group):
            direct = minimize("PSO", one.spec.function, 3, 6, 12, seed=4, run_ids=one.runs)
            assert [r.metrics["best_fitness"] for r in decoded(got[i])] == \
                direct.best_fitness.tolist()


def test_the_sizers_estimates_are_bounded(monkeypatch):
    sizer = LeaseSizer(target_seconds=10.0, min_runs=8)
    monkeypatch.setattr(LeaseSizer, "MAX_ESTIMATES", 10)
    for dim in range(1, 40):
        sizer.observe(fn(PSO, "F1", dim=dim), 0.01)
        assert len(sizer._estimates) <= 10
    assert sizer.estimate(fn(PSO, "F2", dim=39)) == 0.01  # the latest family is kept
