"""A raced job through the service: a worker and the coordinator SIGKILLed in the middle of the
race, and the race ends as the pure replay over directly computed runs says; the summary, the
race document, ``swarmpath results`` and the MCAP carry the decisions."""

from __future__ import annotations

import io
import json
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from mcap.reader import make_reader

from swarmpath.evidence.race_report import study_race
from swarmpath.evidence.racing import race_block
from swarmpath.optimizers import minimize
from swarmpath.service.foxglove_schemas import check_message
from swarmpath.service.protocol import parse_job_spec

sys.path.insert(0, str(Path(__file__).parent))
from test_service_e2e import ENV, PY, Service

# The default design (Pocock-spent rank-sum looks every round from 16 runs, written into the
# stored spec) with futility 0.01 (the default 0.05 stops F5's PSO at 24 runs, before a kill
# could land mid-race): F1's comparisons and F5's SSA are decided at the looks at 16 and 24
# runs, PSO against GWO, open without futility to the end, stops as futile at the look at 48
# runs (6 rounds): 168 of the 360 runs
SPEC = {"kind": "benchmark", "algorithms": ["SSA", "PSO", "GWO"], "functions": ["F1", "F5"],
        "dims": [6], "runs": 60, "agents": 10, "iterations": 300, "seed": 4,
        "racing": {"min_runs": 8, "batch": 8, "futility": 0.01}}
# the same study without looks (looks [], the default before; so no futility): F1 is decided
# by the sequence after two rounds, F5's SSA after four, PSO stays open: 200 runs
PLAIN_SPEC = {**SPEC, "racing": {"min_runs": 8, "batch": 8, "looks": []}}


@pytest.fixture(scope="module")
def service(tmp_path_factory) -> Iterator[Service]:
    svc = Service(tmp_path_factory.mktemp("racing"))
    try:
        svc.start_worker("w1")
        svc.start_worker("w2")
        svc.start_coordinator(lease_seconds=6.0)
        svc.wait_workers(["w1", "w2"])
        yield svc
    finally:
        svc.close()


def expected_race(race: dict, spec: dict = SPEC) -> dict:
    """The race document of the job's study replayed over directly computed runs, its blocks
    (and their cells' order) as in ``race``."""
    settings = parse_job_spec(spec).racing.settings(60)
    blocks = []
    for block in race["blocks"]:
        names = [c["algorithm"] for c in block["cells"]]
        values = {a: minimize(a, block["block"]["function"], 6, 10, 300, seed=4,
                              runs=60).best_fitness for a in names}
        blocks.append(({}, race_block(values, names, settings, 4), list(enumerate(names))))
    return study_race(settings, 4, blocks)


def test_a_raced_job_survives_kills_and_decides_as_the_replay(service, tmp_path):
    job = service.submit(SPEC)
    plain = service.submit(PLAIN_SPEC)  # races beside it, through the same kills
    service.wait_for(lambda: service.status(job)["runs_done"] >= 20, 300, "the first round")
    busy = [w["id"] for w in service.get("/workers").json() if w["alive"] and w["current_runs"]]
    victim = busy[0] if busy else "w1"
    service.kill(service.workers[victim])
    service.start_worker(victim + "b")

    def racing_on() -> bool:
        blocks = service.get(f"/jobs/{job}/race").json()["blocks"]
        return max(b["rounds"] for b in blocks) >= 3 and not all(b["finished"] for b in blocks)

    service.wait_for(racing_on, 180, "a block in its fourth round")
    service.kill(service.coordinator)
    time.sleep(1.0)
    service.start_coordinator(lease_seconds=6.0)
    status = service.wait_done(job, 300)
    assert status["state"] == "done" and status["runs_failed"] == 0
    assert service.wait_done(plain, 300)["state"] == "done"
    race = service.get(f"/jobs/{plain}/race").json()
    for block, expected in zip(race["blocks"], expected_race(race, PLAIN_SPEC)["blocks"],
                               strict=True):
        assert [c["runs"] for c in block["cells"]] == [c["runs"] for c in expected["cells"]]
        assert [(d["decision"], d["final"], d["look"]) for d in block["duels"]] == [
            (d["decision"], d["final"], d["look"]) for d in expected["duels"]]
    assert not any(d["look"] for b in race["blocks"] for d in b["duels"])
    assert sum(c["runs"] for b in race["blocks"] for c in b["cells"]) == 200

    race = service.get(f"/jobs/{job}/race").json()
    assert race["settings"]["looks"] == "every-round"
    used = 0
    for block, expected in zip(race["blocks"], expected_race(race)["blocks"], strict=True):
        assert [c["runs"] for c in block["cells"]] == [c["runs"] for c in expected["cells"]]
        assert [(d["decision"], d["final"], d["look"], d["power"]) for d in block["duels"]] == [
            (d["decision"], d["final"], d["look"], d["power"]) for d in expected["duels"]]
        used += sum(c["runs"] for c in block["cells"])
    assert sorted(d["look"] for b in race["blocks"] for d in b["duels"] if d["look"]) == [
        16, 16, 24, 48]
    assert [(b["block"]["function"], d["a"]) for b in race["blocks"] for d in b["duels"]
            if d["decision"] == "futile"] == [("F5", "PSO")]
    assert status["runs_done"] == status["runs_total"] == used == 168

    runs = service.get(f"/jobs/{job}/runs", params={"limit": 1000}).json()["items"]
    assert len(runs) == used and {r["state"] for r in runs} == {"done"}
    direct = minimize("SSA", "F5", 6, 10, 300, seed=4, runs=60).best_fitness
    ssa = [r for r in runs if r["cell"] == "SSA/F5/6"]
    assert [r["best_fitness"] for r in ssa] == direct[: len(ssa)].tolist()

    summary = service.get(f"/jobs/{job}/summary").json()
    assert summary["statistics"]["race"] == race
    by_cell = {c["cell"]: c["runs"] for b in race["blocks"] for c in b["cells"]}
    assert [row["race_runs"] for row in summary["rows"]] == [by_cell[i] for i in range(6)]
    mcap = service.get(f"/jobs/{job}/mcap")
    reader = make_reader(io.BytesIO(mcap.content))
    blocks = [json.loads(m.data) for _s, _c, m in reader.iter_messages(topics=["/race"])]
    assert sorted(b["block"]["function"] for b in blocks) == ["F1", "F5"]
    assert all(b["finished"] for b in blocks)
    assert not any(check_message(b) for b in blocks)  # Foxglove reads them: no nulls
    meta = {m.name: m.metadata for m in reader.iter_metadata()}
    assert json.loads(meta["swarmpath.race"]["settings"])["min_runs"] == 8
    results = list(reader.iter_messages(topics=["/results"]))
    assert len(results) == used

    out = subprocess.run([PY, "-m", "swarmpath.cli", "results", job, "--url", service.url],
                         capture_output=True, text=True, env={**ENV, "COLUMNS": "250"},
                         timeout=120)
    assert out.returncode == 0, out.stderr
    assert "race (alpha 0.05 over 4 comparisons" in out.stdout and "race_runs" in out.stdout


def test_a_race_extended_through_the_cli_reuses_its_runs(service):
    job = service.submit({**SPEC, "runs": 24})
    assert service.wait_done(job, 300)["state"] == "done"
    out = subprocess.run([PY, "-m", "swarmpath.cli", "extend", job, "--runs", "60", "--wait",
                          "--url", service.url], capture_output=True, text=True, env=ENV,
                         timeout=600)
    assert out.returncode == 0, out.stderr
    new = out.stdout.split()[0]
    assert f"extends {job} to 60 runs per cell" in out.stderr
    reused = int(out.stderr.split(" runs reused")[0].rsplit(" ", 1)[1])
    assert reused == service.status(job)["runs_done"]
    race = service.get(f"/jobs/{new}/race").json()
    assert race["settings"]["looks"] == [16]  # the old job's rounds' looks (store.extend)
    frozen = {**SPEC, "racing": {**SPEC["racing"], "looks": [16]}}
    for block, expected in zip(race["blocks"], expected_race(race, frozen)["blocks"],
                               strict=True):
        assert [c["runs"] for c in block["cells"]] == [c["runs"] for c in expected["cells"]]
    runs = service.get(f"/jobs/{new}/runs", params={"limit": 1000}).json()["items"]
    old = {(r["cell"], r["run"]): r for r in service.get(
        f"/jobs/{job}/runs", params={"limit": 1000}).json()["items"]}
    assert sum((r["cell"], r["run"]) in old for r in runs) == reused
    assert all(r["worker"] == old[(r["cell"], r["run"])]["worker"] for r in runs
               if (r["cell"], r["run"]) in old)  # copied, not run again
    bad = service.http_client.post(f"/jobs/{new}/extend", json={"runs": 10})
    assert bad.status_code == 422 and bad.json()["detail"][0]["loc"] == ["body", "runs"]
