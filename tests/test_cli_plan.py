"""`swarmpath plan`: run tables, the JSON document, plots, map files and one-line errors."""

import json

import numpy as np
import pytest
import yaml
from PIL import Image
from typer.testing import CliRunner

from swarmpath.cli import app
from swarmpath.evidence.compare_maps import map_statistics
from swarmpath.planners import list_planners
from swarmpath.planners.episode import TIMING_FIELDS
from swarmpath.planners.summary import summarize
from swarmpath.world import list_maps

runner = CliRunner()


def fast(*planners: str) -> str:
    """--params giving each planner a 0.1 s budget (params may name only --planners)."""
    return json.dumps({p: {"iterations": 1000} for p in planners})

RUN_FIELDS = {"planner", "map", "run", "seed", "success", "collisions", "length", "error",
              "smoothness", "min_clearance", "steps", "iterations", "seconds", "optimum", "gap",
              "planned_length", "robot_driven_contacts", "obstacle_driven_contacts", "path"}
SUMMARY_FIELDS = {"planner", "map", "runs", "success_rate", "length_mean", "length_std",
                  "error_mean", "seconds_mean", "robot_driven_contacts",
                  "obstacle_driven_contacts"}
PNG = b"\x89PNG\r\n\x1a\n"


def invoke(*args: str):
    # one process unless a test asks for more: the OMPL runs here have 0.1 s wall-clock budgets,
    # and extra processes next to pytest-xdist's would starve them
    jobs = [] if {"-j", "--jobs"} & set(args) else ["-j", "1"]
    return runner.invoke(app, ["plan", *jobs, *args])


def test_table_has_the_papers_columns_and_a_mean_row():
    result = invoke("--planners", "OMPL-RRTstar", "--maps", "mfb-static", "--runs", "2",
                    "--params", fast("OMPL-RRTstar"))
    assert result.exit_code == 0, result.stderr
    out = result.stdout
    assert "OMPL-RRTstar on mfb-static" in out and "exact optimum" in out
    header = next(line for line in out.splitlines() if line.split()[:1] == ["Run"])
    for column in ("Distance", "Error", "Elapsed time", "CPU time", "Success", "Collisions",
                   "Robot/obstacle-driven", "Gap", "Planned"):
        assert column in header
    assert header.index("Elapsed time") < header.index("CPU time") < header.index("Success")
    lines = [line.split() for line in out.splitlines()]
    at = next(i for i, r in enumerate(lines) if r[:1] == ["Mean"])  # the caption comes after
    assert [r[0] for r in lines[: at + 1] if r and r[0] in {"1", "2", "Mean"}] == [
        "1", "2", "Mean"]
    mean = lines[at]
    assert mean[5] == "2/2"
    # the field's path metrics, one row per planner x map
    quality = next(i for i, r in enumerate(lines) if r[:2] == ["Path", "quality"])
    head = out.splitlines()[quality + 2]
    for column in ("Clearance min", "Clearance mean", "Curvature max", "Cusps", "In danger",
                   "Travel time", "Velocity smoothness", "Angular smoothness", "Jerk"):
        assert column in head
    row = next(r for r in lines[quality:] if r[:2] == ["mfb-static", "OMPL-RRTstar"])
    assert len(row) == 2 + 12 and all(v != "-" for v in row[2:12])
    assert row[12:] == ["-", "-"]  # nav2 costs: maps imported from a grid only


def test_json_document_has_exactly_runs_summary_statistics_and_maps():
    result = invoke("-p", "OMPL-RRTstar,OMPL-BITstar", "-m", "mfb-static", "--runs", "2",
                    "--seed", "3", "--params", fast("OMPL-RRTstar", "OMPL-BITstar"), "--json")
    assert result.exit_code == 0, result.stderr
    doc = json.loads(result.stdout)
    assert set(doc) == {"runs", "summary", "statistics", "maps", "buckets", "extensions"}
    assert doc["buckets"] == []  # no --scen: no MovingAI buckets
    assert doc["maps"] == [{"map": "mfb-static", "optimum": doc["runs"][0]["optimum"],
                            "optimum_reason": None, "octile": None, "bucket": None,
                            "frame": "scenario", "origin": [0.0, 0.0], "start": [0.0, 0.0],
                            "goal": [10.0, 10.0]}]
    assert len(doc["runs"]) == 4
    for i, run in enumerate(doc["runs"]):
        assert RUN_FIELDS <= set(run)
        assert run["planner"] == ["OMPL-RRTstar", "OMPL-BITstar"][i // 2]
        assert (run["map"], run["run"], run["seed"]) == ("mfb-static", i % 2, 3)
        assert run["success"] is True and run["collisions"] == 0
        assert run["robot_driven_contacts"] == run["obstacle_driven_contacts"] == 0
        assert run["length"] == pytest.approx(run["planned_length"], abs=1e-3)  # omni: straight
        assert all(len(row) == 3 for row in run["path"])
        assert run["path"][0] == [0.0, 0.0, 0.0]
        assert run["optimum"] == pytest.approx(doc["runs"][0]["optimum"])
    assert [(s["planner"], s["map"]) for s in doc["summary"]] == [
        ("OMPL-RRTstar", "mfb-static"), ("OMPL-BITstar", "mfb-static")]
    for s in doc["summary"]:
        assert SUMMARY_FIELDS <= set(s)
        assert s["runs"] == 2 and s["success_rate"] == 1.0
    assert doc["summary"] == summarize(doc["runs"])  # the pure function the service reuses
    assert doc["statistics"] == map_statistics(doc["runs"]).to_json()
    assert doc["statistics"]["reference"] == "OMPL-BITstar"  # the last planner listed


def test_plot_writes_one_png_per_planner_and_map_and_box_plots_per_map(tmp_path):
    out = tmp_path / "plots"
    result = invoke("-p", "OMPL-BITstar", "-m", "mfb-static,mfb-dynamic", "--runs", "2",
                    "--params", fast("OMPL-BITstar"), "--plot", str(out))
    assert result.exit_code == 0, result.stderr
    files = sorted(p.name for p in out.iterdir())
    assert files == ["OMPL-BITstar_mfb-dynamic.png", "OMPL-BITstar_mfb-static.png",
                     "box_mfb-dynamic.png", "box_mfb-static.png"]
    for name in files:
        data = (out / name).read_bytes()
        assert data.startswith(PNG) and len(data) > 1000


def test_list_maps_and_planners():
    result = invoke("--list-maps")
    assert result.exit_code == 0
    listed = [line.split()[0] for line in result.stdout.splitlines() if line.strip()]
    assert listed == list_maps()
    result = invoke("--list-planners")
    assert result.exit_code == 0
    listed = [line.split()[0] for line in result.stdout.splitlines() if line.strip()]
    assert listed == list_planners()


def test_scenario_files_nav2_and_movingai_maps_are_accepted(tmp_path):
    doc = {
        "name": "demo", "size": [10, 10], "start": [0.5, 0.5], "goal": [9, 9],
        "robot": {"model": "omni", "radius": 0.3},
        "obstacles": [{"shape": "circle", "center": [5, 5], "radius": 1.5},
                      {"shape": "polygon", "points": [[1, 5], [2, 5], [2, 6.5]]}],
    }
    scenario = tmp_path / "demo.json"
    scenario.write_text(json.dumps(doc))
    scenario_yaml = tmp_path / "demo.yaml"
    scenario_yaml.write_text(yaml.safe_dump({**doc, "name": "demo-yaml"}))
    image = np.full((40, 50), 254, dtype=np.uint8)  # free
    image[15:25, 20:30] = 0  # an occupied block in the middle
    Image.fromarray(image).save(tmp_path / "room.pgm")
    nav2 = tmp_path / "room.yaml"
    nav2.write_text("image: room.pgm\nresolution: 0.1\norigin: [-1.0, -2.0, 0.0]\n"
                    "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.25\n")
    grid = tmp_path / "room.map"
    rows = ["." * 12] * 4 + ["....@@@@@..."] + ["." * 12] * 5
    grid.write_text("type octile\nheight 10\nwidth 12\nmap\n" + "\n".join(rows) + "\n")
    maps = ",".join(str(p) for p in (scenario, scenario_yaml, nav2, grid))
    result = invoke("-p", "OMPL-RRTstar", "-m", maps, "--runs", "1",
                    "--params", fast("OMPL-RRTstar"), "--json")
    assert result.exit_code == 0, result.stderr
    runs = json.loads(result.stdout)["runs"]
    assert len(runs) == 4
    assert [r["map"] for r in runs[:2]] == ["demo", "demo-yaml"]
    for run in runs:
        assert run["collisions"] == 0
        assert run["steps"] >= 1 and "gave up" not in run["reason"]  # OMPL found a path
    # The scenario files carry an omni robot; the imported maps get the default diff-drive robot
    # (see test_planner_ompl.py::test_diff_drive_robot_reaches_the_goal for its known problem).
    for run in runs[:2]:
        assert run["success"], run["reason"]
        assert run["length"] + run["error"] >= run["optimum"] - 1e-9


def test_deterministic_mode_gives_the_same_paths():
    params = '{"OMPL-RRTstar": {"iterations": 200}}'
    docs = [json.loads(invoke("-p", "OMPL-RRTstar", "-m", "mfb-static", "--runs", "2",
                              "--params", params, "--json").stdout) for _ in range(2)]
    assert [r["path"] for r in docs[0]["runs"]] == [r["path"] for r in docs[1]["runs"]]


def test_processes_do_not_change_the_runs():
    args = ("-p", "MFB,RFO-GWO-EA", "-m", "mfb-dynamic", "--runs", "2", "--seed", "5", "--json")
    one, two = (json.loads(invoke(*args, "-j", j).stdout)["runs"] for j in ("1", "2"))
    assert [(r["planner"], r["run"]) for r in two] == [
        (p, r) for p in ("MFB", "RFO-GWO-EA") for r in (0, 1)]
    for a, b in zip(one, two, strict=True):
        for key in TIMING_FIELDS:  # wall and CPU time: the only fields allowed to differ
            a.pop(key), b.pop(key)
        assert a == b


def test_the_plotted_world_is_the_one_the_episode_simulated():
    from swarmpath.cli.plan import simulated_world
    from swarmpath.planners import Episode
    from swarmpath.world import get_map

    scenario = get_map("icoot-map4")  # ten obstacles and the goal on a random walk
    episode = Episode(scenario, "MFB", 7, 3, step_limit=5)
    rebuilt = simulated_world(scenario, 7, 3)
    for t in (0.0, 0.35, 4.0, 31.7):
        assert np.array_equal(rebuilt.obstacle_positions_at(t),
                              episode.sim.world.obstacle_positions_at(t))
        assert np.array_equal(rebuilt.goal_at(t), episode.sim.world.goal_at(t))
    other = simulated_world(scenario, 7, 4)
    assert not np.array_equal(other.obstacle_positions_at(4.0), rebuilt.obstacle_positions_at(4.0))


@pytest.mark.parametrize(
    ("args", "option"),
    [
        (["-p", "NoSuchPlanner"], "--planners"),
        (["-m", "no-such-map"], "--maps"),
        (["-m", "missing.json"], "--maps"),
        (["--params", "{not json"], "--params"),
        (["--params", '{"OMPL-RRTstar": {"speed": 2}}'], "--params"),
        (["--params", '{"MFB": {"agents": 3}}'], "--params"),
        (["--runs", "0"], "--runs"),
        (["--seed", "-1"], "--seed"),
        (["--jobs", "-1"], "--jobs"),
        (["-j", "257"], "--jobs"),
    ],
)
def test_bad_input_is_one_line_naming_the_option(args, option):
    base = {"-p": "OMPL-RRTstar", "-m": "mfb-static"}
    full = list(args)
    for flag, value in base.items():
        if flag not in full:
            full += [flag, value]
    result = invoke(*full)
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and option in lines[0] and "error" in lines[0]


def test_bad_scenario_file_names_the_field(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"name": "x", "size": [10, 10], "start": [0, 0], "goal": [9, 9],
                               "obstacles": [{"shape": "circle", "center": [5, 5],
                                              "radius": -1}]}))
    result = invoke("-p", "OMPL-RRTstar", "-m", str(bad))
    assert result.exit_code == 2
    line = result.stderr.strip()
    assert "--maps" in line and "radius" in line and "\n" not in line


def test_plan_of_one_planner_leaves_scipy_stats_unloaded():
    """Start-up: the statistical tests (scipy.stats, the largest import) load only when there
    is a second planner to compare with; one planner's table needs none."""
    from child_python import last_line

    code = ("import sys\n"
            "from swarmpath.cli import main\n"
            "sys.argv = ['swarmpath', 'plan', '-p', 'MFB', '--runs', '1']\n"
            "try:\n    main()\nexcept SystemExit as exc:\n    assert not exc.code, exc.code\n"
            "print('scipy.stats' in sys.modules, 'swarmpath.evidence.compare' in sys.modules)\n")
    assert last_line(code, timeout=300) == "False False"


def test_the_command_line_leaves_scipy_optimize_and_special_unloaded():
    """Every ``swarmpath`` process (a worker, its slots, each command) imports the cli package;
    scipy.optimize and scipy.special (about 0.8 s of CPU) load only where they are used: a
    race's group-sequential boundaries (evidence.group_sequential), not at the import of
    bench's racing options."""
    from child_python import last_line

    code = ("import sys, swarmpath.cli\n"
            "print('scipy.optimize' in sys.modules, 'scipy.special' in sys.modules)\n")
    assert last_line(code) == "False False"


def test_plan_workers_import_no_command_line():
    """``plan -j`` children unpickle swarmpath.parallel's child loop and plan_runs.episode_task:
    neither may pull in the cli package (typer and every command, ~0.3 s of CPU per child)."""
    from child_python import last_line

    code = ("import sys, swarmpath.parallel, swarmpath.plan_runs\n"
            "print('typer' in sys.modules, 'swarmpath.cli' in sys.modules)\n")
    assert last_line(code) == "False False"
