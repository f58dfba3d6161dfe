"""The example plugin package (examples/swarmpath-example), installed as a user installs it:
``pip install`` into a directory of its own (its entry points are found there), then its own test
suite, ``swarmpath plugins``, ``plan`` with ``swarm:mGWO``, ``audit``, ``reproduce --add``, and
``swarmpath up``, whose results must equal a local ``bench`` run for run - installed, and loaded
with ``--plugin`` files instead. The main suite's processes never see the plugin (it is not in
.venv)."""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

import owned

sys.path.insert(0, str(Path(__file__).parent))
from test_service_e2e import ENV, PY, ROOT, free_port, stop_group

EXAMPLE = ROOT / "examples" / "swarmpath-example"
FILES = [EXAMPLE / "src" / "swarmpath_example" / "mgwo.py",
         EXAMPLE / "src" / "swarmpath_example" / "spring.py"]
SPEC = {"kind": "benchmark", "algorithms": ["GWO", "mGWO"], "functions": ["spring-design", "F1"],
        "dims": [3], "runs": 4, "agents": 10, "iterations": 30, "seed": 3}


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The example installed (pip, no network: the test extra brings setuptools) into a site
    directory of its own; built from a copy, so the checkout gets no build files."""
    tmp = tmp_path_factory.mktemp("example")
    source = tmp / "source"
    shutil.copytree(EXAMPLE, source, ignore=shutil.ignore_patterns("build", "*.egg-info"))
    target = tmp / "site"
    done = subprocess.run([PY, "-m", "pip", "install", "--quiet", "--no-deps",
                           "--no-build-isolation", "--target", str(target), str(source)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    return target


def env_for(site: Path | None) -> dict[str, str]:
    env = {k: v for k, v in ENV.items() if k != "SWARMPATH_PLUGINS"}
    if site is not None:
        env["PYTHONPATH"] = os.pathsep.join([str(site), ENV["PYTHONPATH"]])
    return env


def cli(args: list[str], env: dict[str, str], timeout: float = 600) -> subprocess.CompletedProcess:
    return subprocess.run([PY, "-m", "swarmpath.cli", *args], capture_output=True, text=True,
                          env=env, timeout=timeout)


def test_the_example_test_suite_passes_installed(site):
    out = subprocess.run([PY, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                          str(EXAMPLE / "tests")], capture_output=True, text=True,
                         env=env_for(site), timeout=900, cwd=site)
    assert out.returncode == 0, out.stdout[-4000:] + out.stderr[-2000:]
    assert " passed" in out.stdout and "failed" not in out.stdout


def test_installed_extensions_come_from_their_distribution(site):
    out = cli(["plugins", "--only-plugins", "--json"], env_for(site))
    assert out.returncode == 0, out.stderr
    rows = {(r["kind"], r["name"]): r for r in json.loads(out.stdout)["extensions"]}
    assert set(rows) == {("optimizer", "mGWO"), ("function", "spring-design")}
    for row in rows.values():
        assert row["origin"] == "distribution swarmpath-example 0.1.0"
    plan = cli(["plan", "-p", "swarm:mGWO", "-m", "mfb-static", "--runs", "1", "--json"],
               env_for(site))
    assert plan.returncode == 0, plan.stderr
    assert [r["planner"] for r in json.loads(plan.stdout)["runs"]] == ["swarm:mGWO"]
    audit = cli(["audit", "-a", "mGWO", "-f", "F1,F9", "-d", "5", "--runs", "3",
                 "--iterations", "50", "--json"], env_for(site))
    assert audit.returncode == 0, audit.stderr
    assert "mGWO" in audit.stdout
    beside = cli(["reproduce", "icoot-table2", "-a", "COOT,ICOOT", "-f", "F1", "--runs", "2",
                  "--no-origin-check", "-j", "1", "--add", "mGWO", "--json"], env_for(site))
    assert beside.returncode == 0, beside.stderr
    (cell,) = json.loads(beside.stdout)["statistics"]["added"]["cells"]
    assert (cell["algorithm"], cell["function"], len(cell["runs"])) == ("mGWO", "F1", 2)


def _local(env: dict[str, str], extra: list[str]) -> dict[tuple[str, str], list[float]]:
    out = cli(["bench", "-a", "GWO,mGWO", "-f", "spring-design,F1", "-d", "3", "--runs", "4",
               "--agents", "10", "--iterations", "30", "--seed", "3", "--json", *extra], env)
    assert out.returncode == 0, out.stderr
    return {(c["algorithm"], c["function"]): c["best_fitness"]
            for c in json.loads(out.stdout)["cells"]}


@pytest.mark.parametrize("how", ["installed", "--plugin"])
def test_up_gives_the_runs_of_a_local_bench(site, tmp_path, how):
    env = env_for(site if how == "installed" else None)
    extra = [] if how == "installed" else [a for f in FILES for a in ("--plugin", str(f))]
    http, zport = free_port(), free_port()
    log = open(tmp_path / "up.log", "wb")
    proc = owned.popen(
        [PY, "-m", "swarmpath.cli", "up", "--workers", "1", "--slots", "2", "--http",
         f"127.0.0.1:{http}", "--zenoh", f"tcp/127.0.0.1:{zport}", "--data",
         str(tmp_path / "data"), *extra], stdout=log, stderr=log, env=env)
    try:
        with httpx.Client(base_url=f"http://127.0.0.1:{http}", timeout=30.0) as client:
            status = _run_job(client, proc, tmp_path)
            assert status["state"] == "done" and status["runs_failed"] == 0, status
            origin = status["pins"]["optimizer:mGWO"]["origin"]
            assert origin == ("distribution swarmpath-example 0.1.0" if how == "installed"
                              else f"file {FILES[0]}")
            runs = client.get(f"/jobs/{status['id']}/runs", params={"limit": 100}).json()["items"]
        farm: dict[tuple[str, str], list[float]] = {}
        for r in sorted(runs, key=lambda r: r["run"]):
            farm.setdefault((r["algorithm"], r["function"]), []).append(r["best_fitness"])
        assert farm == _local(env, extra)  # the same numbers, run for run
    finally:
        stop_group(proc)
        log.close()


def _run_job(client: httpx.Client, proc: subprocess.Popen[bytes], tmp: Path) -> dict:
    deadline = time.monotonic() + 240
    job = None
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise AssertionError((tmp / "up.log").read_text(errors="replace")[-4000:])
        with contextlib.suppress(httpx.HTTPError):
            if job is None:
                workers = client.get("/workers").json()
                if any(w["alive"] for w in workers):
                    r = client.post("/jobs", json=SPEC)
                    assert r.status_code == 201, r.text
                    job = r.json()["id"]
            else:
                status = client.get(f"/jobs/{job}").json()
                if status["state"] in ("done", "failed", "cancelled"):
                    return dict(status)
        time.sleep(0.5)
    raise AssertionError("the job did not finish: " +
                         (tmp / "up.log").read_text(errors="replace")[-4000:])
