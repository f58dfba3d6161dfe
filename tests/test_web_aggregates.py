"""The dashboard's aggregates: grids, curve sampling, bands, box plots, per-job accumulation."""

import math

import numpy as np
import pytest

from swarmpath.service.web import aggregates as agg
from swarmpath.service.web.scene import load_cell_scenario, motion, scene


def test_curve_grid_is_log_spaced_and_covers_both_ends():
    g = agg.curve_grid(500)
    assert g[0] == 1 and g[-1] == 500
    assert np.all(np.diff(g) > 0)
    assert g.size <= agg.GRID_POINTS
    assert (g < 50).sum() > (g > 450).sum()  # denser early on
    assert agg.curve_grid(3).tolist() == [1, 2, 3]
    with pytest.raises(ValueError):
        agg.curve_grid(0)


def test_sample_curve_reads_iterations_and_thinned_curves():
    curve = np.arange(100, 0, -1, dtype=float)  # value after iteration i+1 is 100 - i
    g = agg.curve_grid(100)
    assert agg.sample_curve(curve, g).tolist() == (101 - g).tolist()
    # thinned as the worker thins a curve that does not fit a message: 0, 8, ..., 96, 99
    from swarmpath.service.worker.packing import _thin

    thin = _thin(list(curve), 8)
    got = agg.sample_curve(thin, g, stride=8)
    expected = [curve[(i - 1) // 8 * 8] if i < 100 else curve[-1] for i in g]
    assert got.tolist() == expected
    assert np.all(got >= curve[g - 1])  # best-so-far: the earlier sample is an upper bound


def test_band_is_median_and_quartiles_per_column():
    rows = np.array([[1.0, 10.0], [2.0, 20.0], [3.0, 30.0], [4.0, 40.0], [5.0, 50.0]])
    b = agg.band(rows)
    assert b["median"] == [3.0, 30.0]
    assert b["q1"] == [2.0, 20.0] and b["q3"] == [4.0, 40.0]
    assert all(math.isnan(v) for v in agg.band(np.zeros((0, 2)))["median"])


def test_box_stats_tukey_whiskers_and_outliers():
    values = [1, 2, 3, 4, 5, 6, 7, 8, 100, math.inf]
    b = agg.box_stats(values)
    assert b is not None
    assert b["n"] == 9  # the infinite value is left out
    assert b["median"] == 5.0 and b["q1"] == 3.0 and b["q3"] == 7.0
    assert b["hi"] == 8.0 and b["lo"] == 1.0 and b["outliers"] == [100.0]
    assert agg.box_stats([math.nan, math.inf]) is None
    many = agg.box_stats(list(range(100)) + [1000 + i for i in range(100)] + [50] * 2000)
    assert many is not None and len(many["outliers"]) == agg.MAX_OUTLIERS


def test_thin_path_keeps_ends():
    path = [[i * 0.1, 0.0, i * 0.5] for i in range(1000)]
    thin = agg.thin_path(path, 50)
    assert len(thin) == 50 and thin[0] == [0.0, 0.0, 0.0] and thin[-1] == [99.9, 0.0, 499.5]
    assert agg.thin_path([]) == []


def _bench_cells(runs=4):
    cells, idx = [], 0
    for fn in ("F1", "F8"):
        for alg in ("GWO", "PSO"):
            spec = {"kind": "benchmark", "algorithm": alg, "function": fn, "dim": 2,
                    "agents": 5, "iterations": 20}
            cells.append({"index": idx, "key": f"{alg}/{fn}/2", "spec": spec, "runs": runs})
            idx += 1
    return cells


def test_job_aggregates_benchmark_view_is_incremental_and_deduplicated():
    from swarmpath.functions import get_function

    job = agg.JobAggregates("j1", "benchmark", _bench_cells())
    f8_star = get_function("F8").f_min_for(2)
    for cell in range(4):
        for run in range(4):
            base = f8_star if cell >= 2 else 0.0
            curve = base + np.linspace(1.0, 0.1, 20) * (1 + cell) + 0.01 * run
            assert job.add(cell, run, ok=True, metrics={"best_fitness": float(curve[-1])},
                           curve=curve.tolist())
    assert not job.add(0, 0, ok=True, metrics={"best_fitness": 0.0})  # duplicate
    assert not job.add(9, 0, ok=True, metrics={})  # no such cell
    v1 = job.view()
    assert job.view() is v1  # cached until something is added
    assert [g["function"] for g in v1["groups"]] == ["F1", "F8"]
    g = v1["groups"][1]
    assert set(g["algorithms"]) == {"GWO", "PSO"}
    band = g["algorithms"]["GWO"]["band"]
    assert len(band["median"]) == len(g["iterations"])
    assert min(band["q1"]) >= 0.0  # errors f - f*, not raw F8 values (negative)
    assert g["best"] == ["GWO"]  # its curves were scaled by 3 versus 4
    assert g["algorithms"]["GWO"]["box"]["n"] == 4
    assert job.add(3, 3, ok=True, metrics={}) is False
    job2 = agg.JobAggregates("j1", "benchmark", _bench_cells(runs=5))
    job2.add(0, 4, ok=False, metrics={})
    view = job2.view()
    assert view["groups"][0]["algorithms"]["GWO"]["failed"] == 1
    assert view["groups"][0]["algorithms"]["GWO"]["runs"] == 0


def test_adding_runs_together_equals_adding_them_one_by_one():
    """add_many (what the coordinator calls per accepted batch, curves as arrays) gives the same
    view as add per run: whole curves, a thinned one, failures, repeats, unknown cells."""
    rng = np.random.default_rng(3)
    entries = []
    for cell in range(4):
        for run in range(4):
            curve = np.minimum.accumulate(rng.uniform(0.0, 10.0, 20))
            metrics: dict = {"best_fitness": float(curve[-1])}
            if (cell, run) == (1, 2):  # a thinned curve (every 4th value, and the last)
                curve, metrics = np.append(curve[::4], curve[-1]), {**metrics, "curve_stride": 4}
            times = (0.5 + run, None if cell == 3 else 0.25 * run)  # cell 3: CPU not known
            entries.append((cell, run, (cell, run) != (2, 1), metrics, curve, None, times))
    entries += [entries[0], (9, 0, True, {}, None, None, None),
                (0, 7, True, {}, None, None, None)]
    one = agg.JobAggregates("j1", "benchmark", _bench_cells())
    for cell, run, ok, metrics, curve, path, times in entries:
        one.add(cell, run, ok=ok, metrics=metrics, curve=curve, path=path, times=times)
    many = agg.JobAggregates("j1", "benchmark", _bench_cells())
    assert many.add_many(entries) == 16 and many.add_many(entries[:3]) == 0
    a, b = one.view(), many.view()
    assert a == b and a["groups"][1]["algorithms"]["GWO"]["failed"] == 1
    # wall and CPU seconds: medians over the finished runs (cell 2's run 1 crashed)
    gwo_f1, pso_f8 = a["groups"][0]["algorithms"]["GWO"], a["groups"][1]["algorithms"]["PSO"]
    assert (gwo_f1["seconds"], gwo_f1["cpu_seconds"]) == (2.0, 0.375)
    assert pso_f8["seconds"] == 2.0 and pso_f8["cpu_seconds"] is None  # missing, not 0
    assert a["groups"][1]["algorithms"]["GWO"]["seconds"] == 2.5  # runs 0, 2, 3


def test_job_aggregates_map_view_counts_success_and_marks_failures():
    spec = {"kind": "map", "planner": "ICOOT", "map": "m1", "scenario": None, "params": {}}
    job = agg.JobAggregates("j2", "map", [{"index": 0, "key": "ICOOT/m1", "spec": spec,
                                          "runs": 3}])
    path = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]
    job.add(0, 0, ok=True, metrics={"success": True, "length": 1.4, "gap": 0.1,
                                    "seconds": 0.2, "collisions": 0, "min_clearance": 0.3},
            path=path)
    job.add(0, 1, ok=True, metrics={"success": False, "collisions": 2, "seconds": 0.3,
                                    "reason": "collided 2 times", "length": 9.0,
                                    "min_clearance": -0.02}, path=path)
    job.add(0, 2, ok=False, metrics={})
    g = job.view()["groups"][0]
    cell = g["planners"]["ICOOT"]
    assert cell["runs"] == 3 and cell["succeeded"] == 1 and cell["crashed"] == 1
    assert cell["success_rate"] == pytest.approx(1 / 3)
    assert cell["failures"] == {"collision": 1}
    assert cell["box"]["length"]["n"] == 1  # lengths of successful runs only
    assert cell["box"]["seconds"]["n"] == 2
    # the least clearance of every finished run, the failed one too (the summary's)
    assert cell["box"]["min_clearance"]["n"] == 2 and cell["box"]["min_clearance"]["min"] == -0.02
    assert [p["failure"] for p in cell["paths"]] == [None, "collision"]


@pytest.mark.parametrize(("reason", "collisions", "kind"), [
    ("planner gave up: no feasible move", 0, "stall"),
    ("time limit (120 s simulated)", 0, "timeout"),
    ("step limit (2000 decisions)", 0, "timeout"),
    ("collided 3 times", 3, "collision"),
    ("not finished", 0, "other"),
])
def test_failure_kind(reason, collisions, kind):
    assert agg.failure_kind({"reason": reason, "collisions": collisions}) == kind


def test_scene_and_motion_of_a_dynamic_preset():
    from swarmpath.world.presets import get_map, list_maps

    dynamic = [m for m in list_maps() if get_map(m).is_dynamic]
    assert dynamic, "no dynamic preset map"
    sc = load_cell_scenario({"map": dynamic[0], "scenario": None})
    s = scene(sc)
    assert len(s["obstacles"]) == len(sc.obstacles)
    assert any(o["moving"] for o in s["obstacles"]) or sc.goal_motion is not None
    m = motion(sc, seed=1, run=0, t_end=10.0, samples=11)
    assert len(m["times"]) == 11
    for k, track in m["offsets"].items():
        assert sc.obstacles[int(k)].is_moving
        assert track[0] == [0.0, 0.0] and len(track) == 11
    assert m == motion(sc, seed=1, run=0, t_end=10.0, samples=11)  # reproducible


@pytest.mark.parametrize("reference", [None, "GWO"])
def test_statistics_are_compare_on_the_runs_best_values(reference):
    from swarmpath.evidence.compare import compare_samples, friedman

    job = agg.JobAggregates("j3", "benchmark", _bench_cells(runs=8), reference=reference)
    rng = np.random.default_rng(5)
    values: dict[tuple[str, int], dict[str, list[float]]] = {}
    for cell, c in enumerate(_bench_cells(runs=8)):
        s = c["spec"]
        for run in range(8):
            v = float(rng.random() * (3 if s["algorithm"] == "PSO" else 1))
            job.add(cell, run, ok=True, metrics={"best_fitness": v})
            values.setdefault((s["function"], 2), {}).setdefault(s["algorithm"], []).append(v)
    st = job.view()["statistics"]
    expected = compare_samples(values, ["GWO", "PSO"], reference)
    assert st["reference"] == (reference or "PSO")
    for (function, dim), per in values.items():
        for a in per:
            assert st["markers"].get(f"{function}/{dim}", {}).get(a) == expected.marker(
                (function, dim), a)
    means = {f: {a: float(np.mean(v)) for a, v in per.items()} for (f, _d), per in values.items()}
    assert st["friedman"]["2"]["mean_ranks"] == pytest.approx(
        friedman(means, ["GWO", "PSO"], reference).mean_ranks)
    assert st["counts"] == expected.counts()


def test_a_young_view_is_shared_until_max_age():
    job = agg.JobAggregates("j4", "benchmark", _bench_cells(runs=3))
    job.add(0, 0, ok=True, metrics={"best_fitness": 1.0}, curve=[3.0, 2.0, 1.0])
    first = job.view(max_age=3600.0)
    job.add(0, 1, ok=True, metrics={"best_fitness": 2.0}, curve=[3.0, 2.5, 2.0])
    assert job.view(max_age=3600.0) is first and first["version"] == 1  # younger than max_age
    fresh = job.view()  # max_age 0: recomputed since a run was added
    assert fresh["version"] == 2 and fresh["groups"][0]["algorithms"]["GWO"]["runs"] == 2
    assert job.view() is fresh  # nothing added since


def test_map_statistics_are_compare_on_the_runs():
    from swarmpath.evidence.compare import compare_samples, compare_success

    cells = [{"index": i, "key": f"{p}/m1", "runs": 12,
              "spec": {"kind": "map", "planner": p, "map": "m1", "scenario": None}}
             for i, p in enumerate(("MFB", "ICOOT"))]
    job = agg.JobAggregates("j5", "map", cells)
    rng = np.random.default_rng(2)
    lengths: dict[str, list[float]] = {"MFB": [], "ICOOT": []}
    seconds: dict[str, list[float]] = {"MFB": [], "ICOOT": []}
    success = {"MFB": 0, "ICOOT": 0}
    runs = []
    for i, p in enumerate(("MFB", "ICOOT")):
        for run in range(12):
            ok = run % (2 if p == "MFB" else 6) != 0
            m = {"success": ok, "length": 14.0 + 0.1 * rng.random() + (1.0 if p == "MFB" else 0.0),
                 "seconds": float(rng.random()), "collisions": 0 if ok else 1}
            job.add(i, run, ok=True, metrics=m, path=[[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
            runs.append({**m, "planner": p, "map": "m1"})
            seconds[p].append(m["seconds"])
            if ok:
                lengths[p].append(m["length"])
                success[p] += 1
    st = job.view()["statistics"]
    assert st["reference"] == "ICOOT"
    assert st["markers"]["m1"]["MFB"] == compare_success(
        {"m1": {p: (success[p], 12) for p in success}}, ["MFB", "ICOOT"]).marker("m1", "MFB")
    for name, values in (("length", lengths), ("seconds", seconds)):
        expected = compare_samples({"m1": values}, ["MFB", "ICOOT"]).marker("m1", "MFB")
        assert st[f"{name}_markers"]["m1"]["MFB"] == expected
    assert st["length_markers"]["m1"]["MFB"] == "-"  # every MFB path is longer
    # the +/=/- counts and Friedman mean ranks are those swarmpath plan / results print
    from swarmpath.evidence.compare_maps import map_statistics

    cli = map_statistics(runs, ["MFB", "ICOOT"])
    for name in ("length", "seconds"):
        assert st[f"{name}_counts"] == cli.comparisons[name].counts()
        assert st["friedman"][name]["mean_ranks"] == cli.friedman[name].mean_ranks
    assert st["friedman"]["length"]["mean_ranks"] == {"MFB": 2.0, "ICOOT": 1.0}
