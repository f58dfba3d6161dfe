"""Origin-bias audit: decades lost per optimizer, origin-suspect cells, the ``audit`` command."""

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from swarmpath.cli import app
from swarmpath.evidence import audit as au
from swarmpath.functions import get_function, list_functions
from swarmpath.optimizers import list_optimizers, minimize

runner = CliRunner()


def test_decades_lost_by_hand():
    values = {
        ("A", "F1", 5, "none"): [0.0, 0.0],  # mean gap 0 -> the floor 1e-300
        ("A", "F1", 5, "shift"): [1e-4, 3e-4],  # mean 2e-4
        ("A", "F1", 5, "shift+rotate"): [0.0, 0.0],
        ("A", "F9", 5, "none"): [2.0, 4.0],  # 3
        ("A", "F9", 5, "shift"): [30.0, 30.0],  # 30: one decade
        ("A", "F9", 5, "shift+rotate"): [0.3, 0.3],  # a decade better
        ("A", "F8", 5, "none"): [-2094.9144363621687 + 1.0] * 2,  # f_min(5) + 1
        ("A", "F8", 5, "shift"): [-2094.9144363621687 + 1000.0] * 2,  # three decades
        ("A", "F8", 5, "shift+rotate"): [-2094.9144363621687 + 1.0] * 2,
    }
    (row,) = au.audit(values, ["A"], ["F1", "F9", "F8"], [5])
    shift = row.decades["shift"]
    assert shift["F1"] == pytest.approx(math.log10(2e-4) + 300)
    assert shift["F9"] == pytest.approx(1.0)
    assert shift["F8"] == pytest.approx(3.0, abs=1e-9)
    assert row.median("shift") == pytest.approx(3.0, abs=1e-9)
    assert (row.losing("shift", 1.0), row.losing("shift", 3.0)) == (1 + 1, 1)
    assert row.decades["shift+rotate"]["F9"] == pytest.approx(-1.0)
    assert (row.exact_zeros, row.plain_runs) == (2, 6)


@pytest.mark.parametrize("name", list_functions())
def test_origin_suspect_only_where_the_optimum_is_the_origin(name):
    f = get_function(name)
    at_origin = f.optimum_coordinate == 0.0
    assert au.optimum_at_origin(name) == at_origin
    assert au.origin_suspect(name, [f.f_min, 1.0]) == at_origin
    assert au.origin_suspect(name, [f.f_min + 1e-120]) == at_origin
    assert not au.origin_suspect(name, [f.f_min + 1e-50, math.inf])


def test_origin_suspect_catches_hpo_and_not_pso():
    """HPO's hunter scales positions toward 0: exact zeros on plain F1; PSO has no such move."""
    kw = dict(dim=10, agents=20, iterations=300, runs=3, seed=1)
    assert au.origin_suspect("F1", minimize("HPO", "F1", **kw).best_fitness)
    assert not au.origin_suspect("F1", minimize("PSO", "F1", **kw).best_fitness)


def test_audit_command_covers_every_optimizer():
    args = ["audit", "-f", "F1,F9", "-d", "3", "--runs", "2", "--iterations", "5", "-j", "1"]
    out = runner.invoke(app, [*args, "--json"])
    assert out.exit_code == 0, out.output
    doc = json.loads(out.stdout)
    rows = {r["algorithm"]: r for r in doc["rows"]}
    assert list(rows) == list_optimizers()
    for r in rows.values():
        assert r["plain_runs"] == 4
        assert set(r["transforms"]) == {"shift", "shift+rotate"}
        shift = list(r["transforms"]["shift"]["decades_lost"].values())
        assert r["centre_bias_index"] == pytest.approx(10 ** float(np.mean(shift)))
        assert r["centre_biased"] == (r["centre_bias_index"] > au.KUDELA_BIASED)
        for t in r["transforms"].values():
            lost = list(t["decades_lost"].values())
            assert t["median_decades_lost"] == pytest.approx(float(np.median(lost)))
    table = runner.invoke(app, [*args, "--format", "markdown"])
    assert table.exit_code == 0
    lines = [ln for ln in table.stdout.splitlines() if ln.startswith("| ")]
    assert len(lines) == 1 + len(list_optimizers())


def test_audit_command_refuses_bad_input_naming_the_option():
    out = runner.invoke(app, ["audit", "--format", "html"])
    assert out.exit_code == 2 and "--format" in out.output
    out = runner.invoke(app, ["audit", "-a", "NOPE"])
    assert out.exit_code == 2 and "--algorithms" in out.output


def test_bench_flags_origin_suspect_cells_of_untransformed_studies_only():
    args = ["bench", "-a", "HPO", "-f", "F1,F5", "-d", "10", "--runs", "3", "--iterations",
            "300", "-j", "1"]
    plain = runner.invoke(app, args)
    assert plain.exit_code == 0, plain.output
    assert au.ORIGIN_MARK in plain.stdout and "--transform shift" in plain.stdout
    doc = json.loads(runner.invoke(app, [*args, "--json"]).stdout)
    assert {c["function"]: c["origin_suspect"] for c in doc["cells"]} == {"F1": True, "F5": False}
    moved = runner.invoke(app, [*args, "--transform", "shift"])
    assert moved.exit_code == 0 and au.ORIGIN_MARK not in moved.stdout
    doc = json.loads(runner.invoke(app, [*args, "--transform", "shift", "--json"]).stdout)
    assert all("origin_suspect" not in c for c in doc["cells"])


@pytest.mark.parametrize(("lost", "flagged"), [(30.0, True), (3.2, True), (2.9, False),
                                               (-5.0, False), (None, False)])
def test_reproduce_marks_origin_suspect_cells_by_the_decades_they_lose_shifted(lost, flagged):
    """Not exact zeros: GWO-like cells at 1e-30 that lose 30 decades shifted are marked, an
    exact 0 that survives the shift is not."""
    from swarmpath.cli import reproduce_output as ro
    from swarmpath.evidence.reproduction import Row

    runs = [0.0, 1e-3] if lost is not None and lost < 3 else [1e-30, 1e-20]
    stats = {"avg": float(np.mean(runs)), "median": 0.0, "min": 0.0, "max": 1.0, "std": 0.0}
    extra = {} if lost is None else {"decades_lost_shift": lost}
    row = Row(key="t/A/F1/30", who="A", where="F1", dim=30, published={}, measured=stats,
              runs=runs, log10_ratio=None, verdict="matches", reason=None, evidence=None,
              extra=extra)
    assert (au.ORIGIN_MARK in ro._measured(row, {})[0]) == flagged
    assert ro._origin_note([row]) == ([au.SHIFT_FOOTNOTE] if flagged else [])


def test_benchmark_rows_carry_the_decades_lost_under_shift():
    """The same cell measured shifted: decades lost = log10(mean gap shifted / plain), the
    audit's number."""
    from swarmpath.evidence import reference, reproduction

    table = reference.load("icoot-table2")
    plain, moved = [1e-30, 3e-30], [1e-3, 3e-3]
    (row,) = reproduction.benchmark_rows(table, {("F1", "COOT"): plain}, {},
                                         {("F1", "COOT"): moved})
    assert row.extra["decades_lost_shift"] == pytest.approx(27.0, abs=1e-3)
    assert row.extra["shifted_runs"] == moved
    assert au.shift_suspect(row.extra["decades_lost_shift"])
    assert au.decades_lost("F1", 30, plain, moved) == pytest.approx(27.0)


def test_kudela_index_is_the_geometric_mean_of_the_shift_ratios_and_flags_hpo():
    from swarmpath.evidence.audit import audit as run_audit

    values = {}
    functions = ["F1", "F9", "F10"]
    for algo in ("HPO", "CMA-ES"):
        for f in functions:
            for t in ("none", "shift", "shift+rotate"):
                res = minimize(algo, f, dim=5, agents=20, iterations=150, runs=4, seed=3,
                               transform=t)
                values[(algo, f, 5, t)] = list(res.best_fitness)
    rows = {r.algorithm: r for r in run_audit(values, ["HPO", "CMA-ES"], functions, [5])}
    for r in rows.values():
        ratios = [au.mean_gap(f, 5, values[(r.algorithm, f, 5, "shift")])
                  / au.mean_gap(f, 5, values[(r.algorithm, f, 5, "none")]) for f in functions]
        geometric = math.exp(sum(math.log(q) for q in ratios) / len(ratios))  # no overflow
        assert r.centre_bias_index() == pytest.approx(geometric)
    assert rows["HPO"].centre_biased()  # its hunter pulls toward 0 (docs/algorithms.md)
    assert not rows["CMA-ES"].centre_biased()


def test_a_centred_suite_instance_is_the_instance_moved_so_its_optimum_is_the_origin():
    from swarmpath.functions.registry import suite_of

    for name in ("bbob:f3@i7", "bbob:f20@i2", "cec2017:F5", "cec2022:F12"):
        fn, centred = get_function(name), get_function(name + "@centre")
        d = 10
        x = np.random.default_rng(1).uniform(-5.0, 5.0, (6, d))
        assert centred.name == name + "@centre" and suite_of(centred.name) == suite_of(name)
        assert np.array_equal(centred.optimum(d), np.zeros(d))
        assert centred.kernel(np.zeros((1, d)))[0] == pytest.approx(0.0, abs=1e-9)
        np.testing.assert_array_equal(centred.kernel(x), fn.kernel(x + fn.optimum(d)))
        np.testing.assert_array_equal(centred.value(x), fn.value(x + fn.optimum(d)))
        assert not np.allclose(centred.kernel(x), fn.kernel(x))
    with pytest.raises(KeyError, match="F1@centre"):
        get_function("F1@centre")  # F1 has no instance to centre: F1 is centred already


def test_audit_on_suite_instances_compares_each_with_its_centred_copy():
    args = ["audit", "-a", "HPO,RS", "-f", "bbob:f1,bbob:f2", "--instances", "1-2", "-d", "3",
            "--runs", "2", "--iterations", "60", "-j", "1"]
    out = runner.invoke(app, [*args, "--json"])
    assert out.exit_code == 0, out.output
    doc = json.loads(out.stdout)
    assert doc["settings"]["functions"] == ["bbob:f1", "bbob:f1@i2", "bbob:f2", "bbob:f2@i2"]
    rows = {r["algorithm"]: r for r in doc["rows"]}
    for r in rows.values():
        assert set(r["transforms"]) == {"shift"}  # an instance is rotated already
        lost = r["transforms"]["shift"]["decades_lost"]
        assert list(lost) == doc["settings"]["functions"]
        assert r["centre_bias_index"] == pytest.approx(10 ** float(np.mean(list(lost.values()))))
    assert rows["HPO"]["centre_biased"] and not rows["RS"]["centre_biased"]
    table = runner.invoke(app, args)
    assert table.exit_code == 0 and "@centre" in table.stdout
    assert table.stdout.splitlines()[1].split()[5:8] == ["-", "-", "-"]
