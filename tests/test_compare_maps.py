"""swarmpath.evidence.compare_maps and the comparison under `swarmpath plan`'s tables."""

from __future__ import annotations

import json
import math
from typing import Any

import pytest
from scipy import stats
from typer.testing import CliRunner

from swarmpath.cli import app
from swarmpath.evidence.compare_maps import MEASURES, map_statistics

runner = CliRunner()


def run(planner: str, map_name: str, success: bool, length: float, seconds: float) -> dict:
    return {"planner": planner, "map": map_name, "success": success, "length": length,
            "seconds": seconds}


def test_length_over_successful_runs_time_over_all_success_by_fisher() -> None:
    runs: list[dict[str, Any]] = []
    for i in range(5):
        runs.append(run("A", "m", True, 1.0 + i, 0.5 + i))
        runs.append(run("B", "m", True, 6.0 + i, 0.1 * i))
    runs.append(run("A", "m", False, 0.01, 9.0))  # a failed run's length is not a path length
    tests = map_statistics(runs)
    assert tests.reference == "B"  # the last planner seen
    length = tests.comparisons["length"].get("m", "A")
    assert length is not None and (length.n, length.n_reference) == (5, 5)
    assert length.p == pytest.approx(2 / 252) and length.marker == "+"  # exact, one test
    seconds = tests.comparisons["seconds"].get("m", "A")
    assert seconds is not None and seconds.n == 6
    want = stats.mannwhitneyu([0.5, 1.5, 2.5, 3.5, 4.5, 9.0], [0.0, 0.1, 0.2, 0.3, 0.4],
                              alternative="two-sided")
    assert seconds.p == pytest.approx(want.pvalue) and seconds.marker == "-"
    success = tests.comparisons["success"].get("m", "A")
    assert success is not None
    assert success.p == pytest.approx(stats.fisher_exact([[5, 1], [5, 0]]).pvalue)
    assert success.marker == "="


def test_success_markers_and_a_planner_that_never_succeeds() -> None:
    runs = [run("A", "m", True, 2.0, 1.0) for _ in range(10)]
    runs += [run("B", "m", False, 0.0, 1.0) for _ in range(10)]
    tests = map_statistics(runs, ["A", "B"])
    success = tests.comparisons["success"].get("m", "A")
    assert success is not None and success.p == pytest.approx(2 / math.comb(20, 10))
    assert success.marker == "+"
    assert tests.marker("length", "m", "A") is None  # the reference has no path length to test
    again = map_statistics(runs, ["A", "B"], reference="A")
    assert again.marker("success", "m", "B") == "-"
    json.dumps(tests.to_json(), allow_nan=False)


def test_friedman_over_maps_by_hand() -> None:
    runs = []
    for k, m in enumerate(("m1", "m2", "m3", "m4")):
        for p, base in (("A", 1.0), ("B", 2.0), ("C", 3.0)):
            runs += [run(p, m, True, base + k, base) for _ in range(3)]
    tests = map_statistics(runs)
    f = tests.friedman["length"]
    assert f.mean_ranks == {"A": 1.0, "B": 2.0, "C": 3.0}
    assert f.statistic == pytest.approx(8.0) and f.p == pytest.approx(math.exp(-4.0))
    assert set(tests.to_json()["comparisons"]) == set(MEASURES)


def test_plan_prints_the_comparison_and_rejects_a_bad_reference() -> None:
    params = json.dumps({p: {"iterations": 1000} for p in ("OMPL-RRTstar", "OMPL-BITstar")})
    args = ["plan", "-j", "1", "-p", "OMPL-RRTstar,OMPL-BITstar", "-m", "mfb-static", "--runs",
            "2", "--params", params]
    result = runner.invoke(app, [*args, "--reference", "ompl-rrtstar"])
    assert result.exit_code == 0, result.stderr
    assert "Planners against OMPL-RRTstar" in result.stdout
    comparison = result.stdout[result.stdout.index("Planners against"):]
    row = next(ln.split() for ln in comparison.splitlines()
               if ln.split()[:2] == ["mfb-static", "OMPL-RRTstar"])
    assert row[2] == "2/2"  # the reference: no marker
    *_, counts = (ln.split() for ln in result.stdout.splitlines()
                  if ln.split()[:1] == ["OMPL-BITstar"])  # the counts table comes last
    assert counts[1:4] == ["0/1/0", "0/1/0", "0/1/0"]  # two runs can never differ significantly
    assert "Friedman (length) over 1 maps: the Friedman test needs at least 3" in result.stdout
    bad = runner.invoke(app, [*args, "--reference", "MFB"])
    assert bad.exit_code == 2 and bad.stdout == ""
    assert bad.stderr.strip().startswith("swarmpath plan: error: --reference: 'MFB' is not one")
