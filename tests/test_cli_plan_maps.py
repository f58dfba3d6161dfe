"""`swarmpath plan` on real maps: --start/--goal/--resolution, MovingAI --scen pairs with their
octile optimum, import limits and the optimum budget, each bad value naming its option."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from swarmpath.cli import app

runner = CliRunner()
DATA = Path(__file__).parent / "data"
ARENA = str(DATA / "arena.map")
SCEN = str(DATA / "arena.map.scen")
FAST = json.dumps({"OMPL-RRTstar": {"iterations": 1000}})


def invoke(*args: str):
    return runner.invoke(app, ["plan", "-j", "1", "-p", "OMPL-RRTstar", "--runs", "1",
                               "--params", FAST, *args])


def _scen_rows() -> list[list[str]]:
    return [line.split("\t") for line in Path(SCEN).read_text().splitlines()[1:]]


def test_scen_pairs_become_maps_with_the_octile_optimum_beside_the_exact_one() -> None:
    result = invoke("-m", ARENA, "--scen", SCEN, "--scen-ids", "3,40", "--resolution", "0.5",
                    "--json")
    assert result.exit_code == 0, result.stderr
    doc = json.loads(result.stdout)
    rows = _scen_rows()
    assert [m["map"] for m in doc["maps"]] == ["arena#3", "arena#40"]
    for entry, i in zip(doc["maps"], (3, 40), strict=True):
        assert entry["octile"] == pytest.approx(float(rows[i][8]) * 0.5)
        assert entry["optimum"] is not None and entry["optimum_reason"] is None
        assert entry["optimum"] <= entry["octile"] + 1e-4  # 0.5 m cells, robot 0.105 m
    run = doc["runs"][0]
    sx, sy = int(rows[3][4]), int(rows[3][5])
    assert run["path"][0][:2] == [(sx + 0.5) * 0.5, (49 - sy - 0.5) * 0.5]
    table = invoke("-m", ARENA, "--scen", SCEN, "--scen-ids", "3")
    assert table.exit_code == 0, table.stderr
    assert "octile optimum" in table.stdout and "exact optimum" in table.stdout


def test_start_and_goal_override_an_imported_map() -> None:
    result = invoke("-m", ARENA, "--start", "1.5,2.5", "--goal", "46.5,47.5", "--json")
    assert result.exit_code == 0, result.stderr
    run = json.loads(result.stdout)["runs"][0]
    assert run["path"][0][:2] == [1.5, 2.5]


@pytest.mark.parametrize(
    ("args", "option"),
    [
        (("-m", "mfb-static", "--start", "1,x"), "--start"),
        (("-m", "mfb-static", "--goal", "5"), "--goal"),
        (("-m", "mfb-static", "--start", "2,2.3"), "--start"),  # inside a circle
        (("-m", ARENA, "--goal", "0.5,0.5"), "--goal"),  # a blocked cell
        (("-m", ARENA, "--resolution", "0"), "--resolution"),
        (("-m", ARENA, "--resolution", "1e300"), "--resolution"),  # a 4.9e301 m world
        (("-m", "mfb-static", "--resolution", "2"), "--resolution"),
        (("-m", ARENA, "--scen", SCEN, "--scen-ids", "999"), "--scen-ids"),
        (("-m", ARENA, "--scen", SCEN, "--scen-ids", "0,,1"), "--scen-ids"),
        # arena's .scen (49 x 49 cells) with maze512-32-9: its cells fit, but it is another map
        (("-m", str(DATA / "maze512-32-9.map"), "--scen", SCEN, "--scen-ids", "0"), "--scen"),
        (("-m", ARENA, "--scen-ids", "1"), "--scen-ids"),
        (("-m", "mfb-static", "--scen", SCEN), "--scen"),
        (("-m", ARENA, "--scen", ARENA), "--scen"),
        (("-m", ARENA, "--max-obstacles", "3"), "--max-obstacles"),
        (("-m", ARENA, "--max-cells", "100"), "--max-cells"),
        (("-m", "mfb-static", "--optimum-budget", "0"), "--optimum-budget"),
    ],
)
def test_bad_values_exit_2_naming_the_option(args: tuple[str, ...], option: str) -> None:
    result = invoke(*args)
    assert result.exit_code == 2, result.stdout
    assert option in result.stderr and "error" in result.stderr


def test_a_start_on_an_obstacle_says_where_it_is_never_clearance_minus_0() -> None:
    """``--start 0,0`` on tb3_sandbox said "clearance -0 <= 0.105" (issue 25)."""
    result = invoke("-m", str(DATA / "tb3_sandbox.yaml"), "--start", "0,0", "--frame", "scenario")
    assert result.exit_code == 2
    err = " ".join(result.stderr.split())
    assert "--start" in err and "(0, 0) lies on an obstacle's edge: the robot collides" in err
    assert "-0" not in err
    inside = invoke("-m", "mfb-static", "--start", "2,2.3")
    assert "lies inside an obstacle" in " ".join(inside.stderr.split())


def test_limit_errors_say_how_to_raise_them() -> None:
    result = invoke("-m", ARENA, "--max-obstacles", "3")
    assert "max_obstacles=3" in result.stderr and "--max-obstacles" in result.stderr


def test_the_reason_is_printed_when_the_optimum_gives_up() -> None:
    result = invoke("-m", str(DATA / "tb3_sandbox.yaml"), "--optimum-budget", "1e-9", "--json")
    assert result.exit_code == 0, result.stderr
    assert "no exact optimum on tb3_sandbox: time budget of 1e-09 s exhausted" in result.stderr
    entry = json.loads(result.stdout)["maps"][0]
    assert entry["optimum"] is None and "time budget" in entry["optimum_reason"]


def test_slow_imports_and_optima_report_progress_on_stderr(monkeypatch: pytest.MonkeyPatch) -> None:
    """Past SLOW seconds an import and an optimum say how far they are (here SLOW < 0, so every
    step of tb3_sandbox reports); the budget is one no other test uses, so the optimum is computed
    here, not taken from the process's cache."""
    from swarmpath.cli import plan_maps

    monkeypatch.setattr(plan_maps, "SLOW", -1.0)
    result = invoke("-m", str(DATA / "tb3_sandbox.yaml"), "--optimum-budget", "977", "--json")
    assert result.exit_code == 0, result.stderr
    err = result.stderr
    assert "% of the grid turned into polygons" in err and "imported " in err
    assert "exact optimum of tb3_sandbox: 100% of the disk pairs" in err
    value = json.loads(result.stdout)["maps"][0]["optimum"]
    assert f"exact optimum of tb3_sandbox: {value:.4f} m in " in err


def test_bucket_rows_count_success_and_gap_per_planner_and_bucket() -> None:
    from swarmpath.evidence.buckets import bucket_rows

    runs = [
        {"planner": "A", "map": "m#1", "success": True, "gap": 0.02},
        {"planner": "A", "map": "m#1", "success": False, "gap": None},
        {"planner": "A", "map": "m#2", "success": True, "gap": 0.04},
        {"planner": "A", "map": "m#9", "success": True, "gap": 0.10},
        {"planner": "B", "map": "m#2", "success": False, "gap": None},
        {"planner": "B", "map": "other", "success": True, "gap": 0.0},  # no bucket: left out
    ]
    rows = bucket_rows(runs, {"m#1": 0, "m#2": 0, "m#9": 3})
    assert [(r["planner"], r["bucket"], r["pairs"], r["runs"], r["successes"]) for r in rows] == [
        ("A", 0, 2, 3, 2), ("A", 3, 1, 1, 1), ("B", 0, 1, 1, 0)]
    assert rows[0]["success_rate"] == pytest.approx(2 / 3)
    assert rows[0]["gap_median"] == pytest.approx(0.03)
    assert rows[0]["gap_mean"] == pytest.approx(0.03)
    assert rows[2]["gap_median"] is None and rows[2]["success_rate"] == 0.0


def test_scen_studies_report_success_and_gap_per_bucket(tmp_path) -> None:
    # rows 0, 1 (bucket 0) and 80, 81 (bucket 8) of arena.map.scen
    params = json.dumps({"OMPL-BITstar": {"iterations": 3000}})
    args = ("-p", "OMPL-BITstar", "-m", ARENA, "--scen", SCEN, "--scen-ids", "0,1,80,81",
            "--params", params)
    doc = json.loads(invoke(*args, "--json").stdout)
    rows = _scen_rows()
    assert [m["bucket"] for m in doc["maps"]] == [int(rows[i][0]) for i in (0, 1, 80, 81)]
    assert [(b["bucket"], b["pairs"], b["runs"]) for b in doc["buckets"]] == [(0, 2, 2),
                                                                              (8, 2, 2)]
    for b in doc["buckets"]:
        mine = [r for r in doc["runs"] if doc["maps"][[m["map"] for m in doc["maps"]].index(
            r["map"])]["bucket"] == b["bucket"]]
        assert b["successes"] == sum(r["success"] for r in mine)
    table = invoke(*args, "--plot", str(tmp_path))
    assert table.exit_code == 0, table.stderr
    assert "Per MovingAI bucket" in table.stdout
    lines = [ln.split() for ln in table.stdout.splitlines()]
    assert [r[:2] for r in lines if r[1:2] == ["OMPL-BITstar"] and r[0] in ("0", "8")] == [
        ["0", "OMPL-BITstar"], ["8", "OMPL-BITstar"]]
    assert (tmp_path / "difficulty.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_start_and_goal_of_a_nav2_map_are_in_its_map_frame() -> None:
    # tb3_sandbox's YAML origin is (-10, -10): map (-1.5, -1.5) is the scenario's (8.5, 8.5)
    tb3 = str(DATA / "tb3_sandbox.yaml")
    params = json.dumps({"OMPL-BITstar": {"iterations": 2000}})
    base = ("-p", "OMPL-BITstar", "-m", tb3, "--runs", "1", "--params", params, "--json")
    doc = json.loads(invoke(*base, "--start", "-1.5,-1.5", "--goal", "1.0,2.0").stdout)
    same = json.loads(invoke(*base, "--start", "8.5,8.5", "--goal", "11.0,12.0", "--frame",
                             "scenario").stdout)
    assert doc["runs"][0]["path"] == same["runs"][0]["path"]
    assert doc["runs"][0]["path"][0][:2] == [8.5, 8.5]  # runs keep the scenario frame ...
    assert doc["runs"][0]["frame_origin"] == [-10.0, -10.0]  # ... and say where the map's is
    (entry,) = doc["maps"]
    assert entry["frame"] == "map" and entry["origin"] == [-10.0, -10.0]
    assert entry["start"] == [-1.5, -1.5] and entry["goal"] == [1.0, 2.0]
    inside = invoke(*base, "--start", "-8,-8.5")  # in the unknown space around the building
    assert inside.exit_code == 2 and "--start" in inside.stderr
    assert "minus the YAML origin" in " ".join(inside.stderr.split())
    bad = invoke(*base, "--start", "1,1", "--frame", "world")
    assert bad.exit_code == 2 and "--frame" in bad.stderr
