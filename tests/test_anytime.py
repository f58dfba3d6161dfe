"""swarmpath.evidence.anytime: targets, runtimes, ECDF and its area, ERT with its bootstrap
interval and fixed-budget values, on cases worked by hand; and what bench prints and writes."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from swarmpath.cli import app
from swarmpath.evidence import anytime
from swarmpath.evidence.anytime import RunTrace

runner = CliRunner()


def trace(evals: list[float], errors: list[float]) -> RunTrace:
    return RunTrace(np.array(evals, dtype=float), np.array(errors, dtype=float))


def test_default_targets_are_iohanalyzers_log_linear_ten() -> None:
    runs = [trace([10, 20, 30], [100.0, 10.0, 1.0]), trace([10, 20], [50.0, 0.5])]
    t = anytime.default_targets(runs)
    assert t.size == 10 and t[0] == 100.0 and t[-1] == 0.5  # both ends exact, descending
    np.testing.assert_allclose(np.diff(np.log10(t)), -np.log10(200) / 9)
    # zeros and values below 1e-12 are raised to IOHanalyzer's floor
    assert anytime.default_targets([trace([1, 2], [1.0, 0.0])])[-1] == 1.0
    assert anytime.default_targets([trace([1, 2], [1.0, 1e-20])])[-1] == 1e-12
    b = anytime.bbob_targets()
    assert b.size == 51 and b[0] == pytest.approx(100.0) and b[-1] == pytest.approx(1e-8)


def test_runtimes_ert_auc_and_fixed_budget_by_hand() -> None:
    runs = [trace([10, 20, 30], [100.0, 10.0, 1.0]), trace([10, 40], [60.0, 60.0])]
    targets = np.array([50.0, 5.0, 0.1])
    times = anytime.runtimes(runs, targets)
    assert times.tolist() == [[20.0, 30.0, math.inf], [math.inf] * 3]
    budgets = np.array([30.0, 40.0])
    # ERT of 50: (20 spent by the run reaching it + 40 by the one that did not) / 1 success
    assert anytime.ert(times[:, 0], budgets) == 60.0
    assert anytime.ert(times[:, 2], budgets) == math.inf
    # area under the ECDF over budgets 0..40, over 40: pairs (20, 30) reached, 4 missed
    assert anytime.ecdf_auc(times, 40.0) == pytest.approx(((1 - 20 / 40) + (1 - 30 / 40)) / 6)
    assert anytime.ecdf_curve(times, np.array([19.0, 20.0, 30.0])).tolist() == [0, 1 / 6, 2 / 6]
    fixed = anytime.fixed_budget(runs, np.array([5.0, 10.0, 25.0, 100.0]))
    assert fixed.tolist() == [[math.inf, 100.0, 10.0, 1.0], [math.inf, 60.0, 60.0, 60.0]]


def test_ert_interval_is_a_seeded_bootstrap_of_the_runs() -> None:
    same = anytime.ert_interval(np.array([5.0] * 8), np.array([9.0] * 8))
    assert same == (5.0, 5.0)
    rng = np.random.default_rng(1)
    times = np.where(rng.random(30) < 0.7, rng.integers(10, 100, 30).astype(float), math.inf)
    budgets = np.full(30, 100.0)
    lo, hi = anytime.ert_interval(times, budgets, seed=3)
    assert (lo, hi) == anytime.ert_interval(times, budgets, seed=3)
    assert lo <= anytime.ert(times, budgets) <= hi
    # the bootstrap by hand: resample the runs, ERT of each resample, 2.5 and 97.5 % order stats
    idx = np.random.default_rng(3).integers(0, 30, size=(anytime.RESAMPLES, 30))
    values = np.sort([anytime.ert(times[i], budgets[i]) for i in idx])
    assert (lo, hi) == (values[24], values[975])
    never = anytime.ert_interval(np.full(5, math.inf), np.full(5, 10.0))
    assert never == (math.inf, math.inf)


def test_trace_of_maps_iterations_to_evaluations_and_subtracts_f_star() -> None:
    t = anytime.trace_of([5.0, 3.0, -1.0], f_star=-2.0, iterations=3, evaluations=40, agents=10)
    assert t.evaluations.tolist() == [20.0, 30.0, 40.0]
    assert t.errors.tolist() == [7.0, 5.0, 1.0]


def test_bench_json_and_plot_carry_the_anytime_view(tmp_path: Path) -> None:
    args = ["bench", "-a", "GWO,PSO", "-f", "F1,F8", "-d", "2", "--agents", "6",
            "--iterations", "10", "--runs", "4", "--seed", "2"]
    doc = json.loads(runner.invoke(app, [*args, "--json"]).stdout)
    groups = {(g["function"], g["dim"]): g for g in doc["anytime"]}
    assert set(groups) == {("F1", 2), ("F8", 2)}
    g = groups[("F8", 2)]  # F8's f is negative: the targets are on f - f*
    assert len(g["targets"]) == 10 and all(float(t) > 0 for t in g["targets"])
    assert g["budget"] == 66 and g["target_set"] == "iohanalyzer"
    for a in ("GWO", "PSO"):
        cell = g["algorithms"][a]
        assert 0 <= cell["auc"] <= 1 and cell["runs"] == 4 and cell["hits"][0] >= 1
    printed = runner.invoke(app, [*args, "--anytime"])
    assert "F8, D=2: fixed target" in printed.stdout and "ECDF AUC" in printed.stdout
    out = tmp_path / "plots"
    assert runner.invoke(app, [*args, "--plot", str(out)]).exit_code == 0
    assert (out / "anytime_F8_d2.png").stat().st_size > 0
