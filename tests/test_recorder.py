"""The per-job MCAP: contents, Foxglove schemas, indexes, flushing, crash recovery."""

from __future__ import annotations

import json
import shutil
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from mcap.reader import NonSeekingReader, make_reader

from swarmpath import __version__
from swarmpath.service import foxglove as fg
from swarmpath.service.protocol import MapJobSpec, RunResult
from swarmpath.service.recorder import (
    OWN_SCHEMAS,
    JobRecorder,
    Recorders,
    final_path,
    part_path,
    salvage_messages,
)
from swarmpath.service.recorder.common import COMPRESSION_ENV, COMPRESSIONS, chunk_compression
from swarmpath.service.store import Store

sys.path.insert(0, str(Path(__file__).parent))
from test_store import SPEC, T0, drain, execute, signed


def read_all(path: Path):
    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        summary = reader.get_summary()
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
        messages = [
            (schema, channel, json.loads(msg.data), msg.log_time)
            for schema, channel, msg in reader.iter_messages(log_time_order=False)
        ]
    return summary, metadata, messages


def check_indexed(summary) -> None:
    assert summary is not None and summary.statistics is not None
    assert summary.chunk_indexes, "no chunk indexes"
    for ci in summary.chunk_indexes:
        assert ci.message_index_offsets, "chunk index without message indexes"
        assert ci.compression == "lz4"  # the default chunk compression
    assert summary.statistics.message_count == sum(
        summary.statistics.channel_message_counts.values()
    )


def check_data_crc(path: Path) -> None:
    """The streaming reader validates chunk CRCs and the data section CRC."""
    with open(path, "rb") as f:
        n = sum(1 for _ in NonSeekingReader(f, validate_crcs=True).iter_messages(
            log_time_order=False))
    assert n > 0


@pytest.fixture
def store(tmp_path):
    s = Store(tmp_path / "data")
    yield s
    s.close()


# ------------------------------------------------------------------------------- benchmark
def test_benchmark_job_file(store):
    job = store.create_job(SPEC, now=T0)
    recorders = Recorders(store)
    recorders.open(job)
    assert part_path(store.data_dir, job).exists() and not recorders.ready(job)
    while (lease := store.lease("w1", 3, now=T0)) is not None:
        for run_id, status in zip(lease.run_ids(), store.accept_results(execute(lease), T0),
                                  strict=True):
            assert status == "accepted"
            assert recorders.record_run(job, run_id)
    path = recorders.finish(job)
    assert path == final_path(store.data_dir, job) and recorders.ready(job)
    assert not part_path(store.data_dir, job).exists()

    summary, metadata, messages = read_all(path)
    check_indexed(summary)
    check_data_crc(path)
    results = [m for _s, c, m, _t in messages if c.topic == "/results"]
    curves = [m for _s, c, m, _t in messages if c.topic == "/curves"]
    assert sorted(m["run_id"] for m in results) == list(range(20))  # exactly one per run
    assert sorted(m["run_id"] for m in curves) == list(range(20))
    by_run = {m["run_id"]: m for m in results}
    for item in store.runs(job, limit=100):
        assert by_run[item["run_id"]]["best_fitness"] == item["best_fitness"]
        assert by_run[item["run_id"]]["algorithm"] == item["algorithm"]
        assert by_run[item["run_id"]]["backend"] == "auto"  # the job spec's default backend
        assert by_run[item["run_id"]]["cpu_seconds"] == item["cpu_seconds"] >= 0.0
    assert all(len(c["best_fitness"]) == c["iterations"] == 8 for c in curves)
    names = {s.name: s for s in summary.schemas.values()}
    assert set(names) == {"swarmpath.BenchmarkRunResult", "swarmpath.ConvergenceCurve"}
    assert all(s.encoding == "jsonschema" for s in names.values())
    assert all(c.message_encoding == "json" for c in summary.channels.values())
    for s in names.values():
        assert fg.check_foxglove_rules(json.loads(s.data)) == []
    for _s, _c, m, _t in messages:
        assert fg.check_message(m) == []
    job_meta = metadata["swarmpath.job"]
    assert job_meta["job_id"] == job and job_meta["swarmpath_version"] == __version__
    assert json.loads(job_meta["spec"])["functions"] == ["F1", "F9"]
    final_meta = metadata["swarmpath.summary"]
    assert final_meta["state"] == "done" and final_meta["runs_written"] == "20"
    assert len(json.loads(final_meta["summary"])["rows"]) == 4
    pins = {k: json.loads(v) for k, v in metadata["swarmpath.extensions"].items()}
    assert set(pins) == {"optimizer:GWO", "optimizer:PSO", "function:F1", "function:F9"}
    assert all(p["source"] == "built-in" and len(p["digest"]) == 64 for p in pins.values())
    assert summary.statistics.metadata_count == 3  # job, extensions, summary


def test_a_run_is_written_once(store, tmp_path):
    job = store.create_job(SPEC, now=T0)
    drain(store)
    rec = JobRecorder(tmp_path / "x.mcap", job, "benchmark", SPEC, T0)
    record = store.run_record(job, 3)
    assert rec.add(record) is True
    assert rec.add(record) is False
    rec.finish()
    _summary, _meta, messages = read_all(tmp_path / "x.mcap")
    assert [m["run_id"] for _s, c, m, _t in messages if c.topic == "/results"] == [3]




@pytest.mark.parametrize("name", COMPRESSIONS)
def test_every_chunk_compression_holds_the_same_messages(store, tmp_path, name):
    job = store.create_job(SPEC, now=T0)
    drain(store)
    records = list(store.iter_run_records(job))
    files = {}
    for label, compression in (("default", None), (name, chunk_compression(name))):
        rec = JobRecorder(tmp_path / f"{label}.mcap", job, "benchmark", SPEC, T0,
                          flush_interval=1e9, compression=compression)
        for record in records:
            rec.add(record)
        files[label] = rec.finish()
    summary, _meta, messages = read_all(files[name])
    _s, _m, default_messages = read_all(files["default"])
    assert messages == default_messages and len(messages) == 2 * len(records)
    assert {ci.compression for ci in summary.chunk_indexes} == {"" if name == "none" else name}


@pytest.mark.parametrize("name", COMPRESSIONS)
def test_the_fast_writer_writes_the_bytes_of_the_mcap_writer(store, tmp_path, name):
    """JobRecorder writes through FastWriter (its own message records, chunk records and CRCs);
    with fast=False the mcap package's Writer writes the same job: the files are identical,
    byte for byte, with every chunk compression."""
    from swarmpath.service.recorder.fastwriter import FastWriter

    job = store.create_job(SPEC, now=T0)
    drain(store)
    records = list(store.iter_run_records(job))
    paths = []
    for fast in (True, False):
        rec = JobRecorder(tmp_path / f"{fast}.mcap", job, "benchmark", SPEC, T0,
                          flush_interval=1e9, chunk_size=4096,  # several chunk cuts
                          compression=chunk_compression(name), fast=fast)
        assert isinstance(rec._writer, FastWriter) is fast
        for i, record in enumerate(records):
            if i == len(records) // 2:  # a metadata record between chunks
                rec.note_platform("w1", {"fingerprint": "abc", "cpu": "x"})
            rec.add(record)
        paths.append(rec.finish())
    summary, _meta, _messages = read_all(paths[0])
    assert len(summary.chunk_indexes) > 1
    check_data_crc(paths[0])
    assert paths[0].read_bytes() == paths[1].read_bytes()


def test_an_unknown_chunk_compression_is_refused_naming_the_setting(monkeypatch, store):
    monkeypatch.setenv(COMPRESSION_ENV, "brotli")
    with pytest.raises(ValueError, match=COMPRESSION_ENV):
        Recorders(store)
    monkeypatch.setenv(COMPRESSION_ENV, "ZSTD")
    assert Recorders(store).compression is chunk_compression("zstd")


def test_finish_takes_stored_results_a_concurrent_batch_has_not_recorded_yet(store):
    """One thread stores the job's last results and finalizes while another has stored its
    batch but not yet handed it to the recorder: the file still holds every stored run."""
    job = store.create_job(SPEC, now=T0)
    recorders = Recorders(store)
    recorders.open(job)
    held_back = set()
    while (lease := store.lease("w1", 3, now=T0)) is not None:
        for run_id, status in zip(lease.run_ids(), store.accept_results(execute(lease), T0),
                                  strict=True):
            assert status == "accepted"
            if len(held_back) < 5:
                held_back.add(run_id)  # stored, never passed to record_run
            else:
                recorders.record_run(job, run_id)
    _summary, meta, messages = read_all(recorders.finish(job))
    ids = [m["run_id"] for _s, c, m, _t in messages if c.topic == "/results"]
    assert sorted(ids) == list(range(20)) and held_back <= set(ids)
    assert meta["swarmpath.summary"]["runs_written"] == "20"


def test_non_finite_curve_values_are_clamped(store, tmp_path):
    job = store.create_job({**SPEC, "runs": 1}, now=T0)
    drain(store)
    record = store.run_record(job, 0)
    record["curve"] = [float("inf"), 1.0]
    record["metrics"]["best_fitness"] = float("nan")
    rec = JobRecorder(tmp_path / "x.mcap", job, "benchmark", SPEC, T0)
    rec.add(record)
    rec.finish()
    _summary, _meta, messages = read_all(tmp_path / "x.mcap")
    result = next(m for _s, c, m, _t in messages if c.topic == "/results")
    curve = next(m for _s, c, m, _t in messages if c.topic == "/curves")
    assert "best_fitness" not in result  # left out rather than invalid JSON
    assert curve["best_fitness"][0] > 1e300


def _raw_curves(path: Path) -> list[bytes]:
    with open(path, "rb") as f:
        return [m.data for _s, c, m in make_reader(f).iter_messages(log_time_order=False)
                if c.topic == "/curves"]


@pytest.mark.parametrize("values", [
    [0.5, 1e-300, 1.5e30, -2.0, 0.1 + 0.2, 123456.789],  # finite: text straight from the array
    [float("inf"), 1.0, float("nan"), float("-inf")],  # non-finite: clamped
])
def test_a_curve_array_and_the_same_floats_as_a_list_give_the_same_message(
        store, tmp_path, values):
    """A store record's curve is a float64 array that orjson writes from its buffer next to the
    other fields' JSON; the message is byte for byte the one made from a list of the floats,
    non-finite values clamped either way."""
    import numpy as np

    job = store.create_job({**SPEC, "runs": 1}, now=T0)
    drain(store)
    record = store.run_record(job, 0)
    assert isinstance(record["curve"], np.ndarray)  # what the fast path gets from the store
    written = []
    for curve in (np.array(values), list(values)):
        rec = JobRecorder(tmp_path / f"{len(written)}.mcap", job, "benchmark", SPEC, T0)
        rec.add({**record, "curve": curve})
        written.append(_raw_curves(rec.finish()))
    assert written[0] == written[1] and len(written[0]) == 1
    big = 1.7976931348623157e308  # the clamp: -inf -> -big, +inf and nan -> +big
    expected = [v if np.isfinite(v) else -big if v < 0 else big for v in values]
    assert json.loads(written[0][0])["best_fitness"] == expected


# ------------------------------------------------------------------------------------- flush
def test_flush_about_once_a_second_and_truncated_file_salvage(store, tmp_path):
    job = store.create_job({**SPEC, "runs": 5}, now=T0)
    drain(store)
    now = [0.0]
    rec = JobRecorder(tmp_path / "x.mcap", job, "benchmark", SPEC, T0, clock=lambda: now[0])
    records = list(store.iter_run_records(job))
    for r in records[:6]:
        now[0] += 0.3
        rec.add(r)  # flushes once 1 s passed: after the 4th (t = 1.2)
    assert not rec.flush_if_due()  # only 0.6 s since that flush
    now[0] += 0.5
    assert rec.flush_if_due()  # idle flush by the timer
    assert not rec.flush_if_due()  # nothing new
    rec.add(records[6])  # written to the open chunk only: lost by a crash
    crashed = tmp_path / "crashed.mcap"
    shutil.copy(rec.part, crashed)  # what a killed process leaves behind
    data = crashed.read_bytes()
    crashed.write_bytes(data + b"\x05garbage-after-the-cut")  # a torn tail
    with pytest.raises(Exception):  # noqa: B017 - the seeking reader needs a footer
        with open(crashed, "rb") as f:
            make_reader(f).get_summary()
    got = salvage_messages(crashed, topics=["/results"])
    assert [m["run_id"] for _t, m in got] == [r["run_id"] for r in records[:6]]
    rec.finish()


# -------------------------------------------------------------------------------- recovery
def test_recorder_rebuilds_from_the_store_after_a_coordinator_restart(tmp_path):
    data = tmp_path / "data"
    store = Store(data)
    job = store.create_job(SPEC, now=T0)
    recorders = Recorders(store)
    lease = store.lease("w1", 3, now=T0)
    for run_id, _ in zip(lease.run_ids(), store.accept_results(execute(lease), T0), strict=True):
        recorders.record_run(job, run_id)
    recorders.tick()
    lease = store.lease("w1", 3, now=T0)  # accepted, but the coordinator dies before recording
    assert lease.runs == [3, 4]
    store.accept_results(execute(lease), T0)
    # "crash": drop everything without closing or finishing
    del recorders
    store.close()

    store = Store(data)
    recorders = Recorders(store)
    assert recorders.recover() == [job]  # fresh .part from the store
    rec = recorders.open(job)
    assert rec.written == set(range(5))
    for run_id in range(5):  # a replay of the live path writes nothing twice
        assert not recorders.record_run(job, run_id)
    while (lease := store.lease("w2", 4, now=T0)) is not None:
        store.accept_results(execute(lease), T0)
        for run_id in lease.run_ids():
            recorders.record_run(job, run_id)
    recorders.finish(job)
    _summary, _meta, messages = read_all(final_path(data, job))
    ids = [m["run_id"] for _s, c, m, _t in messages if c.topic == "/results"]
    assert sorted(ids) == list(range(20))
    store.close()


def test_finished_job_without_file_is_finalized_on_recover(store):
    job = store.create_job({**SPEC, "runs": 1}, now=T0)
    drain(store)
    cancelled = store.create_job(SPEC, now=T0)
    store.cancel(cancelled)
    recorders = Recorders(store)
    assert sorted(recorders.recover()) == sorted([job, cancelled])
    assert recorders.ready(job) and recorders.ready(cancelled)
    _summary, metadata, messages = read_all(recorders.path(cancelled))
    assert metadata["swarmpath.summary"]["state"] == "cancelled" and messages == []
    assert recorders.recover() == []


KILLED = textwrap.dedent(
    """
    import os, signal, sys
    sys.path.insert(0, {tests!r})
    from swarmpath.service.store import Store
    from swarmpath.service.recorder import Recorders
    from test_store import SPEC, T0, execute
    store = Store({data!r})
    job = store.create_job(SPEC, now=T0)
    recorders = Recorders(store, flush_interval=0.0)
    recorded = []
    for _ in range(3):
        lease = store.lease("w1", 3, now=T0)
        store.accept_results(execute(lease), T0)
        for run_id in lease.run_ids():
            recorders.record_run(job, run_id)
            recorded.append(run_id)
    print(job, *recorded, flush=True)
    os.kill(os.getpid(), signal.SIGKILL)
    """
)


def test_sigkill_mid_job_then_restart_gives_each_result_once(tmp_path):
    data = tmp_path / "data"
    code = KILLED.format(tests=str(Path(__file__).parent), data=str(data))
    proc = subprocess.run([sys.executable, "-c", code], timeout=120, capture_output=True)
    assert proc.returncode == -signal.SIGKILL, proc.stderr.decode()[-2000:]
    job, *recorded = proc.stdout.decode().split()
    assert len(recorded) == 8
    salvaged = salvage_messages(part_path(data, job), topics=["/results"])
    # flushed after each message (interval 0): everything recorded before the kill is readable
    assert [m["run_id"] for _t, m in salvaged] == [int(r) for r in recorded]
    with Store(data) as store:
        recorders = Recorders(store)
        recorders.recover()
        drain(store, "w2")
        for item in store.runs(job, limit=100):
            recorders.record_run(job, item["run_id"])
        recorders.finish(job)
        summary, _meta, messages = read_all(final_path(data, job))
        check_indexed(summary)
        ids = [m["run_id"] for _s, c, m, _t in messages if c.topic == "/results"]
        assert sorted(ids) == list(range(20))


# ------------------------------------------------------------------------------------ maps
def test_foxglove_schemas_have_the_published_layout():
    scene = fg.scene_update_schema()
    assert scene["title"] == "foxglove.SceneUpdate"
    entity = scene["properties"]["entities"]["items"]
    assert entity["title"] == "foxglove.SceneEntity"
    assert list(entity["properties"]) == [
        "timestamp", "frame_id", "id", "lifetime", "frame_locked", "metadata", "arrows", "cubes",
        "spheres", "cylinders", "lines", "triangles", "texts", "models",
    ]
    cyl = entity["properties"]["cylinders"]["items"]["properties"]
    assert list(cyl) == ["pose", "size", "bottom_scale", "top_scale", "color"]
    line = entity["properties"]["lines"]["items"]["properties"]
    assert list(line) == ["type", "pose", "thickness", "scale_invariant", "points", "color",
                          "colors", "indices"]
    assert [o["const"] for o in line["type"]["oneOf"]] == [0, 1, 2]
    poses = fg.poses_in_frame_schema()
    assert list(poses["properties"]) == ["timestamp", "frame_id", "poses"]
    assert list(poses["properties"]["poses"]["items"]["properties"]["orientation"][
        "properties"]) == ["x", "y", "z", "w"]
    grid = fg.grid_schema()
    assert list(grid["properties"]) == [
        "timestamp", "frame_id", "pose", "column_count", "cell_size", "row_stride", "cell_stride",
        "fields", "data",
    ]
    assert grid["properties"]["data"]["contentEncoding"] == "base64"
    for schema in (scene, poses, grid, *OWN_SCHEMAS.values()):
        assert fg.check_foxglove_rules(schema) == []
    assert fg.check_foxglove_rules({"type": ["number", "null"]})
    assert fg.check_foxglove_rules({"type": "array", "items": {"type": "array"}})
    assert fg.check_message({"a": [[1, 2]]}) and fg.check_message({"a": None})


SCENARIO = {
    "name": "demo", "size": [10, 10], "start": [0, 0], "goal": [10, 10],
    "robot": {"model": "omni", "radius": 0.3},
    "obstacles": [
        {"shape": "circle", "center": [2, 2.3], "radius": 0.5},
        {"shape": "circle", "center": [4, 2], "radius": 0.3, "speed": 0.3, "heading_deg": 111.8},
        {"shape": "polygon", "points": [[1, 5], [2, 5], [2, 6.5]]},
    ],
}


def map_record(job: str, run: int, created: float, scenario=SCENARIO) -> dict:
    path = [[0.0, 0.0, 0.0], [3.0, 4.0, 5.0], [10.0, 10.0, 12.0]]
    return {
        "job_id": job, "kind": "map", "run_id": run, "cell_index": 0, "cell": "P/demo",
        "spec": {"kind": "map", "planner": "P", "map": "demo", "scenario": scenario,
                 "params": {}},
        "run": run, "seed": 1, "worker": "w", "lease_id": "l", "status": "ok", "failure": None,
        "seconds": 0.5, "created": created,
        "metrics": {"success": True, "collisions": 0, "length": 14.9, "error": 0.1,
                    "steps": 2, "optimum": None, "gap": None, "reason": "goal reached"},
        "path": path,
    }


def test_map_job_file_opens_in_foxglove(tmp_path):
    spec = {"kind": "map", "planners": ["P"], "maps": [SCENARIO], "runs": 2, "seed": 1}
    rec = JobRecorder(tmp_path / "m.mcap", "job1", "map", spec, T0)
    for run in range(2):
        assert rec.add(map_record("job1", run, T0 + 1 + run))
    rec.finish()
    summary, metadata, messages = read_all(tmp_path / "m.mcap")
    check_indexed(summary)
    check_data_crc(tmp_path / "m.mcap")
    names = {s.name for s in summary.schemas.values()}
    assert {"foxglove.SceneUpdate", "foxglove.PosesInFrame", "foxglove.Grid",
            "swarmpath.MapRunResult"} <= names
    for s in summary.schemas.values():
        assert s.encoding == "jsonschema"
        assert fg.check_foxglove_rules(json.loads(s.data)) == []
    topics = {c.topic: c for c in summary.channels.values()}
    assert {"/results", "/map/demo/occupancy", "/map/demo/obstacles", "/scene/P/demo",
            "/paths/P/demo"} <= set(topics)
    assert summary.schemas[topics["/map/demo/occupancy"].schema_id].name == "foxglove.Grid"
    assert summary.schemas[topics["/paths/P/demo"].schema_id].name == "foxglove.PosesInFrame"
    for _s, _c, m, _t in messages:
        assert fg.check_message(m) == [], m
    by_topic: dict[str, list] = {}
    for _s, c, m, t in messages:
        by_topic.setdefault(c.topic, []).append((m, t))
    results = [m for m, _t in by_topic["/results"]]
    assert sorted(r["run_id"] for r in results) == [0, 1]
    assert results[0]["length"] == 14.9 and results[0]["success"] is True
    assert "gap" not in results[0] and results[0]["reason"] == "goal reached"
    (grid, t), = by_topic["/map/demo/occupancy"]
    assert t == round(T0 * 1e9)
    import base64

    cells = base64.b64decode(grid["data"])
    assert len(cells) % grid["column_count"] == 0 and set(cells) <= {0, 100}
    assert 100 in cells and grid["fields"][0]["type"] == fg.UINT8
    # static obstacles only: the cell under the moving circle's start (4, 2) is free, the one
    # under the static circle (2, 2.3) is occupied
    size = grid["cell_size"]["x"]

    def cell(x, y):
        return cells[int(y / size) * grid["column_count"] + int(x / size)]

    assert cell(2.0, 2.3) == 100 and cell(4.0, 2.0) == 0
    assert grid["frame_id"] == "map/demo"
    (obstacles, _t), = by_topic["/map/demo/obstacles"]
    ents = {e["id"]: e for e in obstacles["entities"]}
    assert len(ents["obstacles"]["cylinders"]) == 1 and len(ents["obstacles"]["lines"]) == 1
    assert {"start", "goal", "world"} <= set(ents)
    assert {e["frame_id"] for e in obstacles["entities"]} == {"map/demo"}
    (tf, _t), = by_topic["/tf"]
    assert (tf["parent_frame_id"], tf["child_frame_id"]) == ("world", "map/demo")
    paths = by_topic["/paths/P/demo"]
    assert len(paths) == 2 and len(paths[0][0]["poses"]) == 3
    assert paths[0][1] == round(T0 * 1e9) + 12 * 10**9  # base + t_end
    scene = by_topic["/scene/P/demo"]
    ids = {e["id"] for m, _t in scene for e in m["entities"]}
    assert {"run-0/robot", "run-0/path", "run-0/obstacles", "run-0/goal", "run-1/robot"} <= ids
    for m, _t in scene:  # every entity of a run says which run it is
        for e in m["entities"]:
            if not e["id"].endswith("/obstacles"):
                about = {kv["key"]: kv["value"] for kv in e["metadata"]}
                assert e["id"].startswith(f"run-{about['run']}/") and about["planner"] == "P"
            assert e["frame_id"] == "map/demo"
    # the moving obstacle is drawn where the world puts it at t = 5 s
    from swarmpath.service.recorder import world_for
    from swarmpath.world.scenario_io import scenario_from_dict

    world = world_for(scenario_from_dict(SCENARIO), 1, 0)
    at5 = next(e for m, t in scene for e in m["entities"]
               if e["id"] == "run-0/obstacles" and t == round(T0 * 1e9) + 5 * 10**9)
    expect = world.obstacles_at(5.0).circles
    got = sorted((c["pose"]["position"]["x"], c["pose"]["position"]["y"])
                 for c in at5["cylinders"])
    want = sorted((float(x), float(y)) for x, y, _r in expect)
    assert [v for xy in got for v in xy] == pytest.approx([v for xy in want for v in xy])
    assert want != sorted((x, y) for x, y, _r in world.obstacles_at(0.0).circles)  # it moved
    assert json.loads(metadata["swarmpath.job"]["spec"])["maps"][0]["name"] == "demo"


def test_map_job_through_the_store(store):
    spec = MapJobSpec.model_construct(kind="map", planners=["P"], maps=[SCENARIO], runs=2,
                                      seed=1, params={})
    job = store.create_job(spec, now=T0)
    recorders = Recorders(store)
    while (lease := store.lease("w", 2, now=T0)) is not None:
        results = [
            signed(lease, RunResult(
                lease_id=lease.lease_id, job_id=job, cell=lease.cell, run=r, worker="w",
                seconds=0.5, metrics=map_record(job, r, T0)["metrics"],
                path=[tuple(p) for p in map_record(job, r, T0)["path"]]))
            for r in lease.runs
        ]
        store.accept_results(results, T0)
        for run_id in lease.run_ids():
            recorders.record_run(job, run_id)
    path = recorders.finish(job)
    summary, _meta, messages = read_all(path)
    assert sorted(m["run_id"] for _s, c, m, _t in messages if c.topic == "/results") == [0, 1]
    assert any(c.topic == "/paths/P/demo" for c in summary.channels.values())


def test_map_runs_without_geometry_still_record_results(tmp_path):
    rec = JobRecorder(tmp_path / "m.mcap", "job1", "map", {}, T0)
    record = map_record("job1", 0, T0, scenario=None)
    record["spec"]["map"] = "no-such-map"
    rec.add(record)
    rec.finish()
    _summary, _meta, messages = read_all(tmp_path / "m.mcap")
    assert [c.topic for _s, c, _m, _t in messages if c.topic == "/results"] == ["/results"]


def test_maps_have_their_own_frames_side_by_side_and_runs_their_metadata(tmp_path):
    from mcap.reader import make_reader

    from swarmpath.service.recorder import MAP_GAP

    small = {**SCENARIO, "name": "small", "size": [6, 4], "goal": [5, 3],
             "obstacles": SCENARIO["obstacles"][:1]}
    spec = {"kind": "map", "planners": ["P"], "maps": [SCENARIO, small], "runs": 2, "seed": 1}
    rec = JobRecorder(tmp_path / "m.mcap", "job1", "map", spec, T0)
    second = map_record("job1", 2, T0 + 1, small)  # the second map's run arrives first
    second["spec"]["map"], second["cell"] = "small", "P/small"
    second["path"] = [[0.0, 0.0, 0.0], [5.0, 3.0, 4.0]]
    assert rec.add(second)
    for run in range(2):
        assert rec.add(map_record("job1", run, T0 + 2 + run))
    rec.finish()
    _summary, _metadata, messages = read_all(tmp_path / "m.mcap")
    tfs = {m["child_frame_id"]: m for _s, c, m, _t in messages if c.topic == "/tf"}
    assert set(tfs) == {"map/demo", "map/small"}
    # the spec's order, not the arrival order: demo at x = 0, small to its right
    assert tfs["map/demo"]["translation"]["x"] == 0.0
    assert tfs["map/small"]["translation"]["x"] == 10.0 + MAP_GAP
    assert all(m["parent_frame_id"] == "world" for m in tfs.values())
    frames = {c.topic: m.get("frame_id") for _s, c, m, _t in messages if "frame_id" in m}
    assert frames["/map/small/occupancy"] == "map/small" and frames["/paths/P/demo"] == "map/demo"
    with open(tmp_path / "m.mcap", "rb") as f:
        runs = [m.metadata for m in make_reader(f).iter_metadata() if m.name == "swarmpath.run"]
    assert sorted(int(r["run_id"]) for r in runs) == [0, 1, 2]
    small_run = next(r for r in runs if r["run_id"] == "2")
    assert (small_run["map"], small_run["run"], small_run["success"]) == ("small", "2", "true")
    assert small_run["scene_topic"] == "/scene/P/small" and small_run["entity_prefix"] == "run-2/"
    assert small_run["frame_id"] == "map/small"


def test_a_runs_movingai_bucket_is_in_its_result_metadata_and_entities(tmp_path):
    """A map with a bucket (a .scen pair's, the spec's ``buckets``) gives its runs' /results
    messages ``bucket`` (an integer the schema declares), their ``swarmpath.run`` records and
    scene entities a ``bucket`` key; a map without one (every map of an older job) has no such
    key anywhere, and a file written so reads as before."""
    from mcap.reader import make_reader

    from swarmpath.path_metrics import PATH_METRICS

    declared = OWN_SCHEMAS["swarmpath.MapRunResult"]["properties"]
    assert declared["bucket"]["type"] == "integer" and set(PATH_METRICS) <= set(declared)
    pair = {**SCENARIO, "name": "arena#150"}
    spec = {"kind": "map", "planners": ["P"], "maps": [SCENARIO, pair], "runs": 1, "seed": 1,
            "buckets": {"arena#150": 15}}
    rec = JobRecorder(tmp_path / "m.mcap", "job1", "map", spec, T0)
    plain = map_record("job1", 0, T0 + 1)
    paired = map_record("job1", 1, T0 + 2, pair)
    paired["spec"]["map"], paired["cell"] = "arena#150", "P/arena#150"
    assert rec.add(plain) and rec.add(paired)
    rec.finish()
    _summary, _metadata, messages = read_all(tmp_path / "m.mcap")
    results = {m["map"]: m for _s, c, m, _t in messages if c.topic == "/results"}
    assert results["arena#150"]["bucket"] == 15 and "bucket" not in results["demo"]
    with open(tmp_path / "m.mcap", "rb") as f:
        runs = {m.metadata["map"]: m.metadata for m in make_reader(f).iter_metadata()
                if m.name == "swarmpath.run"}
    assert runs["arena#150"]["bucket"] == "15" and "bucket" not in runs["demo"]
    entities = [e for _s, c, m, _t in messages if c.topic.startswith("/scene/")
                for e in m["entities"]]
    about = {e["id"]: {kv["key"]: kv["value"] for kv in e["metadata"]} for e in entities}
    assert about["run-1/path"]["bucket"] == "15" and about["run-1/robot"]["bucket"] == "15"
    assert "bucket" not in about["run-0/path"]


# -------------------------------------------------------------------------- recorder process
def test_the_recorder_process_writes_what_the_store_holds_even_after_dying(store):
    """The MCAP written by the recorder process (poked as results are stored, killed once
    midway and restarted) has exactly the messages of the file the coordinator's own recorders
    write from the same store."""
    from swarmpath.service.recorder.process import RecorderProcess

    job = store.create_job(SPEC, now=T0)
    recorder = RecorderProcess(store.data_dir)
    try:
        lease = store.lease("w1", 3, now=T0)
        assert set(store.accept_results(execute(lease), T0)) == {"accepted"}
        recorder.poke(job)
        recorder._proc.kill()  # a crash: the next call starts another, which rebuilds
        recorder._proc.join(10)
        assert drain(store) == 17
        recorder.poke(job)
        path = recorder.finish(job)
        assert path == final_path(store.data_dir, job) and recorder.ready(job)
    finally:
        recorder.close()
    assert recorder._proc.exitcode is not None
    summary, meta, got = read_all(path)
    check_indexed(summary)
    path.rename(path.with_name("process.mcap"))
    _summary, meta_in, want = read_all(Recorders(store).finish(job))
    assert [(c.topic, m, t) for _s, c, m, t in got] == [(c.topic, m, t) for _s, c, m, t in want]
    assert len(got) == 40 and meta == meta_in


def test_a_nav2_map_is_placed_through_its_own_map_frame(tmp_path):
    # a map imported from nav2 carries its YAML origin: /tf puts its scenario frame in the
    # map's own frame at that origin, and the map's frame in the world where the map goes
    nav2 = {**SCENARIO, "name": "nav2", "grid": {"frame": "map", "origin": [-10.0, -4.5],
                                                 "resolution": 0.5, "unknown": []}}
    spec = {"kind": "map", "planners": ["P"], "maps": [nav2], "runs": 1, "seed": 1}
    rec = JobRecorder(tmp_path / "m.mcap", "job1", "map", spec, T0)
    record = map_record("job1", 0, T0 + 1, nav2)
    record["spec"]["map"], record["cell"] = "nav2", "P/nav2"
    assert rec.add(record)
    rec.finish()
    _summary, _metadata, messages = read_all(tmp_path / "m.mcap")
    tfs = {m["child_frame_id"]: m for _s, c, m, _t in messages if c.topic == "/tf"}
    assert set(tfs) == {"map/nav2/map", "map/nav2"}
    assert tfs["map/nav2/map"]["parent_frame_id"] == "world"
    assert tfs["map/nav2"]["parent_frame_id"] == "map/nav2/map"
    assert (tfs["map/nav2"]["translation"]["x"], tfs["map/nav2"]["translation"]["y"]) == (
        -10.0, -4.5)
    # the scenario frame ends up where it was: world x = offset 0, y = 0
    assert tfs["map/nav2/map"]["translation"]["x"] + tfs["map/nav2"]["translation"]["x"] == 0.0
    assert tfs["map/nav2/map"]["translation"]["y"] + tfs["map/nav2"]["translation"]["y"] == 0.0
