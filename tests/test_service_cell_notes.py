"""A map job says why a cell has no exact optimum and warns about stated trajectories that cross
a static obstacle: found by the worker, carried in the run metrics (bounded), checked by the
coordinator and shown in the summary, the runs and the dashboard; the optimum's time budget is a
job spec field (422 naming it)."""

from __future__ import annotations

import base64
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from swarmpath.service.cell_notes import (
    MAX_NOTE_CHARS,
    MAX_WARNINGS,
    CellNotes,
    cell_notes,
    note_lines,
    note_metrics,
)
from swarmpath.service.http.app import create_app
from swarmpath.service.protocol import Keys, Lease, LeaseRequest, decode_work_reply, encode
from swarmpath.service.scenarios import ByteLRU, answer, resolve
from swarmpath.service.settings import CoordinatorSettings
from swarmpath.service.worker import execute_lease, pack_lease_columns

DATA = Path(__file__).parent / "data"
ARENA = (DATA / "arena.map").read_text()
WALL = {"shape": "polygon", "points": [[6, 0], [6.5, 0], [6.5, 10], [6, 10]]}
RRT = {"OMPL-RRTstar": {"iterations": 1000}}


@pytest.fixture
def client(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Any:
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    app = create_app(CoordinatorSettings(data_dir=tmp_path / "data"), use_zenoh=False)
    with TestClient(app) as c:
        yield c


def _work_off(client: Any) -> int:
    """A worker's loop on the app's coordinator: lease, execute, put columnar frames."""
    core = client.app.state.core
    core.publish = lambda key, payload: None
    core.worker_alive("w1")
    cache = ByteLRU(10_000_000)

    def fetch(key: str, payload: bytes) -> bytes:
        return answer(key, payload, core.store.lease_scenario_ref, core.store.lease_scenario,
                      cache)

    done = 0
    while True:
        reply = decode_work_reply(core.handle_lease_request(
            encode(LeaseRequest(worker="w1", max_runs=10))))
        if not isinstance(reply, Lease):
            return done
        # a scenario over INLINE_SCENARIO_BYTES (an uploaded nav2 map with its grid) travels by
        # reference: fetched as the worker fetches it, through the coordinator's answer
        ref = getattr(reply.spec, "scenario_ref", None)
        if ref is not None:
            reply = resolve(reply, Keys().scenario(ref.sha256), fetch, cache)
        results = execute_lease(reply)
        triples = [(reply.lease_id, reply.capability, data) for _run, data in results]
        for payload in pack_lease_columns("w1", triples):
            core.handle_results(f"swarmpath/results/{reply.job_id}", payload)
        done += len(results)


def _walls(name: str, **extra: object) -> dict:
    doc = {"name": name, "size": [10, 10], "start": [1, 1], "goal": [3, 5],
           "robot": {"model": "omni", "radius": 0.3}, "obstacles": [WALL]}
    doc.update(extra)
    return doc


def test_a_tiny_budget_says_why_and_enough_budget_gives_a_gap(client: Any) -> None:
    tb3 = client.post("/maps", json={
        "name": "tb3", "format": "nav2", "yaml": (DATA / "tb3_sandbox.yaml").read_text(),
        "image": base64.b64encode((DATA / "tb3_sandbox.pgm").read_bytes()).decode()}).json()
    arena = client.post("/maps", json={"name": "arena", "format": "movingai",
                                       "map": ARENA}).json()
    tiny = client.post("/jobs", json={"kind": "map", "planners": ["OMPL-RRTstar"], "runs": 2,
                                      "params": RRT, "maps": [{"map": tb3["id"]}],
                                      "optimum_budget": 1e-6})
    assert tiny.status_code == 201, tiny.text
    enough = client.post("/jobs", json={"kind": "map", "planners": ["OMPL-RRTstar"], "runs": 1,
                                        "params": RRT, "maps": [{"map": arena["id"]}]})
    assert enough.status_code == 201, enough.text
    assert _work_off(client) == 3
    summary = client.get(f"/jobs/{tiny.json()['id']}/summary").json()
    [row] = summary["rows"]
    assert row["gap_mean"] is None and summary["warnings"] == []
    assert row["optimum_reason"].startswith("time budget of 1e-06 s exhausted after ")
    runs = client.get(f"/jobs/{tiny.json()['id']}/runs").json()["items"]
    assert [r["optimum_reason"] == row["optimum_reason"] for r in runs] == [True, True]
    summary = client.get(f"/jobs/{enough.json()['id']}/summary").json()
    [row] = summary["rows"]
    assert row["optimum_reason"] is None and row["gap_mean"] > 0
    [run] = client.get(f"/jobs/{enough.json()['id']}/runs").json()["items"]
    assert "optimum_reason" not in run and run["optimum"] > 0
    cells = client.get(f"/ui/jobs/{tiny.json()['id']}/data").json()
    text = repr(cells)
    assert "time budget of 1e-06 s exhausted" in text


def test_stated_paths_through_walls_are_warned_naming_the_field(client: Any) -> None:
    mover = {"shape": "circle", "center": [2, 8], "radius": 0.4, "speed": 0.5,
             "heading_deg": 0}
    job = client.post("/jobs", json={
        "kind": "map", "planners": ["OMPL-RRTstar"], "runs": 1, "params": RRT,
        "maps": ["mfb-static", _walls("clear"),
                 _walls("walls", obstacles=[WALL, mover],
                        goal_motion={"speed": 0.2, "heading_deg": 0})]})
    assert job.status_code == 201, job.text  # a warning never refuses the job
    assert _work_off(client) == 3
    summary = client.get(f"/jobs/{job.json()['id']}/summary").json()
    warnings = summary["warnings"]
    assert [(w["field"], w["map"]) for w in warnings] == [("maps[2].goal_motion", "walls"),
                                                         ("maps[2].obstacles[1]", "walls")]
    assert "the goal's stated path enters a static obstacle" in warnings[0]["message"]
    assert "t = 13.5 s" in warnings[0]["message"]
    assert "t = 7.2 s" in warnings[1]["message"]
    reasons = {r["map"]: r["optimum_reason"] for r in summary["rows"]}
    assert reasons["mfb-static"] is None and reasons["clear"] is None
    assert "moving" in reasons["walls"]
    lines = note_lines(summary)  # what `swarmpath results JOB` prints under the table
    assert lines[0] == f"no exact optimum on walls (blank gap): {reasons['walls']}"
    assert lines[1].startswith("warning: maps[2].goal_motion (walls): the goal's stated path")
    assert len(lines) == 3
    data = client.get(f"/ui/jobs/{job.json()['id']}/data").json()  # the dashboard's job page
    walls = next(g for g in data["groups"] if g["map"] == "walls")["planners"]["OMPL-RRTstar"]
    assert [f for f, _m in walls["warnings"]] == ["goal_motion", "obstacles[1]"]
    assert walls["optimum_reason"] == reasons["walls"]


@pytest.mark.parametrize("value", [0, -1, 1e9, "soon", True])
def test_a_bad_budget_is_a_422_naming_the_field(client: Any, value: object) -> None:
    r = client.post("/jobs", json={"kind": "map", "planners": ["MFB"], "maps": ["mfb-static"],
                                   "optimum_budget": value})
    assert r.status_code == 422, r.text
    assert r.json()["detail"][0]["loc"][:2] == ["body", "optimum_budget"]


def test_the_worker_bounds_what_it_sends() -> None:
    long = "x" * (MAX_NOTE_CHARS * 3)
    many = [(f"obstacles[{k}]", long) for k in range(3 * MAX_WARNINGS)]
    out = note_metrics(long, [("not a field", "m"), *many])
    assert len(out) == 1 + MAX_WARNINGS and "warning:not a field" not in out
    assert all(len(v) == MAX_NOTE_CHARS for v in out.values())
    assert note_metrics(None, []) == {}


def test_the_coordinator_trusts_nothing_in_the_metrics() -> None:
    runs: list[dict[str, Any]] = [
        {"optimum_reason": 7, "warning:goal_motion": "x" * (MAX_NOTE_CHARS + 1),
         "warning:obstacles[1]; drop table": "y", "warning:obstacles[2]": ["z"]},
        {"optimum_reason": "r" * (MAX_NOTE_CHARS + 1)},
        {"optimum_reason": "budget", "warning:obstacles[3]": "hits a wall"},
        {"optimum_reason": "another", **{f"warning:obstacles[{k}]": "w" for k in range(50)}},
    ]
    notes = cell_notes(runs, 4, "m")
    assert notes.optimum_reason == "budget"
    assert len(notes.warnings) == MAX_WARNINGS
    assert notes.warnings[0].field == "maps[4].obstacles[0]"
    assert {w.field for w in notes.warnings} >= {"maps[4].obstacles[3]"}
    assert cell_notes(runs, None, "m").warnings == []
    CellNotes.model_validate(notes.model_dump())  # within its own schema


def test_the_worker_checks_a_scenario_once(monkeypatch: pytest.MonkeyPatch) -> None:
    """The trajectory check (0.2-0.5 s) runs once per scenario in a worker process, however many
    leases of its cells come."""
    from swarmpath.service import cell_notes as notes
    from swarmpath.world import trajectories
    from swarmpath.world.scenario_io import load_scenario

    calls: list[object] = []
    real = trajectories.trajectory_warnings

    def counted(s: Any) -> list[tuple[str, str]]:
        calls.append(s)
        return real(s)

    monkeypatch.setattr(trajectories, "trajectory_warnings", counted)
    monkeypatch.setattr(notes, "_WARNINGS", type(notes._WARNINGS)())
    doc = _walls("w", goal_motion={"speed": 0.2, "heading_deg": 0})
    first = notes.scenario_warnings(load_scenario(doc))
    again = notes.scenario_warnings(load_scenario(doc))  # an equal scenario, built again
    assert first == again and [f for f, _m in first] == ["goal_motion"] and len(calls) == 1
