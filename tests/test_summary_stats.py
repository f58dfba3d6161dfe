"""The statistics of a job's summary (service.summary_stats) and the job spec's `reference`."""

from __future__ import annotations

import json

import pytest
from pydantic import ValidationError
from scipy import stats

from swarmpath import report
from swarmpath.compare_maps import map_statistics as map_tests
from swarmpath.service.protocol import parse_job_spec
from swarmpath.service.summary_stats import (
    MAP_TEST_COLUMNS,
    benchmark_statistics,
    map_statistics,
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
