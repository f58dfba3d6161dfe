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
from swarmpath.evidence import prints, reference, reproduction, reproduction_maps
from swarmpath.evidence.reference import Reason
from swarmpath.evidence.reproduction import BETTER, CONSISTENT, MATCHES, NOT_COMPARABLE, WORSE
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
        "jso-cec2017-d10", "jso-cec2017-d30", "cmaes-pycma-bbob-d5",
        "lshade-reference-cec2017-d10",
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


def test_verdicts_on_hand_worked_cells():
    # published SSA F3: avg 1292.1, min 195.21, max 2873.7, 1000 runs
    spread = _row("F3", "SSA", [1000.0, 1200.0, 1400.0, 1600.0, 1300.0, 1250.0])
    assert spread.verdict == CONSISTENT and not spread.unexplained
    assert spread.interval[0] < 1292.1 < spread.interval[1]
    assert (spread.exceedance.above, spread.exceedance.below) == (0, 0)
    same = _row("F3", "SSA", [2500.0] * 10)  # interval [2500, 2500]: within a decade only
    assert same.verdict == MATCHES and same.interval == (2500.0, 2500.0)
    worse = _row("F3", "SSA", [5e4, 6e4])
    assert worse.verdict == WORSE and worse.unexplained and worse.log10_ratio > 1
    assert worse.exceedance.above == 2
    better = _row("F3", "SSA", [1.0, 2.0])
    assert better.verdict == BETTER and better.unexplained and better.log10_ratio < -1
    assert better.exceedance.below == 2 and better.exceedance.departs()


def test_runs_inside_the_published_range_no_longer_explain_a_mean_off_by_decades():
    # COOT F1: avg 8.7095e-11 but min 9.8206e-58, max 8.6061e-08 (a range of 50 decades)
    row = _row("F1", "COOT", [1e-40, 1e-35])
    assert row.verdict == BETTER and row.unexplained and row.reason is None
    assert not row.exceedance.departs()


def test_both_at_the_floor_are_consistent_and_f8_can_fail():
    # ICOOT F9 published min 0, avg 1.06e-14: our exact zeros are far below
    assert _row("F9", "ICOOT", [0.0, 0.0]).verdict == BETTER
    ihpo = reference.load("ihpo-table2")
    at_floor = _row("F9", "HPO", [0.0, 0.0, 0.0], table=ihpo)  # published 0 everywhere
    assert at_floor.verdict == CONSISTENT and at_floor.log10_ratio == 0
    # F10 published 8.8818e-16 (MATLAB's floor), ours 4.44e-16: both at the floor
    assert _row("F10", "HPO", [4.440892098500626e-16] * 3, table=ihpo).verdict == CONSISTENT
    # F8: ICOOT avg -6564.9; f_min(30) = -12569.5: a gap of 6004.6
    fmin = -418.9828872724338 * 30
    assert _row("F8", "ICOOT", [fmin + 600.0] * 2).log10_ratio == pytest.approx(-1.0, abs=0.01)
    # a decade on the gap would accept 600 .. 60000, i.e. every f an optimizer ends with;
    # F8's tolerance is 10 % of the gap: 25 % better is better, 3 % better matches
    assert _row("F8", "ICOOT", [fmin + 4500.0] * 3).verdict == BETTER
    assert _row("F8", "ICOOT", [fmin + 5800.0] * 3).verdict == MATCHES
    near = _row("F8", "ICOOT", list(fmin + np.array([5000.0, 7000.0, 6100.0, 5900.0, 6000.0])))
    assert near.verdict == CONSISTENT and near.interval[0] < -6564.9 < near.interval[1]


def test_illegible_self_contradicting_or_derived_published_cells_are_not_comparable():
    assert _row("F8", "PSO", [-5000.0]).verdict == NOT_COMPARABLE  # illegible in the print
    row = _row("F9", "PSO", [40.0])  # min = max = 76.413, avg 38.604
    assert row.verdict == NOT_COMPARABLE and "contradicts" in row.reason
    assert not row.unexplained
    mcoot = _row("F1", "mCOOT", [1e-30, 1e-20])  # the column is COOT's times 6.296 x 10^k
    assert mcoot.verdict == NOT_COMPARABLE and "not a measurement" in mcoot.reason


def test_printed_cells_that_no_set_of_runs_can_have():
    f = prints.contradiction
    assert f({"min": 1.2345, "max": 3.1, "avg": 0.5432, "std": 0.1}, 1000, 0.0).startswith("avg")
    # avg = max with a spread (icoot-table4 SSA F4): every run would have to be the max
    assert f({"min": 27.379, "max": 39.255, "avg": 39.255, "std": 2.7189}, 1000, 0.0)
    # Bhatia-Davis: runs in [0, 1.2345] averaging 0.61725 have a std of at most 0.6176
    assert f({"min": 0.0, "max": 1.2345, "avg": 0.61725, "std": 0.6123}, 1000, 0.0) is None
    assert "std" in f({"min": 0.0, "max": 1.2345, "avg": 0.61725, "std": 0.6234}, 1000, 0.0)
    # without a max: 1000 runs >= 0 averaging 1 have a std of at most sqrt(1000)
    assert f({"min": None, "max": None, "avg": 1.0, "std": 31.0}, 1000, 0.0) is None
    assert f({"min": None, "max": None, "avg": 1.0, "std": 5.0e5}, 1000, 0.0)
    # the mean of 1000 runs is at least max / 1000 when every run is >= 0 ...
    assert f({"min": 0.0, "max": 1.2345, "avg": 1.1234e-3, "std": None}, 1000, 0.0)
    assert f({"min": 0.0, "max": 1.2345, "avg": 1.2346e-3, "std": None}, 1000, 0.0) is None
    # ... within the print's rounding: 8.9600e-02 is 8.96e-02 printed with padding zeros
    assert f({"min": 0.0, "max": 89.635, "avg": 8.96e-2, "std": 2.8345}, 1000, 0.0) is None
    # one run at the max and 999 at 0 (ICOOT F1 of Table 2 prints avg = max / 1000 and
    # std = max / sqrt(1000)): the extreme case, and possible
    assert f({"min": 3.4334e-52, "max": 1.7486e-15, "avg": 1.7507e-18, "std": 5.5295e-17},
             1000, 0.0) is None


def test_a_reason_explains_only_the_direction_it_states():
    key = reference.cell_key("icoot-table2", "SSA", "F3", 30)
    worse_reason = {key: Reason("because", "swarmpath bench ...", WORSE)}
    row = _row("F3", "SSA", [5e4], worse_reason)
    assert row.verdict == WORSE and row.holds and not row.unexplained
    assert (row.reason, row.evidence) == ("because", "swarmpath bench ...")
    # the same reason on a cell that came out better does not explain it
    flipped = _row("F3", "SSA", [1.0], worse_reason)
    assert flipped.verdict == BETTER and not flipped.holds and flipped.unexplained
    assert flipped.reason == "because"  # still shown, with its claim
    assert flipped.to_json("benchmark")["reason_explains"] == WORSE


def test_a_reason_that_does_not_hold_is_printed_as_failing_only_where_the_cell_needs_one():
    from swarmpath.cli import reproduce_output as output

    key = reference.cell_key("icoot-table2", "SSA", "F3", 30)
    worse_reason = {key: Reason("because", "swarmpath bench ...", WORSE)}
    flipped = _row("F3", "SSA", [1.0], worse_reason)  # better: needs a reason, this one fails
    _, (line,), (note,) = output.grid(T2, [flipped], {})
    assert line[-1] == "[1] UNEXPLAINED"
    assert note.startswith(f"{key}: DOES NOT HOLD (it explains `worse`; the cell is `better`")
    # the published mean in the interval: no reason is needed, the reason is not a failure
    spread = _row("F3", "SSA", [1000.0, 1200.0, 1400.0, 1600.0, 1300.0, 1250.0], worse_reason)
    assert spread.verdict == CONSISTENT and not spread.holds and not spread.unexplained
    _, (line,), (note,) = output.grid(T2, [spread], {})
    assert line[-1] == "[1]"
    assert note.startswith(f"{key}: not needed here (it explains `worse`; the cell is "
                           "`consistent`")


def test_a_tail_reason_holds_only_for_the_runs_it_describes():
    key = reference.cell_key("icoot-table2", "COOT", "F1", 30)
    none = {key: Reason("sampling", "swarmpath reproduce ...", BETTER, "none")}
    # COOT F1: min 9.8206e-58, max 8.6061e-08
    assert not _row("F1", "COOT", [1e-40, 1e-35], none).unexplained
    below = _row("F1", "COOT", [1e-70, 1e-70, 1e-35], none)  # two runs below the min
    assert below.verdict == BETTER and below.exceedance.departs() and below.unexplained
    above = {key: Reason("stuck", "swarmpath bench ...", WORSE, "above")}
    stuck = _row("F1", "COOT", [1e-5, 1e-5, 1e-6], above)
    assert stuck.verdict == WORSE and not stuck.unexplained
    one = _row("F1", "COOT", [1e-5] + [5e-8] * 29, above)  # one run above: no departure
    assert one.verdict == WORSE and one.unexplained


def _outcome(length: float, success: bool = True) -> dict:
    return {"success": success, "length": length, "error": 0.01, "seconds": 0.5,
            "collisions": 0}


def test_map_verdicts():
    mfb = reference.load("mfb-maps")
    scen = {m: get_map(m) for m in mfb.maps}
    published = mfb.cells[("MFB", "mfb-static")].mean["distance_m"]  # mean of the 10 runs
    rows = reproduction_maps.map_rows(mfb, {
        ("MFB", "mfb-static"): [_outcome(published * 1.05), _outcome(published * 1.05)],
        ("HPSO-MFB", "mfb-static"): [_outcome(30.0), _outcome(1.0, success=False)],
    }, {}, scen)
    assert [r.verdict for r in rows] == [MATCHES, WORSE]
    assert rows[1].extra["success"] == "1/2" and rows[1].runs == [30.0]
    icoot = reference.load("icoot-maps")
    rows = reproduction_maps.map_rows(icoot, {("ICOOT", "icoot-map1"): [_outcome(14.6)],
                                         ("ICOOT", "icoot-map3"): [_outcome(1.0, False)]},
                                 {}, {m: get_map(m) for m in icoot.maps})
    assert [r.verdict for r in rows] == [NOT_COMPARABLE, NOT_COMPARABLE]
    assert "shorter than the 14.1421 m straight line" in rows[0].reason
    assert rows[1].reason == "no successful run"
    # RFO-GWO's lengths are in unknown units: compared relative to RFO-GWO-EA on the same map
    rfo = reference.load("rfogwo-maps")
    scen = {m: get_map(m) for m in rfo.maps}
    published = rfo.cells[("GWO", "rfogwo-map1")].mean["length_units"] / rfo.cells[
        ("RFO-GWO-EA", "rfogwo-map1")].mean["length_units"]  # 52,908 / 43,122 = 1.227
    rows = reproduction_maps.map_rows(rfo, {
        ("GWO", "rfogwo-map1"): [_outcome(234.0), _outcome(236.0)],
        ("RFO-GWO-EA", "rfogwo-map1"): [_outcome(229.0), _outcome(229.0)],
        ("RFO", "rfogwo-map2"): [_outcome(300.0)],
    }, {}, scen)
    gwo, ea, rfo2 = rows
    assert gwo.published["avg"] == pytest.approx(published)
    assert gwo.measured["avg"] == pytest.approx(235.0 / 229.0)  # relatively shorter: better
    assert gwo.verdict == BETTER and gwo.extra["length_m"] == 235.0
    assert ea.verdict == NOT_COMPARABLE and "reference of the length ratios" in ea.reason
    assert rfo2.verdict == NOT_COMPARABLE and "no successful run of RFO-GWO-EA" in rfo2.reason


def test_document_counts_and_is_strict_json():
    rows = [_row("F3", "SSA", [5e4]), _row("F3", "SSA", [math.inf]), _row("F8", "PSO", [1.0])]
    rows.append(_row("F3", "SSA", [1000.0, 1200.0, 1400.0, 1600.0, 1300.0, 1250.0]))
    doc = reproduction.document(T2, {"runs": 1, "seed": 1}, rows)
    text = json.dumps(doc, allow_nan=False)
    assert json.loads(text)["unexplained"] == 2 and doc["consistent"] == 1
    assert doc["counts"]["SSA"] == {CONSISTENT: 1, MATCHES: 0, BETTER: 0, WORSE: 2,
                                    NOT_COMPARABLE: 0}
    assert doc["counts"]["PSO"][NOT_COMPARABLE] == 1
    cell = doc["cells"][0]
    assert {"function", "dim", "algorithm", "published", "measured", "runs", "log10_ratio",
            "interval95", "exceedance", "verdict", "reason", "reason_holds"} <= set(cell)
    assert cell["exceedance"]["above_max"] == 1 and cell["exceedance"]["paper_runs"] == 1000
    assert reproduction.summary_line(rows) == "4 cells, 2 unexplained, 1 consistent"


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
