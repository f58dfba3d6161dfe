"""Job MCAP files pass the checks of @mcap/core, the TypeScript reader Foxglove itself uses.

tests/mcap_reader/check.mjs reads a file twice with that library (indexed, with CRC validation of
every chunk, and streamed record by record), compares the Statistics record, the chunk and message
indexes and the messages actually read, verifies the data section CRC, and prints the channels and
schemas as the library decoded them. scripts/test installs the library with `npm ci`.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from swarmpath import __version__
from swarmpath.service import foxglove as fg
from swarmpath.service.recorder import JobRecorder, Recorders
from swarmpath.service.recorder.common import COMPRESSION_ENV, COMPRESSIONS
from swarmpath.service.store import Store

sys.path.insert(0, str(Path(__file__).parent))
from test_recorder import SCENARIO, map_record
from test_store import SPEC, T0, execute

READER = Path(__file__).parent / "mcap_reader"


def _node() -> str:
    node = shutil.which("node")
    if node is None:
        pytest.skip("Node.js is not installed: the @mcap/core check needs `node` on PATH")
    if not (READER / "node_modules" / "@mcap" / "core").is_dir():
        pytest.fail(f"@mcap/core is not installed: run scripts/test (it runs npm ci in {READER})")
    return node


def foxglove_read(path: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([_node(), str(READER / "check.mjs"), str(path)],
                          capture_output=True, text=True, timeout=60)


def accepted(path: Path) -> dict[str, Any]:
    done = foxglove_read(path)
    assert done.returncode == 0, done.stderr
    report: dict[str, Any] = json.loads(done.stdout)
    return report


def topics(report: dict[str, Any]) -> dict[str, dict[str, Any]]:
    return {c["topic"]: c for c in report["channels"]}


def check_common(report: dict[str, Any], compression: str = COMPRESSIONS[0],
                 pinned: bool = True) -> None:
    """``pinned``: the file is a stored job's (its extensions pinned), not a bare recorder's."""
    assert report["library"].startswith(f"swarmpath {__version__}")
    names = {"none": ""}  # how the MCAP chunk record names no compression
    assert report["chunks"] >= 1
    assert report["compression"] == [names.get(compression, compression)]
    assert report["dataSectionCrc"] == "valid"
    assert report["messageCount"] == sum(c["messages"] for c in report["channels"])
    for channel in report["channels"]:
        assert channel["messageEncoding"] == "json" and channel["schemaEncoding"] == "jsonschema"
        assert fg.check_foxglove_rules(channel["schema"]) == [], channel["topic"]
    job = report["metadata"]["swarmpath.job"]
    assert job["swarmpath_version"] == __version__ and json.loads(job["spec"])
    indexes = list(report["metadataIndexes"])
    assert indexes[0] == "swarmpath.job" and indexes[-1] == "swarmpath.summary"
    if pinned:  # the job's pinned extensions (origin, version, digest) right after it
        assert indexes.pop(1) == "swarmpath.extensions"
        pins = {k: json.loads(v) for k, v in report["metadata"]["swarmpath.extensions"].items()}
        assert pins and all(len(p["digest"]) == 64 for p in pins.values())
    # one swarmpath.run per map run, one swarmpath.platform per worker and platform that sent
    # results (written by a live coordinator, not by a rebuild from the store)
    assert set(indexes[1:-1]) <= {"swarmpath.run", "swarmpath.platform"}


@pytest.fixture
def store(tmp_path):
    s = Store(tmp_path / "data")
    yield s
    s.close()


def benchmark_file(store: Store) -> tuple[Path, int]:
    job = store.create_job(SPEC, now=T0)
    recorders = Recorders(store)
    recorders.open(job)
    runs = 0
    while (lease := store.lease("w1", 3, now=T0)) is not None:
        store.accept_results(execute(lease), T0)
        for run_id in lease.run_ids():
            assert recorders.record_run(job, run_id)
            runs += 1
    return recorders.finish(job), runs


@pytest.mark.parametrize("compression", COMPRESSIONS)
def test_every_chunk_compression_passes_the_foxglove_reader(store, monkeypatch, compression):
    monkeypatch.setenv(COMPRESSION_ENV, compression)
    path, runs = benchmark_file(store)
    report = accepted(path)
    check_common(report, compression)
    assert topics(report)["/curves"]["messages"] == runs == 20


def test_a_benchmark_job_file_passes_the_foxglove_reader(store):
    path, runs = benchmark_file(store)
    report = accepted(path)
    check_common(report)
    by_topic = topics(report)
    assert by_topic["/results"]["messages"] == runs == 20  # one message per completed run
    assert by_topic["/results"]["schemaName"] == "swarmpath.BenchmarkRunResult"
    assert by_topic["/curves"]["messages"] == runs
    assert report["metadata"]["swarmpath.summary"]["runs_written"] == str(runs)


def test_a_map_job_file_passes_the_foxglove_reader(tmp_path):
    spec = {"kind": "map", "planners": ["P"], "maps": [SCENARIO], "runs": 3, "seed": 1}
    recorder = JobRecorder(tmp_path / "m.mcap", "job1", "map", spec, T0)
    for run in range(3):
        assert recorder.add(map_record("job1", run, T0 + 1 + run))
    recorder.finish()
    report = accepted(tmp_path / "m.mcap")
    check_common(report, pinned=False)
    by_topic = topics(report)
    assert by_topic["/results"]["messages"] == 3
    # Foxglove's well-known schemas, by exact name, on the map, scene and trajectory topics
    assert by_topic["/map/demo/occupancy"]["schemaName"] == "foxglove.Grid"
    assert by_topic["/map/demo/obstacles"]["schemaName"] == "foxglove.SceneUpdate"
    assert by_topic["/scene/P/demo"]["schemaName"] == "foxglove.SceneUpdate"
    assert by_topic["/paths/P/demo"]["schemaName"] == "foxglove.PosesInFrame"
    assert by_topic["/paths/P/demo"]["messages"] == 3
    assert by_topic["/tf"]["schemaName"] == "foxglove.FrameTransform"
    assert report["metadataIndexes"].count("swarmpath.run") == 3


def test_the_reader_rejects_damaged_files(store, tmp_path):
    path, _runs = benchmark_file(store)
    data = bytearray(path.read_bytes())
    # A flipped byte inside the first chunk's compressed records breaks its CRC.
    damaged = tmp_path / "damaged.mcap"
    middle = len(data) // 4
    data[middle] ^= 0xFF
    damaged.write_bytes(bytes(data))
    done = foxglove_read(damaged)
    assert done.returncode == 1 and "mcap check:" in done.stderr
    # A file cut short (a crash before finish) has no footer: the indexed reader refuses it.
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[: len(data) // 2])
    done = foxglove_read(cut)
    assert done.returncode == 1 and "indexed reader" in done.stderr
