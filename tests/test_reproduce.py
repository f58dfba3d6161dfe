"""`swarmpath reproduce`: verdicts per cell, the measured numbers (those of bench / plan / the
optimizer API with the same seed), the JSON document and the one-line errors."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from swarmpath.cli import app
from swarmpath.cli import reproduce as cli
from swarmpath.evidence import reference, reproduction
from swarmpath.evidence.reference import Reason
from swarmpath.evidence.reproduction import BETTER, MATCHES, NOT_COMPARABLE, WORSE
from swarmpath.optimizers import minimize
from swarmpath.world import get_map

runner = CliRunner()
T2 = reference.load("icoot-table2")


def invoke(*args: str):
    return runner.invoke(app, ["reproduce", *args])


def test_list_names_exactly_the_reproducible_tables():
    res = invoke("--list")
    assert res.exit_code == 0
    assert res.stdout.split() == [
        "icoot-table2", "icoot-table3", "icoot-table4", "ihpo-table2",
        "icoot-maps", "ihpo-maps", "rfogwo-maps", "mfb-maps",
    ]


@pytest.mark.parametrize(("args", "field"), [
    (["icoot-table9"], "TABLE"),
    ([], "TABLE"),
    (["icoot-table2", "--runs", "0"], "--runs"),
    (["icoot-table2", "--runs", "1001"], "--runs"),
    (["mfb-maps", "--runs", "11"], "--runs"),
    (["icoot-table2", "--format", "html"], "--format"),
    (["icoot-table2", "--seed", "-1"], "--seed"),
    (["icoot-table2", "--jobs", "-1"], "--jobs"),
    (["icoot-table2", "--from", "x.json"], "--from"),
    (["icoot-table2", "--backend", "cuda"], "--backend"),
    (["mfb-maps", "--backend", "numba"], "--backend"),
])
def test_bad_input_is_one_line_naming_the_field(args, field):
    res = invoke(*args)
    assert res.exit_code == 2
    assert field in res.stderr and "Traceback" not in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1


def test_tables_by_name_list_or_all():
    assert cli.resolve_tables("all") == list(reference.TABLES)
    assert cli.resolve_tables("mfb-maps, icoot-table2,mfb-maps") == ["mfb-maps", "icoot-table2"]


def test_study_setting_is_the_papers_with_runs_lowered():
    s = cli.study_setting(T2, None, 1)
    assert (s["runs"], s["agents"], s["iterations"], s["dims"]) == (1000, 30, 500, [30])
    assert s["algorithms"] == list(T2.algorithms) and s["functions"] == list(T2.functions)
    assert cli.study_setting(T2, 30, 1)["runs"] == 30
    maps = reference.load("icoot-maps")
    assert cli.study_setting(maps, None, 2) == {
        "kind": "map", "planners": ["ICOOT"], "maps": list(maps.maps), "runs": 10, "seed": 2}


def test_measured_cell_is_exactly_minimize_with_the_same_seed():
    setting = {**cli.study_setting(T2, 3, 7), "algorithms": ["ICOOT"], "functions": ["F6"]}
    (cell,) = cli.run_benchmark_local(setting, jobs=1)
    direct = minimize("ICOOT", "F6", dim=30, agents=30, iterations=500, runs=3, seed=7)
    assert cell.best_fitness == [float(v) for v in direct.best_fitness]
    (row,) = [r for r in reproduction.benchmark_rows(T2, {("F6", "ICOOT"): cell.best_fitness}, {})]
    assert row.measured["avg"] == pytest.approx(float(np.mean(direct.best_fitness)), rel=1e-12)
    assert row.runs == cell.best_fitness


def _row(function: str, algorithm: str, values, reasons=None, table=T2):
    (row,) = reproduction.benchmark_rows(table, {(function, algorithm): values}, reasons or {})
    return row


def test_verdicts_by_decades_of_the_mean():
    # published SSA F3 avg 1292.1, min 195.21, max 2873.7
    assert _row("F3", "SSA", [1000.0, 3000.0]).verdict == MATCHES
    worse = _row("F3", "SSA", [5e4, 6e4])
    assert worse.verdict == WORSE and worse.unexplained and worse.log10_ratio > 1
    better = _row("F3", "SSA", [1.0, 2.0])
    assert better.verdict == BETTER and better.unexplained and better.log10_ratio < -1


def test_inside_the_published_range_explains_a_mean_off_by_decades():
    # COOT F1: avg 8.7095e-11 but min 9.8206e-58, max 8.6061e-08
    row = _row("F1", "COOT", [1e-40, 1e-35])
    assert row.verdict == BETTER and not row.unexplained
    assert "inside the published [min, max]" in row.reason
    # below the published minimum: not explained by the range
    assert _row("F1", "COOT", [1e-70, 1e-70]).unexplained


def test_both_at_the_floor_match_and_f8_compares_gaps():
    # ICOOT F9 published min 0, avg 1.06e-14: our exact zeros are far below, but inside range
    assert _row("F9", "ICOOT", [0.0, 0.0]).verdict == BETTER
    ihpo = reference.load("ihpo-table2")
    at_floor = _row("F9", "HPO", [0.0, 0.0, 0.0], table=ihpo)  # published 0 everywhere
    assert at_floor.verdict == MATCHES and at_floor.log10_ratio == 0
    # F10 published 8.8818e-16 (MATLAB's floor), ours 4.44e-16: both at the floor
    assert _row("F10", "HPO", [4.440892098500626e-16] * 3, table=ihpo).verdict == MATCHES
    # F8: ICOOT avg -6564.9; f_min(30) = -12569.5: a gap of 6004.6
    fmin = -418.9828872724338 * 30
    assert _row("F8", "ICOOT", [fmin + 600.0] * 2).log10_ratio == pytest.approx(-1.0, abs=0.01)


def test_illegible_or_self_contradicting_published_cells_are_not_comparable():
    assert _row("F8", "PSO", [-5000.0]).verdict == NOT_COMPARABLE  # illegible in the print
    row = _row("F9", "PSO", [40.0])  # min = max = 76.413, avg 38.604
    assert row.verdict == NOT_COMPARABLE and "contradicts" in row.reason
    assert not row.unexplained


def test_a_reason_explains_the_cell_and_carries_its_evidence():
    key = reference.cell_key("icoot-table2", "SSA", "F3", 30)
    row = _row("F3", "SSA", [5e4], {key: Reason("because", "swarmpath bench ...")})
    assert row.verdict == WORSE and not row.unexplained
    assert (row.reason, row.evidence) == ("because", "swarmpath bench ...")


def _outcome(length: float, success: bool = True) -> dict:
    return {"success": success, "length": length, "error": 0.01, "seconds": 0.5,
            "collisions": 0}


def test_map_verdicts():
    mfb = reference.load("mfb-maps")
    scen = {m: get_map(m) for m in mfb.maps}
    published = mfb.cells[("MFB", "mfb-static")].mean["distance_m"]  # mean of the 10 runs
    rows = reproduction.map_rows(mfb, {
        ("MFB", "mfb-static"): [_outcome(published * 1.05), _outcome(published * 1.05)],
        ("HPSO-MFB", "mfb-static"): [_outcome(30.0), _outcome(1.0, success=False)],
    }, {}, scen)
    assert [r.verdict for r in rows] == [MATCHES, WORSE]
    assert rows[1].extra["success"] == "1/2" and rows[1].runs == [30.0]
    icoot = reference.load("icoot-maps")
    rows = reproduction.map_rows(icoot, {("ICOOT", "icoot-map1"): [_outcome(14.6)],
                                         ("ICOOT", "icoot-map3"): [_outcome(1.0, False)]},
                                 {}, {m: get_map(m) for m in icoot.maps})
    assert [r.verdict for r in rows] == [NOT_COMPARABLE, NOT_COMPARABLE]
    assert "shorter than the 14.1421 m straight line" in rows[0].reason
    assert rows[1].reason == "no successful run"
    rfo = reference.load("rfogwo-maps")
    (row,) = reproduction.map_rows(rfo, {("RFO", "rfogwo-map1"): [_outcome(300.0)]}, {},
                                   {m: get_map(m) for m in rfo.maps})
    assert row.verdict == NOT_COMPARABLE and "no measured counterpart" in row.reason
    assert row.measured["avg"] == 300.0  # our executed length, shown beside the units


def test_document_counts_and_is_strict_json():
    rows = [_row("F3", "SSA", [5e4]), _row("F3", "SSA", [math.inf]), _row("F8", "PSO", [1.0])]
    doc = reproduction.document(T2, {"runs": 1, "seed": 1}, rows)
    text = json.dumps(doc, allow_nan=False)
    assert json.loads(text)["unexplained"] == 2
    assert doc["counts"]["SSA"] == {MATCHES: 0, BETTER: 0, WORSE: 2, NOT_COMPARABLE: 0}
    assert doc["counts"]["PSO"][NOT_COMPARABLE] == 1
    cell = doc["cells"][0]
    assert {"function", "dim", "algorithm", "published", "measured", "runs", "log10_ratio",
            "verdict", "reason"} <= set(cell)
    assert reproduction.summary_line(rows) == "3 cells, 2 unexplained"


def test_map_table_end_to_end_matches_plan_runs(tmp_path):
    """One run per cell of mfb-maps through the command; the lengths are those of the plan
    command's episode with the same seed and run."""
    from swarmpath.cli import plan

    res = invoke("mfb-maps", "--runs", "1", "--seed", "3", "--jobs", "1", "--json")
    assert res.exit_code == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["table"] == "mfb-maps" and doc["setting"]["runs"] == 1
    spec = plan.make_spec("MFB,HPSO-MFB", "mfb-static", runs=1, seed=3)
    for cell in doc["cells"]:
        direct = plan.run_episode(spec, cell["planner"], spec.maps[0], 0)
        assert cell["runs"] == ([direct["length"]] if direct["success"] else [])
        assert cell["verdict"] in reproduction.VERDICTS
    assert doc["unexplained"] == sum(c["unexplained"] for c in doc["cells"])
    # --from judges the same runs again without running them; --out writes markdown and a plot
    saved = tmp_path / "mfb.json"
    saved.write_text(res.stdout)
    again = invoke("--from", str(saved), "--json", "--out", str(tmp_path / "out"))
    assert again.exit_code == 0, again.stderr
    redo = json.loads(again.stdout)
    for a, b in zip(doc["cells"], redo["cells"], strict=True):
        assert (a["runs"], a["verdict"], a["log10_ratio"]) == (b["runs"], b["verdict"],
                                                               b["log10_ratio"])
    md = (tmp_path / "out" / "mfb-maps.md").read_text()
    assert "swarmpath reproduce mfb-maps --runs 1 --seed 3 --format markdown" in md
    assert md.count("| mfb-static |") == 2 and reproduction.summary_line([]) not in md
    assert (tmp_path / "out" / "mfb-maps.png").stat().st_size > 0
    bad = tmp_path / "bad.json"
    bad.write_text('{"table": "nope"}')
    res = invoke("--from", str(bad))
    assert res.exit_code == 2 and "--from" in res.stderr


def test_service_runs_become_the_same_cells_as_bench_in_run_order():
    """--url reads the job's runs back (GET /jobs/{id}/runs items, any order)."""
    items = [
        {"algorithm": "GWO", "function": "F1", "dim": 30, "run": 1, "best_fitness": 2.0,
         "evaluations": 10, "seconds": 0.5},
        {"algorithm": "GWO", "function": "F1", "dim": 30, "run": 0, "best_fitness": "inf",
         "evaluations": 10, "seconds": 0.25},
        {"algorithm": "PSO", "function": "F1", "dim": 30, "run": 0, "best_fitness": 3.0},
    ]
    cells = {(c.algorithm, c.function): c for c in cli.cells_from_runs(items)}
    gwo = cells[("GWO", "F1")]
    assert gwo.run_ids == [0, 1] and gwo.best_fitness == [math.inf, 2.0]
    assert gwo.seconds == 0.75 and cells[("PSO", "F1")].best_fitness == [3.0]
