"""Stated (constant-velocity) trajectories that run into static obstacles are reported by field."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from swarmpath.cli import app
from swarmpath.world import get_map, list_maps
from swarmpath.world.scenario_io import load_scenario
from swarmpath.world.trajectories import trajectory_warnings

WALL = {"shape": "polygon", "points": [[6, 0], [6.5, 0], [6.5, 10], [6, 10]]}


def _scenario(**extra: object) -> dict:
    doc = {"name": "walls", "size": [10, 10], "start": [1, 1], "goal": [3, 5],
           "robot": {"model": "omni", "radius": 0.3}, "obstacles": [WALL]}
    doc.update(extra)
    return doc


def test_goal_driving_into_a_wall_is_named() -> None:
    s = load_scenario(_scenario(goal_motion={"speed": 0.2, "heading_deg": 0}))
    [(field, message)] = trajectory_warnings(s)
    assert field == "goal_motion" and "static obstacle" in message
    assert "t = 13.5 s" in message  # x = 3 + 0.2 t reaches 6 - 0.3 at t = 13.5 s


def test_obstacle_driving_through_a_wall_is_named() -> None:
    mover = {"shape": "circle", "center": [2, 8], "radius": 0.4, "speed": 0.5,
             "heading_deg": 0}
    s = load_scenario(_scenario(obstacles=[WALL, mover]))
    [(field, message)] = trajectory_warnings(s)
    assert field == "obstacles[1]" and "t = 7.2 s" in message  # 2 + 0.5 t = 5.6


def test_paths_clear_of_the_wall_give_nothing() -> None:
    mover = {"shape": "polygon", "points": [[1, 8], [2, 8], [2, 9]], "speed": 0.3,
             "heading_deg": 90}  # bounces between y = 0 and 10 left of the wall
    s = load_scenario(_scenario(obstacles=[WALL, mover],
                                goal_motion={"speed": 0.1, "heading_deg": 90}))
    assert trajectory_warnings(s) == []


@pytest.mark.parametrize("name", list_maps())
def test_presets_have_no_such_paths(name: str) -> None:
    assert trajectory_warnings(get_map(name)) == []


def test_plan_prints_the_warning(tmp_path) -> None:
    p = tmp_path / "walls.json"
    p.write_text(json.dumps(_scenario(goal_motion={"speed": 0.2, "heading_deg": 0})))
    result = CliRunner().invoke(app, ["plan", "-j", "1", "-p", "OMPL-RRTstar", "--runs", "1",
                                      "--params", '{"OMPL-RRTstar": {"iterations": 1000}}', "-m",
                                      str(p), "--json"])
    assert result.exit_code == 0, result.stderr
    assert "warning: walls: goal_motion: the goal's stated path enters" in result.stderr


def test_submit_prints_the_warning_naming_the_map_and_field(tmp_path, monkeypatch) -> None:
    """`swarmpath submit` checks a map job's inline scenarios on the submitter's machine and
    warns by field path; the job is submitted all the same (the simulation is well defined)."""
    from fastapi.testclient import TestClient

    import swarmpath.cli.service as service_cli
    from swarmpath.service.client import ServiceClient
    from swarmpath.service.http.app import create_app
    from swarmpath.service.settings import CoordinatorSettings

    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    mover = {"shape": "circle", "center": [2, 8], "radius": 0.4, "speed": 0.5, "heading_deg": 0}
    spec = {"kind": "map", "planners": ["MFB"], "runs": 1,
            "maps": ["mfb-static", _scenario(obstacles=[WALL, mover]),
                     _scenario(name="calm")]}
    assert service_cli.trajectory_notes({**spec, "kind": "benchmark"}) == []
    p = tmp_path / "spec.json"
    p.write_text(json.dumps(spec))
    app_ = create_app(CoordinatorSettings(data_dir=tmp_path / "data"), use_zenoh=False)
    with TestClient(app_) as c:
        monkeypatch.setattr(service_cli, "_client",
                            lambda url: ServiceClient("http://testserver", transport=c._transport))
        result = CliRunner().invoke(app, ["submit", str(p)])
    assert result.exit_code == 0, result.stderr
    warnings = [ln for ln in result.stderr.splitlines() if "warning" in ln]
    assert warnings == ["swarmpath submit: warning: maps[1].obstacles[1] (walls): its stated "
                        "path runs into a static obstacle at t = 7.2 s"]
    assert len(result.stdout.strip()) == 12  # the job id: submitted all the same
