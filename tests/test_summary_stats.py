"""The statistics of a job's summary (service.summary_stats) and the job spec's `reference`."""

from __future__ import annotations

import json

import pytest
from pydantic import ValidationError
from scipy import stats

from swarmpath.evidence import report
from swarmpath.evidence.compare_maps import map_statistics as map_tests
from swarmpath.service.protocol import parse_job_spec
from swarmpath.service.summary_stats import (
    BENCHMARK_TEST_COLUMNS,
    MAP_TEST_COLUMNS,
    benchmark_statistics,
    map_statistics,
    statistics_lines,
)


def test_benchmark_rows_get_markers_and_p_values_of_the_table() -> None:
    rows = [{"algorithm": a, "function": f, "dim": 2} for f in ("F1", "F2") for a in "ABC"]
    values = [[1.0, 2, 3, 4, 5], [6.0, 7, 8, 9, 10], [11.0, 12, 13, 14, 15],
              [1.0, 1, 1], None, [1.0, 1, 1]]
    doc = benchmark_statistics(rows, values, ["A", "B", "C"])
    assert doc["comparison"]["reference"] == "C"
    by = {(r["function"], r["algorithm"]): r for r in rows}
    p = stats.mannwhitneyu([1.0, 2, 3, 4, 5], [11.0, 12, 13, 14, 15]).pvalue
    assert by[("F1", "A")]["p"] == pytest.approx(p)
    assert by[("F1", "A")]["p_holm"] == pytest.approx(3 * p)  # 3 tests: F1 A, F1 B, F2 A
    assert by[("F1", "A")]["marker"] == "+" and by[("F1", "B")]["marker"] == "+"
    assert by[("F2", "A")]["marker"] == "=" and by[("F2", "A")]["p"] == 1.0
    assert by[("F2", "B")]["marker"] is None  # no run finished yet
    assert by[("F1", "C")]["marker"] is None  # the reference
    same = report.benchmark_tests(
        {(r["algorithm"], r["function"], 2): v for r, v in zip(rows, values, strict=True) if v},
        ["A", "B", "C"])
    assert doc == report.tests_to_json(same)
    json.dumps(doc, allow_nan=False)


def test_map_rows_get_a_marker_per_measure() -> None:
    rows = [{"planner": p, "map": "m"} for p in ("P", "Q")]
    runs = [
        [{"success": True, "length": 1.0 + i, "seconds": 0.1} for i in range(6)],
        [{"success": i < 3, "length": 9.0 + i, "seconds": 0.1} for i in range(6)],
    ]
    doc = map_statistics(rows, runs, ["P", "Q"], reference="P")
    assert set(MAP_TEST_COLUMNS) <= set(rows[1])
    assert rows[0]["length_marker"] is None  # the reference
    assert rows[1]["length_marker"] == "-" and rows[1]["seconds_marker"] == "="
    records = [{**m, "planner": r["planner"], "map": "m"}
               for r, c in zip(rows, runs, strict=True) for m in c]
    assert doc == map_tests(records, ["P", "Q"], "P").to_json()


BENCH = {"kind": "benchmark", "algorithms": ["GWO", "PSO"], "functions": ["F1"], "dims": [2]}
MAP = {"kind": "map", "planners": ["RFO", "OMPL-RRTstar"], "maps": ["mfb-static"]}


@pytest.mark.parametrize("spec", [BENCH, MAP], ids=["benchmark", "map"])
def test_job_spec_reference_is_one_of_the_jobs_members(spec: dict) -> None:
    members = spec.get("algorithms") or spec["planners"]
    assert parse_job_spec(spec).reference is None  # default: the last member, at summary time
    assert parse_job_spec({**spec, "reference": members[0].lower()}).reference == members[0]
    with pytest.raises(ValidationError) as info:
        parse_job_spec({**spec, "reference": "NOPE"})
    (err,) = info.value.errors()
    assert err["loc"][-1] == "reference" and "'NOPE' is not one of" in err["msg"]


def test_store_summary_tests_the_runs_against_the_specs_reference(tmp_path) -> None:
    from swarmpath.service.store import Store
    from test_store import SPEC as STORE_SPEC
    from test_store import direct_values, drain

    spec = {**STORE_SPEC, "reference": "gwo"}
    store = Store(tmp_path / "data")
    try:
        job = store.create_job(spec)
        drain(store)
        summary = store.summary(job)
    finally:
        store.close()
    assert summary is not None
    algorithms = ["GWO", "PSO"]
    assert spec["algorithms"] == algorithms
    expected = report.benchmark_tests(direct_values(spec), algorithms, "GWO")
    assert summary["statistics"] == report.tests_to_json(expected)
    for row in summary["rows"]:
        t = expected.comparison.get((row["function"], row["dim"]), row["algorithm"])
        assert row["marker"] == (None if t is None else t.marker)
        assert row["p_holm"] == (None if t is None else t.p_holm)
    assert [r["marker"] for r in summary["rows"] if r["algorithm"] == "GWO"] == [None, None]
    assert summary["columns"][-len(BENCHMARK_TEST_COLUMNS):] == list(BENCHMARK_TEST_COLUMNS)
    for row in summary["rows"]:  # effect sizes and the posterior beside every marker
        t = expected.comparison.get((row["function"], row["dim"]), row["algorithm"])
        assert row["a12"] == (None if t is None else t.a12)
        assert row["shift"] == (None if t is None or t.shift is None else t.shift.estimate)
        post = expected.bayes.get((row["function"], row["dim"]), row["algorithm"])  # type: ignore[union-attr]
        assert row["p_better"] == (None if post is None else post.p_better)


def test_statistics_lines_of_a_map_summary() -> None:
    rows = [{"planner": p, "map": m} for m in ("m1", "m2") for p in ("P", "Q", "R")]
    runs = [[{"success": True, "length": 1.0 + k + i, "seconds": 0.1 * k} for i in range(4)]
            for k in range(6)]
    doc = map_statistics(rows, runs, ["P", "Q", "R"])
    lines = statistics_lines({"kind": "map", "statistics": doc})
    assert lines[:3] == ["success +/=/- vs R: P 0/2/0, Q 0/2/0",
                         "length +/=/- vs R: P 0/2/0, Q 0/2/0",
                         "seconds +/=/- vs R: P 0/2/0, Q 0/2/0"]
    assert lines[3].startswith("Friedman (length) over 2 blocks: chi2 = 4, p = 0.135")
    assert lines[3].endswith("mean ranks P 1.00 =, Q 2.00 =, R 3.00")
    assert statistics_lines({"kind": "map", "statistics": map_statistics(
        rows[:1], runs[:1], ["P"])}) == []  # one planner: nothing to compare


def test_a_coordinator_starts_without_scipy_stats_and_summarizes_with_it():
    """scipy.stats (about 1 s of CPU) loads at the first summary that tests, not at a
    coordinator's start: the tests' and a farm's hundreds of coordinator starts skip it."""
    from child_python import last_line

    code = ("import sys\n"
            "import swarmpath.service.coordinator\n"
            "before = 'scipy.stats' in sys.modules\n"
            "from swarmpath.evidence.compare import rank_sum\n"
            "u, p = rank_sum([1.0, 2.0, 3.0], [4.0, 5.0, 6.0])\n"
            "print(before, 'scipy.stats' in sys.modules, u, round(p, 3))\n")
    assert last_line(code) == "False True 0.0 0.1"
