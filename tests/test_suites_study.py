"""The suites in a study: names and expansion, errors f - f_opt, instances, budgets, the CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from swarmpath.cli import app
from swarmpath.evidence import report
from swarmpath.evidence.instances import pool_instances
from swarmpath.functions import expand_function_names, get_function, list_functions
from swarmpath.optimizers import ParameterError, minimize
from swarmpath.optimizers.api import minimize_many
from swarmpath.optimizers.budget import iterations_for_budget

runner = CliRunner()


def test_suite_names_ranges_and_the_excluded_cec2017_f2():
    assert expand_function_names("bbob") == [f"bbob:f{k}" for k in range(1, 25)]
    assert len(list_functions("cec2017")) == 30
    assert expand_function_names("cec2017") == [f"cec2017:F{k}" for k in range(1, 31) if k != 2]
    assert expand_function_names("cec2017:F1-F3") == ["cec2017:F1", "cec2017:F3"]
    assert expand_function_names("cec2017:F2") == ["cec2017:F2"]
    assert expand_function_names("cec2022:F11-F12,F1") == ["cec2022:F11", "cec2022:F12", "F1"]
    assert expand_function_names("bbob:f23-f24") == ["bbob:f23", "bbob:f24"]
    for bad in ("bbob:f25", "bbob:f5-f3", "cec2022:F13", "cec2017:F1@i2", "bbob:f1@i0"):
        with pytest.raises(KeyError):
            expand_function_names(bad)


def test_instances_are_cocos_and_named():
    f = get_function("bbob:f3@i7")
    assert (f.name, f.instance) == ("bbob:f3@i7", 7)
    assert get_function("bbob:f3@i1").name == "bbob:f3"
    assert f.f_opt(10) != get_function("bbob:f3").f_opt(10)
    x = f.x_opt(10)
    assert f.evaluate(x[None])[0] == pytest.approx(0.0, abs=1e-12)
    assert f.value(x[None])[0] == pytest.approx(f.f_opt(10))


def test_a_suite_study_reports_errors_from_its_instance():
    res = minimize("GWO", "bbob:f1@i2", dim=5, agents=10, iterations=30, runs=3, seed=2)
    fn = get_function("bbob:f1@i2")
    assert np.all(res.best_fitness >= 0.0)
    assert np.allclose(fn.value(res.best_position) - fn.f_opt(5), res.best_fitness)
    np.testing.assert_array_equal(res.curve[:, -1], res.best_fitness)


def test_cec_errors_below_1e8_are_reported_as_zero():
    fn = get_function("cec2022:F1")
    assert fn.report([5e-9, 1e-8, 2.0]).tolist() == [0.0, 1e-8, 2.0]
    assert get_function("bbob:f1").report([5e-9]).tolist() == [5e-9]


@pytest.mark.parametrize(("name", "dim", "transform", "says"), [
    ("cec2017:F1", 12, "none", "dim in 10, 30, 50, 100"),
    ("cec2022:F1", 30, "none", "dim in 10, 20"),
    ("bbob:f1", 1, "none", "dim >= 2"),
    ("bbob:f1", 5, "shift", "transform must be 'none'"),
])
def test_suite_studies_refuse_what_the_suite_does_not_define(name, dim, transform, says):
    with pytest.raises(ParameterError, match=says):
        minimize("GWO", name, dim=dim, agents=10, iterations=2, runs=1, transform=transform)


def test_the_budget_counts_no_evaluation_past_it():
    """A run capped at e0 + k e1 evaluations reports what the uncapped run had after k
    iterations, and nothing after (its curve stays flat)."""
    free = minimize("GWO", "bbob:f3", dim=4, agents=10, iterations=20, runs=3, seed=5)
    e0, e1 = 10, 10
    k = 7
    capped = minimize_many("GWO", ["bbob:f3"], dim=4, agents=10, iterations=20, runs=3, seed=5,
                           max_evaluations=e0 + k * e1)[0]
    assert capped.evaluations.tolist() == [e0 + k * e1] * 3
    np.testing.assert_array_equal(capped.best_fitness, free.curve[:, k - 1])
    np.testing.assert_array_equal(capped.curve[:, k - 1:], capped.curve[:, -1:].repeat(
        20 - k + 1, axis=1))
    assert np.all(free.best_fitness <= capped.best_fitness)


@pytest.mark.parametrize("algorithm", ["GWO", "mCOOT", "RFO", "FDO"])
def test_budget_iterations_spend_the_budget(algorithm):
    budget = 2000
    t = iterations_for_budget(algorithm, budget, 20, 5)
    res = minimize_many(algorithm, ["bbob:f1"], dim=5, agents=20, iterations=t, runs=2,
                        max_evaluations=budget)[0]
    assert np.all(res.evaluations <= budget)
    assert np.all(res.evaluations > budget - 60)  # within one iteration of it
    with pytest.raises(ParameterError, match="budget_evals 30"):
        iterations_for_budget(algorithm, 30, 20, 5)


def _bench(*args: str):
    return runner.invoke(app, ["bench", "-a", "GWO,PSO", "--agents", "8", "--runs", "3",
                               "--seed", "3", *args])


def test_bench_runs_a_cell_per_instance_and_pools_them_on_request():
    apart = _bench("-f", "bbob:f1,bbob:f6", "-d", "3", "--instances", "1-2",
                   "--iterations", "10", "--json")
    assert apart.exit_code == 0, apart.output
    doc = json.loads(apart.stdout)
    assert sorted({c["function"] for c in doc["cells"]}) == [
        "bbob:f1", "bbob:f1@i2", "bbob:f6", "bbob:f6@i2"]
    pooled = _bench("-f", "bbob:f1,bbob:f6", "-d", "3", "--instances", "1-2",
                    "--iterations", "10", "--json", "--pool-instances")
    assert pooled.exit_code == 0, pooled.output
    cells = json.loads(pooled.stdout)["cells"]
    assert sorted({c["function"] for c in cells}) == ["bbob:f1", "bbob:f6"]
    by = {(c["algorithm"], c["function"]): c for c in doc["cells"]}
    for c in cells:  # the pooled values are the instances' values, in instance order
        assert c["best_fitness"] == (by[(c["algorithm"], c["function"])]["best_fitness"]
                                     + by[(c["algorithm"], c["function"] + "@i2")]["best_fitness"])


def test_bench_budget_in_evaluations_per_dimension():
    out = _bench("-f", "cec2022:F1", "-d", "10", "--budget-evals", "50xD", "--json")
    assert out.exit_code == 0, out.output
    for c in json.loads(out.stdout)["cells"]:
        assert max(c["run_evaluations"]) <= 500
    table = _bench("-f", "cec2022:F1", "-d", "10", "--budget-evals", "50xD")
    assert "budget 50 x D evaluations per run" in table.stdout
    assert "errors f - f_opt (CEC: < 1e-8 as 0)" in table.stdout.replace("\n", " ")


@pytest.mark.parametrize(("args", "option"), [
    (["-f", "F1", "--instances", "1-2"], "--instances"),
    (["-f", "cec2017:F1", "-d", "10", "--instances", "2"], "--instances"),
    (["-f", "bbob:f1", "--instances", "3-1"], "--instances"),
    (["-f", "bbob:f1", "--pool-instances"], "--pool-instances"),
    (["-f", "bbob:f1", "--budget-evals", "10xN"], "--budget-evals"),
    (["-f", "bbob:f1", "-d", "5", "--budget-evals", "10"], "--budget-evals"),
    (["-f", "cec2017", "-d", "20"], "--dims"),
    (["-f", "bbob:f2", "-d", "5", "--transform", "rotate"], "--transform"),
    (["-f", "cec2017:F2@centre", "-d", "10", "--backend", "numba"], "--backend"),
    # a name that fixes its instance is not silently re-instanced into other functions
    (["-f", "bbob:f3@i7", "--instances", "1-2"], "--instances"),
])
def test_bench_names_the_bad_option(args, option):
    out = _bench(*args)
    assert out.exit_code == 2
    assert option in out.output


def test_bench_runs_cec_on_numba_and_auto_with_the_numpy_backends_numbers():
    args = ("-f", "cec2022:F4,cec2022:F12", "-d", "10", "--iterations", "6", "--json")
    docs = [json.loads(out.stdout) for out in (
        _bench(*args, "--backend", "numba"), _bench(*args), _bench(*args, "--backend", "numpy"))]
    assert [doc["settings"]["backend"] for doc in docs] == ["numba", "auto", "numpy"]
    assert len(docs[0]["cells"]) == 4
    for cells in zip(*(doc["cells"] for doc in docs), strict=True):
        assert len({(c["algorithm"], c["function"]) for c in cells}) == 1
        assert cells[0]["best_fitness"] == cells[1]["best_fitness"] == cells[2]["best_fitness"]


def test_bench_runs_bbob_on_numba_with_the_numpy_backends_numbers():
    args = ("-f", "bbob:f7,bbob:f21", "-d", "4", "--instances", "1-2", "--iterations", "8",
            "--json")
    compiled = _bench(*args, "--backend", "numba")
    reference = _bench(*args, "--backend", "numpy")
    assert compiled.exit_code == 0, compiled.output
    docs = [json.loads(out.stdout) for out in (compiled, reference)]
    assert [doc["settings"]["backend"] for doc in docs] == ["numba", "numpy"]
    assert len(docs[0]["cells"]) == 8
    for a, b in zip(docs[0]["cells"], docs[1]["cells"], strict=True):
        assert (a["algorithm"], a["function"]) == (b["algorithm"], b["function"])
        assert a["best_fitness"] == b["best_fitness"]


def test_pooling_keeps_cells_without_instances():
    cell = report.Cell("GWO", "F1", 5, [0, 1], [1.0, 2.0], [10, 10], 0.1)
    (same,) = pool_instances([cell])
    assert same is cell


def test_ioh_export_writes_suite_instances_as_iohprofiler_numbers_them(tmp_path):
    from swarmpath.evidence.ioh import write_ioh

    items = [{"state": "done", "algorithm": "GWO", "function": f, "dim": 5, "run": r,
              "curve": [3.0, 2.0], "evaluations": 20, "seed": 1,
              "spec": {"iterations": 2, "agents": 10}}
             for f in ("bbob:f3", "bbob:f3@i7", "cec2022:F2") for r in (0, 1)]
    write_ioh(items, tmp_path / "json", "j")  # the default: IOHexperimenter's JSON form
    meta = json.loads((tmp_path / "json" / "GWO" / "IOHprofiler_f3_bbob_f3.json").read_text())
    assert (meta["suite"], meta["function_id"], meta["function_name"]) == ("bbob", 3, "bbob:f3")
    assert [r["instance"] for r in meta["scenarios"][0]["runs"]] == [1, 1, 7, 7]
    write_ioh(items, tmp_path, "j", "ioh-info")
    lines = (tmp_path / "GWO" / "IOHprofiler_f3_bbob_f3.info").read_text().splitlines()
    assert lines[0].startswith('suite = "bbob", funcId = 3, funcName = "bbob:f3", DIM = 5')
    assert [e.split(":")[0] for e in lines[2].split(", ")[1:]] == ["1", "1", "7", "7"]
    cec = (tmp_path / "GWO" / "IOHprofiler_f2_cec2022_F2.info").read_text()
    assert cec.startswith('suite = "cec2022", funcId = 2,')


def test_a_reproduction_table_on_a_suite_runs_its_budget_and_pooled_instances():
    """A reproduce-style table may state budget_evals and instances (the baselines' CEC and
    BBOB tables will): its study runs them, pools the instances per function, and skips the
    origin check (an instance moves the optimum already)."""
    from swarmpath.cli import reproduce
    from swarmpath.cli.reproduce_run import run_benchmark_local
    from swarmpath.evidence.reference import BenchmarkTable

    table = BenchmarkTable(
        name="suite-demo", source={}, setting={"runs": 2, "agents": 6, "iterations": 5,
                                               "dims": [3], "budget_evals": "40xD",
                                               "instances": [1, 3]},
        algorithms=("GWO", "PSO"), functions=("bbob:f1", "bbob:f7"), stats=("avg",), notes=(),
        cell_notes={}, cells={})
    setting = reproduce.study_setting(table, None, 2)
    assert setting["budget_evals"] == "40xD" and setting["instances"] == [1, 3]
    assert reproduce._suites(setting)
    cells = pool_instances(run_benchmark_local(setting, 1))
    assert sorted({(c.function, c.algorithm) for c in cells}) == [
        ("bbob:f1", "GWO"), ("bbob:f1", "PSO"), ("bbob:f7", "GWO"), ("bbob:f7", "PSO")]
    assert all(len(c.best_fitness) == 4 and max(c.evaluations) <= 120 for c in cells)


def test_a_table_s_error_floor_makes_errors_below_it_equal():
    """cmaes-pycma-bbob-d5 states COCO's 1e-8: a run at 1e-14 against a published 0 is equal
    there, and hundreds of decades worse without it (bbob resolves errors to the last bit)."""
    from swarmpath.evidence.reference import BenchmarkTable
    from swarmpath.evidence.reproduction import benchmark_rows

    def table(setting_extra):
        return BenchmarkTable(
            name="floor-demo", source={}, setting={"runs": 3, "agents": 5, "iterations": 5,
                                                   "dims": [5], **setting_extra},
            algorithms=("CMA-ES",), functions=("bbob:f1",), stats=("min", "max", "avg", "std"),
            notes=(), cell_notes={},
            cells={("bbob:f1", "CMA-ES"): {"min": 0.0, "max": 0.0, "avg": 0.0, "std": 0.0}})

    runs = {("bbob:f1", "CMA-ES"): [1e-14, 2e-14, 3e-14]}
    (floored,) = benchmark_rows(table({"error_floor": 1e-8}), runs, {})
    (raw,) = benchmark_rows(table({}), runs, {})
    assert floored.log10_ratio == 0.0 and floored.verdict in ("matches", "consistent")
    assert raw.log10_ratio > 10 and raw.verdict == "worse"
