"""Plugins on the farm: a coordinator and workers as subprocesses (tests/test_service_e2e.py's
Service). A job naming a plugin no live worker has waits, saying why; a worker without it never
takes its runs, nor does one whose copy of the plugin has other code; a worker with the same code
joins and the job finishes with nothing failed, its runs equal to a local ``bench`` run for run,
its pins in the status, the summary and the MCAP."""

from __future__ import annotations

import hashlib
import io
import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from mcap.reader import make_reader

sys.path.insert(0, str(Path(__file__).parent))
from test_service_e2e import ENV, PY, Service

PLUGIN = textwrap.dedent('''
    import numpy as np
    from swarmpath.functions import BenchmarkFunction, register_function
    from swarmpath.optimizers import register
    from swarmpath.optimizers.gwo import GWO


    @register
    class FarmGWO(GWO):
        """GWO with a steeper start of its a-schedule (a test plugin)."""

        name = "FarmGWO"
        defaults = {**GWO.defaults, "a_max": 2.4}


    def _bowl(x):
        return np.einsum("...i,...i->...", x - 1.0, x - 1.0)


    register_function(BenchmarkFunction("F14", _bowl, -10.0, 10.0, 1.0))
''')
SPEC = {"kind": "benchmark", "algorithms": ["GWO", "FarmGWO"], "functions": ["F1", "F14"],
        "dims": [3], "runs": 3, "agents": 8, "iterations": 15, "seed": 5}


class PluginService(Service):
    def start_coordinator(self, lease_seconds: float = 4.0, plugin: Path | None = None) -> None:
        self.starts += 1
        self.coordinator = self._spawn("coordinator", [
            "coordinator", "--http", f"127.0.0.1:{self.http}", "--zenoh", self.zenoh,
            "--data", str(self.data), "--lease-seconds", str(lease_seconds), "--insecure",
            *(["--plugin", str(plugin)] if plugin else []),
        ])
        self.wait_for(lambda: self.get("/healthz").status_code == 200, 60, "coordinator up")


def _digest(path: Path) -> str:
    data = path.read_bytes()
    return hashlib.sha256(path.name.encode() + b"\0" + str(len(data)).encode() + b"\0"
                          + data).hexdigest()


@pytest.fixture
def farm(tmp_path):
    svc = PluginService(tmp_path / "farm")
    try:
        yield svc
    finally:
        svc.close()


def test_a_plugin_job_waits_for_a_worker_with_the_same_code(farm, tmp_path):
    plugin = tmp_path / "farm_plugin.py"
    plugin.write_text(PLUGIN)
    other = tmp_path / "other" / "farm_plugin.py"  # the same name, other code
    other.parent.mkdir()
    other.write_text(PLUGIN.replace("2.4", "2.6"))
    farm.start_coordinator(plugin=plugin)
    farm.start_worker("plain")
    farm.wait_workers(["plain"])
    job = farm.submit(SPEC)

    def waiting() -> bool:
        s = farm.status(job)
        return s["state"] == "waiting" and s["runs_done"] == 3

    farm.wait_for(waiting, 120, "the built-in cell done, the rest waiting")
    status = farm.status(job)
    assert "no live worker has optimizer FarmGWO (digest " in status["waiting"]
    assert "no live worker has function F14" in status["waiting"]
    pins = status["pins"]
    assert pins["optimizer:FarmGWO"]["digest"] == _digest(plugin)
    assert pins["optimizer:FarmGWO"]["source"] == "file"
    assert pins["optimizer:GWO"]["source"] == "built-in"
    cli = subprocess.run([PY, "-m", "swarmpath.cli", "status", job, "--url", farm.url],
                         capture_output=True, text=True, env=ENV, timeout=60)
    printed = " ".join(cli.stdout.split())
    assert f"job {job} waiting: no live worker has" in printed
    assert "no live worker has optimizer FarmGWO" in printed
    listed = farm.get("/jobs", params={"state": "waiting"}).json()
    assert job in {j["id"] for j in listed}

    farm.start_worker("other", "--plugin", str(other))  # FarmGWO and F14, other code
    farm.wait_workers(["plain", "other"])
    farm.wait_for(lambda: "worker other has digest" in (farm.status(job)["waiting"] or ""),
                  60, "the other worker named in the reason")
    assert farm.status(job)["runs_done"] == 3  # nobody took a plugin cell

    farm.start_worker("good", "--plugin", str(plugin))
    done = farm.wait_done(job, 180)
    assert done["state"] == "done" and done["runs_done"] == 12 and done["runs_failed"] == 0
    runs = farm.runs(job)
    by_worker: dict[tuple[str, str], set[str]] = {}
    for r in runs:
        by_worker.setdefault((r["algorithm"], r["function"]), set()).add(r["worker"])
    assert by_worker[("GWO", "F1")] <= {"plain", "good"}
    for cell in (("FarmGWO", "F1"), ("FarmGWO", "F14"), ("GWO", "F14")):
        assert by_worker[cell] == {"good"}, (cell, by_worker[cell])

    local = subprocess.run(
        [PY, "-m", "swarmpath.cli", "bench", "-a", "GWO,FarmGWO", "-f", "F1,F14", "-d", "3",
         "--runs", "3", "--agents", "8", "--iterations", "15", "--seed", "5", "--json",
         "--plugin", str(plugin)], capture_output=True, text=True, env=ENV, timeout=300)
    assert local.returncode == 0, local.stderr
    for cell in json.loads(local.stdout)["cells"]:
        got = [r for r in runs if (r["algorithm"], r["function"]) == (cell["algorithm"],
                                                                     cell["function"])]
        assert [r["best_fitness"] for r in sorted(got, key=lambda r: r["run"])] == \
            cell["best_fitness"], cell["algorithm"] + "/" + cell["function"]
    assert json.loads(local.stdout)["extensions"]["optimizer:FarmGWO"]["digest"] == _digest(
        plugin)

    summary = farm.get(f"/jobs/{job}/summary").json()
    assert summary["pins"]["function:F14"]["digest"] == _digest(plugin)
    farm.wait_for(lambda: farm.get(f"/jobs/{job}/mcap").status_code == 200, 60, "the MCAP")
    reader = make_reader(io.BytesIO(farm.get(f"/jobs/{job}/mcap").content))
    meta = {m.name: m.metadata for m in reader.iter_metadata()}
    assert json.loads(meta["swarmpath.extensions"]["optimizer:FarmGWO"])["digest"] == _digest(
        plugin)
