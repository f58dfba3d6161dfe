"""CPU time beside wall time for benchmark runs (issue 23, section 4): measured by ``minimize``,
carried by every wire form of a run's result, stored (NULL for rows from before it, after the
schema migration), in REST rows, summaries, exports, MCAP and ``swarmpath bench``. Never a
timing claim: presence, type, missing-not-zero and how shares and sums are made."""

from __future__ import annotations

import json
import re
import sqlite3
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from swarmpath.cli import app
from swarmpath.evidence import exports, report
from swarmpath.optimizers import minimize, minimize_many
from swarmpath.service.capability import result_body, result_ok, result_proof
from swarmpath.service.protocol import Lease, RunResult
from swarmpath.service.result_columns import ColumnsHead, decode_message, encode_columns
from swarmpath.service.result_frame import FrameError, as_dict, decode_frame, decode_record
from swarmpath.service.store import Store
from swarmpath.service.store.base import SCHEMA_VERSION
from swarmpath.service.store.columns import from_frame
from swarmpath.service.store.summaries import summary_to_csv
from swarmpath.service.worker import execute_lease, pack_lease_columns

sys.path.insert(0, str(Path(__file__).parent))
from test_store import SPEC, T0, execute, signed


def _is_cpu(v) -> bool:
    return isinstance(v, float) and v >= 0.0 and np.isfinite(v)


# ----------------------------------------------------------------------------------- minimize
@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_minimize_reports_cpu_seconds_shared_among_functions_like_the_wall_time(backend):
    if backend == "numba":
        pytest.importorskip("numba")
    one = minimize("PSO", "F1", dim=3, agents=5, iterations=6, runs=3, seed=2, backend=backend)
    assert _is_cpu(one.cpu_seconds)
    # one call's time shared: per run, every function gets the same (wall and CPU alike);
    # the reference stacks functions of different run lists into one call too
    runs = [[0, 1, 2], [4]] if backend == "numpy" else [[0, 1, 2], [0, 1, 2]]
    stacked = minimize_many("PSO", ["F1", "F5"], dim=3, agents=5, iterations=6, seed=2,
                            backend=backend, function_runs=runs)
    assert all(_is_cpu(r.cpu_seconds) for r in stacked)
    per_run = [r.cpu_seconds / len(r.run_ids) for r in stacked]
    assert per_run[0] == pytest.approx(per_run[1], rel=1e-12, abs=1e-15)
    walls = [r.seconds / len(r.run_ids) for r in stacked]
    assert walls[0] == pytest.approx(walls[1], rel=1e-12, abs=1e-15)
    # a timing is not a number of the run: the same numbers again, whatever the CPU time
    again = minimize("PSO", "F1", dim=3, agents=5, iterations=6, runs=3, seed=2,
                     backend=backend)
    assert np.array_equal(again.curve, one.curve)


def test_cpu_totals_are_sums_and_missing_when_a_part_is():
    assert report.cpu_total([0.25, 0.5, 0.0]) == 0.75
    assert report.cpu_total([]) == 0.0
    assert report.cpu_total([0.25, None]) is None  # never a smaller cost that looks measured
    cells = [report.Cell("A", "F1", 2, [0], [1.0], [10], 2.0, cpu_seconds=0.5),
             report.Cell("A", "F2", 2, [0], [1.0], [10], 1.0, cpu_seconds=0.25),
             report.Cell("B", "F1", 2, [0], [2.0], [10], 3.0)]
    report.assign_ranks(cells)
    by_alg = {r["algorithm"]: r for r in report.ranking(cells, ["A", "B"])}
    assert (by_alg["A"]["seconds"], by_alg["A"]["cpu_seconds"]) == (3.0, 0.75)
    assert (by_alg["B"]["seconds"], by_alg["B"]["cpu_seconds"]) == (3.0, None)
    doc = report.study_to_json({"algorithms": ["A", "B"]}, cells, 9.0, "v")
    assert doc["cpu_seconds"] is None and [c["cpu_seconds"] for c in doc["cells"]] == [
        0.5, 0.25, None]
    from swarmpath.evidence.instances import pool_instances

    pooled = pool_instances([report.Cell("A", "bbob:f1@i1", 2, [0], [1.0], [1], 1.0,
                                         cpu_seconds=0.5),
                             report.Cell("A", "bbob:f1@i2", 2, [0], [1.0], [1], 1.0,
                                         cpu_seconds=0.25)])
    assert [c.cpu_seconds for c in pooled] == [0.75]


# -------------------------------------------------------------------------------- bench CLI
def test_bench_json_and_tables_carry_cpu_beside_the_elapsed_time():
    runner = CliRunner()
    args = ["bench", "-a", "GWO,PSO", "-f", "F1,F5", "-d", "2", "--runs", "3", "--agents", "5",
            "--iterations", "6", "-j", "1"]
    got = runner.invoke(app, [*args, "--json"])
    assert got.exit_code == 0, got.stderr
    doc = json.loads(got.stdout)
    cpus = [c["cpu_seconds"] for c in doc["cells"]]
    assert all(_is_cpu(v) for v in cpus)
    assert doc["cpu_seconds"] == pytest.approx(sum(cpus))  # the study's: its cells' sum
    for r in doc["ranking"]:
        mine = [c for c in doc["cells"] if c["algorithm"] == r["algorithm"]]
        assert r["cpu_seconds"] == pytest.approx(sum(c["cpu_seconds"] for c in mine))
        assert r["seconds"] == pytest.approx(sum(c["seconds"] for c in mine))
    text = runner.invoke(app, args, env={"COLUMNS": "200"})
    assert text.exit_code == 0, text.stderr
    words = " ".join(text.stdout.split())  # the caption may wrap
    assert re.search(r"best avg; [0-9.]+ s elapsed, [0-9.]+ s CPU in the runs", words)
    header = next(line for line in text.stdout.splitlines() if "mean rank" in line)
    assert header.index("time (s)") < header.index("CPU (s)")


# ---------------------------------------------------------------------------------- the wire
def _lease(store: Store) -> Lease:
    lease = store.lease("w1", 3, now=T0)
    assert lease is not None
    return lease


def test_a_worker_sends_cpu_seconds_in_every_form_and_an_older_one_is_read_as_missing(
        tmp_path):
    with Store(tmp_path / "d") as store:
        store.create_job(SPEC, now=T0)
        lease = _lease(store)
    records = [data for _run, data in execute_lease(lease)]
    heads = [decode_record(r).head for r in records]
    assert all(_is_cpu(h.cpu_seconds) for h in heads)
    assert len({h.cpu_seconds for h in heads}) == 1  # the batch's CPU, shared evenly
    (message,) = pack_lease_columns("w1", [(lease.lease_id, lease.capability, r)
                                           for r in records])
    (frame,) = decode_message(message)
    assert frame.head.cpu_seconds == [h.cpu_seconds for h in heads]
    assert from_frame(frame, lease.capability).cpu_seconds == frame.head.cpu_seconds
    _worker, again = decode_frame(message)  # the columns read as records, for tools
    assert [as_dict(r)["cpu_seconds"] for r in again] == frame.head.cpu_seconds
    # a frame from a worker that does not send the column: every run's CPU is missing
    old = frame.head.model_copy(update={"cpu_seconds": None})
    assert "cpu_seconds" not in json.loads(old.model_dump_json(exclude_none=True))
    (legacy,) = decode_message(encode_columns(old, [{}] * len(old.runs), lease.capability))
    cols = from_frame(legacy, lease.capability)
    assert [cols.cpu(k) for k in range(len(old.runs))] == [None] * len(old.runs)
    short = frame.head.model_copy(update={"cpu_seconds": frame.head.cpu_seconds[:1]})
    with pytest.raises(FrameError, match="cpu_seconds has 1 entries"):
        decode_message(encode_columns(short, [{}] * len(short.runs), lease.capability))
    with pytest.raises(Exception, match="cpu_seconds"):
        ColumnsHead.model_validate({**json.loads(frame.head.model_dump_json()),
                                    "cpu_seconds": [-1.0] * len(frame.head.runs)})


def test_a_json_result_without_cpu_keeps_the_proof_it_was_made_with():
    cap = "ab" * 32
    result = RunResult(lease_id="L1", job_id="j1", cell="GWO/F1/2", run=0, worker="w1",
                       seconds=0.5, metrics={"best_fitness": 1.0})
    assert "cpu_seconds" not in result_body(result)  # the text an older worker proved
    old = result.model_copy(update={"proof": result_proof(cap, result)})
    assert result_ok(cap, RunResult.model_validate_json(old.model_dump_json(
        exclude={"cpu_seconds"})))
    new = result.model_copy(update={"cpu_seconds": 0.25})
    proven = new.model_copy(update={"proof": result_proof(cap, new)})
    assert result_ok(cap, proven)
    assert not result_ok(cap, proven.model_copy(update={"cpu_seconds": 0.0}))  # covered


# --------------------------------------------------------------------- store, REST, exports
def _drain(store: Store, cpu: bool) -> None:
    while (lease := store.lease("w1", 5, now=T0)) is not None:
        assert set(store.accept_results(execute(lease, cpu=cpu), now=T0)) == {"accepted"}


def test_store_rows_summaries_and_exports_carry_cpu(tmp_path):
    with Store(tmp_path / "d") as store:
        job = store.create_job(SPEC, now=T0)
        _drain(store, cpu=True)
        items = store.runs(job, limit=100, series=True)
        assert len(items) == 20 and all(_is_cpu(i["cpu_seconds"]) for i in items)
        summary = store.summary(job)
    for row in summary["rows"]:
        mine = [i for i in items if i["cell"] == f"{row['algorithm']}/{row['function']}/4"]
        assert row["cpu_seconds_mean"] == pytest.approx(np.mean([i["cpu_seconds"]
                                                                 for i in mine]))
        assert row["seconds_mean"] == pytest.approx(np.mean([i["seconds"] for i in mine]))
    header = summary_to_csv(summary).splitlines()[0].split(",")
    assert header.index("seconds_mean") + 1 == header.index("cpu_seconds_mean")
    names = [n for n, _ in exports.BENCHMARK_COLUMNS]
    assert names.index("seconds") + 1 == names.index("cpu_seconds")
    assert [exports.run_row(i)["cpu_seconds"] for i in items] == [i["cpu_seconds"]
                                                                  for i in items]


def _as_version_3(path: Path) -> None:
    """The store file as schema version 3 wrote it: no results.cpu_seconds."""
    db = sqlite3.connect(path)
    db.execute("ALTER TABLE results DROP COLUMN cpu_seconds")
    db.execute("UPDATE meta SET value = '3' WHERE key = 'schema_version'")
    db.commit()
    db.close()


def test_an_old_store_opens_and_its_runs_show_cpu_as_missing_not_zero(tmp_path):
    from swarmpath.service.recorder import Recorders
    from test_recorder import read_all

    data = tmp_path / "d"
    with Store(data) as store:
        job = store.create_job(SPEC, now=T0)
        lease = _lease(store)
        assert set(store.accept_results(execute(lease, cpu=False), now=T0)) == {"accepted"}
    _as_version_3(data / "swarmpath.sqlite3")
    with Store(data) as store:
        version = store._db.execute(
            "SELECT value FROM meta WHERE key = 'schema_version'").fetchone()[0]
        assert int(version) == SCHEMA_VERSION == 7
        old = [i for i in store.runs(job, limit=100) if i["state"] == "done"]
        assert len(old) == 3 and all(i["cpu_seconds"] is None for i in old)
        assert all(i["seconds"] >= 0.0 for i in old)
        first = store.summary(job)["rows"][0]
        assert first["cpu_seconds_mean"] is None and first["seconds_mean"] is not None
        _drain(store, cpu=True)  # new results after the migration are stored with theirs
        items = store.runs(job, limit=100)
        assert sum(i["cpu_seconds"] is None for i in items) == 3
        assert all(_is_cpu(i["cpu_seconds"]) for i in items if i["run_id"] not in
                   {o["run_id"] for o in old})
        # the summary's CPU mean is over the runs that have one; the CSV cell of none is empty
        rows = store.summary(job)["rows"]
        assert all(r["cpu_seconds_mean"] is not None for r in rows)
        recorders = Recorders(store)
        recorders.open(job)
        for i in items:
            recorders.record_run(job, i["run_id"])
        path = recorders.finish(job)
    messages = {m["run_id"]: m for _s, c, m, _t in read_all(path)[2] if c.topic == "/results"}
    assert len(messages) == 20
    for i in items:
        if i["cpu_seconds"] is None:
            assert "cpu_seconds" not in messages[i["run_id"]]  # left out, not 0
        else:
            assert messages[i["run_id"]]["cpu_seconds"] == i["cpu_seconds"]


def test_a_stored_signed_result_from_before_cpu_is_accepted(tmp_path):
    """A result as a worker from before the field makes it (no cpu_seconds in its JSON) is
    proven and stored, its CPU missing."""
    with Store(tmp_path / "d") as store:
        job = store.create_job(SPEC, now=T0)
        lease = _lease(store)
        results = [signed(lease, r.model_copy(update={"cpu_seconds": None, "proof": None}))
                   for r in execute(lease)]
        wire = [RunResult.model_validate_json(r.model_dump_json(exclude={"cpu_seconds"}))
                for r in results]
        assert set(store.accept_results(wire, now=T0)) == {"accepted"}
        assert [store.run(job, r)["cpu_seconds"] for r in lease.run_ids()] == [None] * 3
