"""The transcribed tables of the seed papers (swarmpath.evidence.reference): integrity, the facts
about the prints that the files' notes state, and the reasons file."""

from __future__ import annotations

import math
from importlib import resources

import pytest

from swarmpath.evidence import prints, reference, reproduction
from swarmpath.evidence.reference import BenchmarkTable, MapTable
from swarmpath.functions import get_function
from swarmpath.optimizers import list_optimizers
from swarmpath.planners import list_planners
from swarmpath.world import list_maps

BENCH = [n for n in reference.TABLES if isinstance(reference.load(n), BenchmarkTable)]
MAPS = [n for n in reference.TABLES if isinstance(reference.load(n), MapTable)]


def test_every_table_file_is_listed_and_every_listed_table_has_a_file():
    files = {
        p.name.removesuffix(".yaml")
        for p in resources.files("swarmpath.evidence.reference").iterdir()
        if p.name.endswith(".yaml") and p.name != reference.REASONS_FILE
    }
    assert files == set(reference.TABLES)


@pytest.mark.parametrize("name", reference.TABLES)
def test_source_and_setting_are_stated(name):
    table = reference.load(name)
    assert {"paper", "table", "caption"} <= set(table.source)
    # a seed paper's table names its seed text; another paper's, where it was read
    assert {"seed", "origin"} & set(table.source)
    assert table.setting["runs"] > 0
    assert table.notes


@pytest.mark.parametrize("name", BENCH)
def test_benchmark_table_is_complete_and_names_what_swarmpath_runs(name):
    table = reference.load(name)
    assert table.stats == ("min", "max", "avg", "std")
    if table.setting.get("budget_evals") is None:  # the seeds' tables: F1-F13
        assert table.functions == tuple(f"F{i}" for i in range(1, 14))
    else:  # a suite's table (CEC 2017: F1-F30 as the paper printed them)
        assert all(":" in f for f in table.functions)
    assert set(table.algorithms) <= set(list_optimizers())
    assert len(table.cells) == len(table.functions) * len(table.algorithms)
    for f in table.functions:
        get_function(f)  # a registered function
    for key in table.cell_notes:
        function, algorithm = key.split("/")
        assert (function, algorithm) in table.cells, key


def _contradicts(table: BenchmarkTable, function: str, algorithm: str) -> bool:
    cell = table.cells[(function, algorithm)]
    ordered = [v for v in (cell["min"], cell["avg"], cell["max"]) if v is not None]
    return (ordered != sorted(ordered) or f"{function}/{algorithm}" in table.contradicts
            or prints.contradiction(cell, int(table.setting["runs"]),
                                          get_function(function).f_min_for(table.dim))
            is not None)


@pytest.mark.parametrize("name", BENCH)
def test_a_print_that_contradicts_itself_has_a_note_saying_how(name):
    """Out of order, or impossible for any set of runs (prints.contradiction), or
    declared in ``contradicts``: a cell note says what the print shows (derived columns are
    not comparable as a whole and need none)."""
    table = reference.load(name)
    silent = [f"{f}/{a}" for f, a in table.cells if a not in table.derived
              and _contradicts(table, f, a) and table.note_for(f, a) is None]
    assert silent == []


@pytest.mark.parametrize("name", BENCH)
def test_cell_notes_only_where_the_print_contradicts_itself(name):
    table = reference.load(name)
    for key in table.cell_notes:
        function, algorithm = key.split("/")
        assert _contradicts(table, function, algorithm), key


def _mantissa_ratio(a: float, b: float) -> float:
    """a / b scaled into [1, 10)."""
    r = abs(a / b)
    return r / 10 ** math.floor(math.log10(r))


@pytest.mark.parametrize("name", ["icoot-table2", "icoot-table3", "icoot-table4"])
def test_published_mcoot_is_coot_times_6296_times_a_power_of_ten(name):
    """The fact the files' notes state: every non-zero legible mCOOT cell is COOT's x 6.296 x
    10^k, except the two listed."""
    table = reference.load(name)
    exceptions = []
    checked = 0
    for f in table.functions:
        m, c = table.cells[(f, "mCOOT")], table.cells[(f, "COOT")]
        for s in table.stats:
            if m[s] in (None, 0.0) or c[s] in (None, 0.0):
                continue
            checked += 1
            if abs(_mantissa_ratio(m[s], c[s]) - 6.296) > 0.003:
                exceptions.append(f"{f}/{s}")
    assert checked > 15
    assert exceptions == {"icoot-table2": ["F7/std"],
                          "icoot-table4": ["F3/min", "F6/min", "F6/max", "F10/avg"]}.get(name, [])


def test_ihpo_paper_copies_the_icoot_papers_columns():
    icoot, ihpo = reference.load("icoot-table2"), reference.load("ihpo-table2")
    compared = 0
    for algorithm in ("PSO", "SSA", "FDO", "COOT"):
        for f in icoot.functions:
            a, b = icoot.cells[(f, algorithm)], ihpo.cells[(f, algorithm)]
            for s in icoot.stats:
                if a[s] is not None and b[s] is not None:
                    compared += 1
                    assert a[s] == b[s], (algorithm, f, s)
    assert compared == 4 * 13 * 4 - 4  # all but ICOOT's illegible PSO F8


def test_one_published_run_sets_the_ihpo_f2_and_f4_means():
    """IHPO F2 and F4 print min 0, std 0 and avg = max / 1000: 999 runs at 0, one at the max
    (the fact ihpo-table2/IHPO/F2/30's reason rests on)."""
    table = reference.load("ihpo-table2")
    for function in ("F2", "F4"):
        cell = table.cells[(function, "IHPO")]
        assert cell["min"] == 0.0 and cell["std"] == 0.0
        assert cell["avg"] == pytest.approx(cell["max"] / 1000, rel=1e-12)


def test_pso_f9_prints_min_equal_max_but_a_different_average():
    cell = reference.load("icoot-table2").cells[("F9", "PSO")]
    assert cell["min"] == cell["max"] == 76.413 and cell["avg"] == 38.604


@pytest.mark.parametrize("name", MAPS)
def test_map_table_names_what_swarmpath_runs(name):
    table = reference.load(name)
    assert set(table.planners) <= set(list_planners())
    assert set(table.maps) <= set(list_maps())
    assert set(table.maps) == set(table.setting["maps"])
    for cell in table.cells.values():
        for column, runs in cell.runs.items():
            assert len(runs) == table.setting["runs"], (cell.planner, cell.map, column)


@pytest.mark.parametrize("name", MAPS)
def test_printed_mean_rows_agree_with_the_printed_runs(name):
    """A printed Mean row equals the mean of the printed runs to the printed precision."""
    table = reference.load(name)
    for cell in table.cells.values():
        for column, runs in cell.runs.items():
            mean = sum(runs) / len(runs)
            assert cell.mean[column] == pytest.approx(mean, rel=2e-4, abs=1e-4), (
                cell.planner, cell.map, column)


def test_static_map_distances_shorter_than_the_straight_line():
    """The fact the map files state: the static-goal maps' published distances are below the
    14.1421 m from (0, 0) to (10, 10)."""
    line = math.hypot(10, 10)
    for name, map_name in (("icoot-maps", "icoot-map1"), ("ihpo-maps", "ihpo-map1")):
        table = reference.load(name)
        (cell,) = [c for c in table.cells.values() if c.map == map_name]
        assert max(cell.runs["distance_m"]) < line
        assert cell.mean["distance_m"] < line


def test_mfb_table5_std_exceeds_the_range_it_describes():
    table = reference.load("mfb-maps")
    for hi, lo, _mean, std in table.extra["table5"].values():
        assert std > hi - lo


def test_reasons_name_existing_cells_and_state_what_they_explain():
    reasons = reference.load_reasons()
    keys = reference.all_cell_keys()
    assert sorted(set(reasons) - keys) == []
    for key, entry in reasons.items():
        assert entry.reason and entry.evidence, key
        assert entry.direction in reference.DIRECTIONS, key
        assert entry.exceedance in (None, *reference.EXCEEDANCES), key


def test_a_reason_for_a_difference_names_a_cell_the_print_lets_us_compare():
    """better/worse reasons on illegible, self-contradicting or derived cells could never
    hold (those cells are not comparable): none is left."""
    dead = []
    for key, entry in reference.load_reasons().items():
        table = reference.load(key.split("/")[0])
        if entry.direction == "not comparable" or not isinstance(table, BenchmarkTable):
            continue
        _, algorithm, function, _ = key.split("/")
        if reproduction.not_comparable(table, function, algorithm) is not None:
            dead.append(key)
    assert dead == []


def test_reasons_file_refuses_a_reason_without_a_direction(monkeypatch):
    docs = {
        "no direction": {"t/A/F1/30": {"reason": "r", "evidence": "e"}},
        "bad direction": {"t/A/F1/30": {"reason": "r", "evidence": "e", "direction": "up"}},
        "bad exceedance": {"t/A/F1/30": {"reason": "r", "evidence": "e", "direction": "worse",
                                          "exceedance": "sideways"}},
        "same_as nowhere": {"t/A/F1/30": {"same_as": "t/B/F1/30"}},
    }
    for what, doc in docs.items():
        monkeypatch.setattr(reference, "_read", lambda _name, doc=doc: doc)
        with pytest.raises(reference.ReferenceError):
            reference.load_reasons()
        assert what
    copied = {"t/A/F1/30": {"reason": "r", "evidence": "e", "direction": "better",
                            "exceedance": "none"},
              "u/A/F1/30": {"same_as": "t/A/F1/30"}}
    monkeypatch.setattr(reference, "_read", lambda _name: copied)
    reasons = reference.load_reasons()
    assert reasons["u/A/F1/30"] == reasons["t/A/F1/30"]
    assert reasons["u/A/F1/30"].direction == "better"


def test_unknown_table_is_refused_with_the_valid_names():
    with pytest.raises(KeyError, match="icoot-table2"):
        reference.load("icoot-table9")


def test_a_suite_table_s_setting_line_names_its_paper_and_budget():
    from swarmpath.cli.reproduce_output import _setting_text

    text = _setting_text(reference.load("jso-cec2017-d10"), {"runs": 10, "seed": 1})
    assert text == ("The results of the jSO algorithm for D = 10 of Brest, Maucec & Boskovic, "
                    "CEC 2017 (51 runs, 10000xD evaluations, 10 dims); measured: 10 runs per "
                    "cell, seed 1")
    assert " of 000_" in _setting_text(reference.load("icoot-table2"), {"runs": 3, "seed": 1})
