"""scripts/bench/maps.py, the benchmark of issue 23's target: .scen row ranges, each row's own
start and goal, and a stopped run resumed from its --jsonl file without running a run twice."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ARENA = str(ROOT / "tests" / "data" / "arena.map")


@pytest.fixture(scope="module")
def maps():
    spec = importlib.util.spec_from_file_location("bench_maps",
                                                  ROOT / "scripts" / "bench" / "maps.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_row_range_with_a_step_names_every_chosen_row(maps):
    assert maps.scen_rows("a/x.map#0-159/10") == [f"a/x.map#{i}" for i in range(0, 160, 10)]
    assert maps.scen_rows("x.map#3-5") == ["x.map#3", "x.map#4", "x.map#5"]
    assert maps.scen_rows("x.map#7") == ["x.map#7"]
    assert maps.scen_rows("mfb-static") == ["mfb-static"]


def test_a_scen_row_has_its_own_start_goal_and_bucket_on_the_map_imported_once(maps):
    from swarmpath.world.movingai import movingai_cell_center

    rows = (ROOT / "tests" / "data" / "arena.map.scen").read_text().splitlines()[1:]
    for i in (0, 155):
        f = rows[i].split("\t")
        scenario, about = maps.load(f"{ARENA}#{i}")
        assert scenario.name == f"arena#{i}"
        assert scenario.start == movingai_cell_center(int(f[4]), int(f[5]), int(f[3]))
        assert scenario.goal == movingai_cell_center(int(f[6]), int(f[7]), int(f[3]))
        assert about == {"bucket": int(f[0]), "octile": float(f[8])}
    assert list(maps._BASES) == [ARENA]


def run(maps, monkeypatch, capsys, *args: str) -> str:
    monkeypatch.setattr(sys, "argv", ["maps.py", *args])
    maps.main()
    return capsys.readouterr().out


def test_resume_runs_only_what_the_jsonl_file_lacks_and_counts_the_rest(maps, tmp_path,
                                                                         monkeypatch, capsys):
    sink = tmp_path / "runs.jsonl"
    common = ["--planners", "MFB", "--knowledge", "map", "--jsonl", str(sink), "--resume"]
    run(maps, monkeypatch, capsys, *common, "--maps", f"{ARENA}#0", "--seeds", "1")
    first = [json.loads(line) for line in sink.read_text().splitlines()]
    assert [(r["map"], r["seed"], r["params"]) for r in first] == [
        ("arena.map#0", 1, {"knowledge": "map"})]
    assert first[0]["bucket"] == 0 and first[0]["optimum"] is not None
    out = run(maps, monkeypatch, capsys, *common, "--maps", f"{ARENA}#0-10/10", "--seeds", "1",
              "--by-map")
    runs = [json.loads(line) for line in sink.read_text().splitlines()]
    assert [(r["map"], r["seed"]) for r in runs] == [("arena.map#0", 1), ("arena.map#10", 1)]
    assert runs[0] == first[0]  # not run again
    assert "| MFB (map) | arena.map (2 rows) | 2/2 |" in out
    # other parameters are other runs
    run(maps, monkeypatch, capsys, "--planners", "MFB", "--jsonl", str(sink), "--resume",
        "--maps", f"{ARENA}#0", "--seeds", "1")
    assert len(sink.read_text().splitlines()) == 3
    table = run(maps, monkeypatch, capsys, "--table", str(sink))
    assert "| MFB (map) | arena.map#0 | 1/1 |" in table
    assert "| MFB | arena.map#0 | 1/1 |" in table
    grid = run(maps, monkeypatch, capsys, "--table", str(sink), "--matrix").splitlines()
    assert grid[0] == "| planner | arena.map |"
    assert grid[2].startswith("| MFB (map) | 2/2, ") and grid[3].startswith("| MFB | 1/1, ")


ROOM = str(ROOT / "tests" / "data" / "room-32-32-4-even-10.scen")
EVEN = [str(ROOT / "tests" / "data" / f"{m}-even-10.scen")
        for m in ("random-32-32-20", "room-32-32-4", "maze-32-32-4")]


def test_per_bucket_rows_of_a_mapf_scen_are_the_first_of_each_bucket(maps):
    rows = (ROOT / "tests" / "data" / "room-32-32-4-even-10.scen").read_text().splitlines()[1:]
    buckets = [int(line.split("\t")[0]) for line in rows]
    one = maps.scen_rows(f"{ROOM}#b1")
    assert [int(n.split("#")[1]) for n in one] == [buckets.index(b) for b in sorted(set(buckets))]
    two = maps.scen_rows(f"{ROOM}#b2")
    assert len(two) == 2 * len(set(buckets)) and set(one) < set(two)
    assert maps.scen_rows(f"{ROOM}#4-6") == [f"{ROOM}#4", f"{ROOM}#5", f"{ROOM}#6"]


def test_a_mapf_scen_row_runs_on_the_map_its_rows_name_beside_it(maps):
    from swarmpath.world.movingai import movingai_cell_center

    f = (ROOT / "tests" / "data" / "room-32-32-4-even-10.scen").read_text().splitlines()[8]
    f = f.split("\t")
    scenario, about = maps.load(f"{ROOM}#7")
    assert scenario.name == "room-32-32-4-even-10#7"
    assert scenario.start == movingai_cell_center(int(f[4]), int(f[5]), 32)
    assert scenario.goal == movingai_cell_center(int(f[6]), int(f[7]), 32)
    assert about == {"bucket": int(f[0]), "octile": float(f[8])}
    assert str(ROOT / "tests" / "data" / "room-32-32-4.map") in maps._BASES


def test_octile_lengths_follow_movingai_rules(maps):
    import numpy as np

    blocked = np.zeros((3, 3), dtype=bool)
    assert maps.octile_lengths(blocked, [((0, 0), (2, 1)), ((0, 0), (2, 2))]) == pytest.approx(
        [1 + np.sqrt(2), 2 * np.sqrt(2)])
    blocked[0, 1] = True  # x = 1, y = 0: the diagonal (0, 0) -> (1, 1) would cut its corner
    assert maps.octile_lengths(blocked, [((0, 0), (1, 1))]) == [2.0]
    blocked[1, 0] = True  # the start boxed in
    assert maps.octile_lengths(blocked, [((0, 0), (1, 1))]) == [np.inf]


def test_every_row_of_the_mapf_scen_files_has_the_octile_length_of_its_map(maps):
    checked = maps.check_scen([f"{p}#b10" for p in EVEN], exact=False)
    assert [(e["file"], e["rows"], e["buckets"]) for e in checked] == [
        ("random-32-32-20-even-10.scen", 100, 10), ("room-32-32-4-even-10.scen", 130, 13),
        ("maze-32-32-4-even-10.scen", 200, 20)]
    for e in checked:
        assert e["octile_agree"] == e["bucket_agree"] == e["rows"], e


def test_the_exact_optimum_of_the_disk_robot_lies_between_the_line_and_the_octile_path(maps):
    # any angle is shorter than the grid's 8 directions; a 0.105 m robot fits the octile path
    (e,) = maps.check_scen([f"{EVEN[0]}#0-1"])
    assert e["exact_ge_line"] == e["exact_le_octile"] == 2
    assert e["ratio_min"] <= e["ratio_max"] < 1
