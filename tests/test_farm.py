"""The farm simulator (scripts/bench/farm.py): its simulated workers' results go through the
coordinator's real checks (login, liveliness, lease capability proofs, fencing) and a job is
completed exactly once; results proven with a wrong key are never accepted."""

from __future__ import annotations

import importlib.util
import json
import os
import sqlite3
import subprocess
import sys
from pathlib import Path

from mcap.reader import make_reader

from swarmpath.service.store import Store

ROOT = Path(__file__).resolve().parents[1]
FARM = ROOT / "scripts" / "bench" / "farm.py"


def _farm_memory():
    spec = importlib.util.spec_from_file_location(
        "farm_memory", ROOT / "scripts" / "bench" / "farm_memory.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def farm(tmp: Path, *args: str, timeout: float = 120.0) -> tuple[int, dict]:
    out = tmp / "farm.json"
    proc = subprocess.run(
        [sys.executable, str(FARM), "--data", str(tmp / "data"), "--json", str(out), *args],
        capture_output=True, text=True, timeout=timeout,
        env={"PYTHONPATH": str(ROOT / "services"), "PATH": "/usr/bin:/bin"},
    )
    assert out.is_file(), proc.stderr[-3000:]
    (res,) = json.loads(out.read_text())
    return proc.returncode, res


def test_simulated_workers_complete_a_job_exactly_once(tmp_path):
    code, res = farm(tmp_path, "--workers", "3", "--procs", "2", "--slots", "2", "--runs", "60",
                     "--cells", "3", "--iterations", "50", "--runs-per-lease", "7",
                     "--seconds", "60")
    assert code == 0, res
    assert res["state"] == "done" and res["runs_finished"] == res["runs_total"] == 180
    m = res["metrics"]
    assert m["results_accepted_total"] == 180
    assert m["messages_unproven_total"] == 0 and m["results_stale_total"] == 0
    assert res["alive_seen"] == 3
    store = Store(tmp_path / "data" / "this-k3" / "store")
    try:
        runs = list(store.iter_runs(res["job"]))
    finally:
        store.close()
    assert [r["run_id"] for r in runs] == list(range(180))
    assert all(r["state"] == "done" and len(r["curve"]) == 50 and len(r["best_position"]) == 2
               and r["worker"].startswith("farm-sim") for r in runs)  # ids of the farm's login
    # runs of one template differ (each run's numbers are its own), as real runs do
    assert len({r["curve"][-1] for r in runs}) == 180
    db = sqlite3.connect(tmp_path / "data" / "this-k3" / "store" / "swarmpath.sqlite3")
    assert db.execute("SELECT COUNT(*) FROM results").fetchone()[0] == 180
    db.close()
    mcap = tmp_path / "data" / "this-k3" / "store" / "mcap" / f"{res['job']}.mcap"
    with open(mcap, "rb") as f:
        ids = [json.loads(msg.data)["run_id"]
               for _s, channel, msg in make_reader(f).iter_messages()
               if channel.topic == "/results"]
    assert sorted(ids) == list(range(180))


def test_results_proven_with_a_wrong_key_are_never_accepted(tmp_path):
    code, res = farm(tmp_path, "--workers", "1", "--runs", "20", "--iterations", "20",
                     "--seconds", "4", "--wrong-capability")
    assert code == 1
    assert res["state"] == "cancelled" and res["runs_finished"] == 0
    assert res["metrics"]["results_accepted_total"] == 0
    assert res["metrics"]["results_stale_total"] >= 20


def test_map_runs_arrive_with_their_paths(tmp_path):
    code, res = farm(tmp_path, "--workers", "2", "--runs", "6", "--map", "mfb-static",
                     "--planner", "MFB", "--seconds", "60")
    assert code == 0 and res["state"] == "done" and res["runs_finished"] == 6
    store = Store(tmp_path / "data" / "this-k2" / "store")
    try:
        runs = list(store.iter_runs(res["job"]))
    finally:
        store.close()
    assert [r["run_id"] for r in runs] == list(range(6))
    # a real run's path (rows x, y, t) and outcome, each run's times its own
    assert all(r["success"] and len(r["path"]) > 10 and len(r["path"][0]) == 3 for r in runs)
    assert len({r["path"][-1][2] for r in runs}) == 6


def test_memory_profile_marks_the_quarters_and_the_second_half_slope():
    fm = _farm_memory()
    # 0..1000 runs in steps of 100, one sample a second; RSS +2 KB per run in the first half,
    # flat after it (anonymous = RSS - 50 MB)
    samples = []
    for i in range(11):
        runs = 100 * i
        rss = 200.0 + min(runs, 500) * 2 / 1024
        samples.append((float(i), runs, rss, rss - 50.0, 50.0))
    p = fm.memory_profile(samples, 1000)
    assert p["rss_at"] == {"0": 200.0, "25": round(200 + 300 * 2 / 1024, 1),
                           "50": round(200 + 1000 / 1024, 1), "75": round(200 + 1000 / 1024, 1),
                           "100": round(200 + 1000 / 1024, 1)}
    assert p["anon_at"]["100"] == round(150 + 1000 / 1024, 1)
    assert p["second_half_mb"] == 0.0 and p["slope_kb_per_run"] == 0.0
    assert p["slope_mb_per_s"] == 0.0
    # growing all along: the slope over the second half is the growth per run and per second
    growing = [(float(i), 100 * i, 200.0 + 100 * i * 2 / 1024, 150.0, 50.0) for i in range(11)]
    g = fm.memory_profile(growing, 1000)
    assert g["slope_kb_per_run"] == 2.0 and g["slope_mb_per_s"] == round(200 / 1024, 4)
    assert g["second_half_mb"] == round(g["rss_at"]["100"] - g["rss_at"]["50"], 1) > 0.9
    # a job cancelled before its end has no 100 % mark and no slope
    cut = fm.memory_profile(growing[:6], 1000)
    assert "100" not in cut["rss_at"] and cut["slope_kb_per_run"] is None
    assert "50" in cut["rss_at"] and "75" not in cut["rss_at"]
    assert "slope 2.0 KB per run" in fm.profile_line(g)


def test_proc_memory_splits_the_resident_memory():
    rss, anon, file = _farm_memory().proc_memory(os.getpid())
    assert rss > 0 and anon > 0 and file > 0
    assert abs(rss - anon - file) < 1.0  # VmRSS = RssAnon + RssFile + RssShmem
