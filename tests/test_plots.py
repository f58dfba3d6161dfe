"""swarmpath.evidence.plots: what the figures draw (medians, bands, colours, failure marks), file
names."""

import numpy as np
import pytest
from matplotlib.colors import to_hex

from swarmpath.evidence import plots
from swarmpath.world.presets import get_map
from swarmpath.world.scenario_io import scenario_from_dict


def curves(rng, runs, iters, scale):
    return np.minimum.accumulate(scale * rng.random((runs, iters)) + 1e-3, axis=1)


def test_convergence_figure_draws_the_median_and_the_iqr_of_each_algorithm():
    rng = np.random.default_rng(0)
    data = {"GWO": curves(rng, 7, 40, 10.0), "PSO": curves(rng, 5, 40, 100.0)}
    fig = plots.convergence_figure("F1, 10 dimensions", {k: v.tolist() for k, v in data.items()})
    ax = fig.axes[0]
    lines = ax.get_lines()
    assert len(lines) == 2 and len(ax.collections) == 2  # a median and a band per algorithm
    for line, band, (name, values) in zip(lines, ax.collections, data.items(), strict=True):
        assert np.allclose(line.get_ydata(), np.median(values, axis=0))
        assert list(line.get_xdata()) == list(range(1, 41))
        verts = band.get_paths()[0].vertices
        assert verts[:, 1].min() == pytest.approx(np.percentile(values, 25, axis=0).min())
        assert verts[:, 1].max() == pytest.approx(np.percentile(values, 75, axis=0).max())
        assert to_hex(band.get_facecolor()[0][:3]) == to_hex(line.get_color())
        assert name in line.get_label()
    assert ax.get_yscale() == "log"
    assert ax.get_xlabel() == "iteration"
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert legend == ["GWO (median of 7)", "PSO (median of 5)"]


def test_curves_are_log_f_minus_f_star_like_the_dashboard():
    # F8-like: negative f, f* = -4: the error f - f* is drawn on a log axis
    fig = plots.convergence_figure("F8", {"GWO": [[-1.0, -2.0, -3.0], [-1.0, -1.5, -4.0]]},
                                   f_star=-4.0)
    ax = fig.axes[0]
    assert ax.get_yscale() == "log"
    assert np.allclose(ax.get_lines()[0].get_ydata(), [3.0, 2.25, 0.5])
    # one algorithm reaches 0 (F9, F11): still log, its zeros at the smallest positive error,
    # and the other two stay decades apart (a linear axis would show three flat lines at 0)
    zero = [[1.0, 0.0, 0.0]] * 3
    small, big = [[1.0, 1e-3, 1e-5]] * 3, [[10.0, 5.0, 1e3 / 1e3]] * 3
    fig = plots.convergence_figure("F9", {"A": zero, "B": small, "C": big})
    ax = fig.axes[0]
    assert ax.get_yscale() == "log"
    a, b, c = (line.get_ydata() for line in ax.get_lines())
    assert a[-1] == pytest.approx(1e-5) and b[-1] == pytest.approx(1e-5)
    assert c[1] / b[1] == pytest.approx(5e3)
    assert "0 drawn at 1.0e-05" in ax.get_ylabel()


def test_thinned_curves_are_resampled_onto_the_longest():
    x, values = plots.curve_matrix([[8.0, 4.0, 2.0, 1.0, 0.5], [8.0, 2.0, 0.5]])
    assert list(x) == [1, 2, 3, 4, 5]
    assert values[1].tolist() == [8.0, 5.0, 2.0, 1.25, 0.5]  # first and last iteration kept


def test_box_figure_keeps_one_colour_per_name_and_marks_missing_ones():
    fig = plots.box_figure("t", [("length", {"A": [1.0, 2.0, 3.0], "B": [], "C": [2.0, None]})],
                           empty="nothing")
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_xticklabels()]
    assert labels == ["A", "B\n(none)", "C"]
    colours = plots.palette(["A", "B", "C"])
    faces = [to_hex(p.get_facecolor()[:3]) for p in ax.patches]
    assert faces == [to_hex(colours["A"][:3]), to_hex(colours["C"][:3])]


def wall_scenario():
    return scenario_from_dict({
        "name": "wall", "size": [10, 10], "start": [1, 5], "goal": [9, 5],
        "obstacles": [{"shape": "circle", "center": [5, 5], "radius": 1.0}],
    })


def test_map_figure_legend_matches_the_drawn_paths_and_marks_failed_runs():
    sc = wall_scenario()
    through = [[1.0, 5.0, 0.0], [3.0, 5.0, 1.0], [4.5, 5.0, 2.0], [5.0, 5.0, 3.0]]
    around = [[1.0, 5.0, 0.0], [5.0, 8.0, 1.0], [9.0, 5.0, 2.0]]
    runs = [
        {"run": 0, "success": True, "collisions": 0, "path": around},
        {"run": 1, "success": True, "collisions": 0, "path": [[1, 5, 0], [5, 2, 1], [9, 5, 2]]},
        {"run": 2, "success": False, "collisions": 2, "reason": "collided 2 times",
         "path": through},
    ]
    fig = plots.map_figure("X", sc, runs, lambda run: sc.instantiate(np.random.default_rng(run)))
    ax = fig.axes[0]
    handles = {h.get_label(): h for h in fig.legends[0].legend_handles}
    ok_colour = to_hex(handles["run (reached the goal)"].get_color())
    fail_colour = to_hex(handles["run (failed; x: where it stopped)"].get_color())
    lines = ax.get_lines()
    solid = [ln for ln in lines if ln.get_linestyle() == "-" and len(ln.get_xdata()) == 3]
    assert len(solid) == 2 and all(to_hex(ln.get_color()) == ok_colour for ln in solid)
    dashed = [ln for ln in lines if ln.get_linestyle() == "--" and len(ln.get_xdata()) == 4]
    assert len(dashed) == 1 and to_hex(dashed[0].get_color()) == fail_colour
    stop = [ln for ln in lines if ln.get_marker() == "x"]
    assert len(stop) == 1 and (stop[0].get_xdata()[0], stop[0].get_ydata()[0]) == (5.0, 5.0)
    assert to_hex(stop[0].get_color()) == fail_colour
    hits = [ln for ln in lines if ln.get_marker() == "o" and ln.get_linestyle() == "None"
            and to_hex(ln.get_markerfacecolor()) == fail_colour]
    # the steps ending at (4.5, 5) and (5, 5) touch the circle; the one ending at (3, 5) does not
    assert len(hits) == 1 and sorted(hits[0].get_xdata()) == [4.5, 5.0]
    assert "colliding step" in handles


def test_map_figure_without_collisions_has_no_collision_legend():
    sc = wall_scenario()
    runs = [{"run": 0, "success": False, "collisions": 0, "reason": "step limit",
             "path": [[1.0, 5.0, 0.0], [2.0, 8.0, 1.0]]}]
    fig = plots.map_figure("X", sc, runs, lambda run: None)
    labels = [h.get_label() for h in fig.legends[0].legend_handles]
    assert "colliding step" not in labels and "run (failed; x: where it stopped)" in labels


def test_write_plots_names_files_by_cell(tmp_path):
    bench = [{"algorithm": a, "function": "F1", "dim": 2, "best_fitness": 0.1 * (i + 1),
              "curve": [1.0, 0.5, 0.1 * (i + 1)]} for a in ("GWO", "PSO") for i in range(3)]
    names = sorted(p.name for p in plots.write_benchmark_plots(bench, tmp_path))
    assert names == ["box_F1_d2.png", "curves_F1_d2.png"]
    sc = get_map("mfb-static")
    runs = [{"planner": "OMPL-RRT*", "map": sc.name, "run": 0, "success": True, "collisions": 0,
             "length": 15.0, "gap": 0.01, "seconds": 0.1,
             "path": [[*sc.start, 0.0], [*sc.goal, 1.0]]}]
    out = plots.write_map_plots(runs, {sc.name: sc}, lambda s, r: None, tmp_path / "m")
    assert sorted(p.name for p in out) == ["OMPL-RRT_mfb-static.png", "box_mfb-static.png"]
    assert all(p.read_bytes().startswith(b"\x89PNG") for p in out)


def _panel_texts(fig):
    return [[t.get_text() for t in ax.texts] for ax in fig.axes]


def test_map_box_figure_says_why_each_empty_panel_is_empty():
    moving = [{"planner": "MFB", "success": True, "length": 14.0, "gap": None, "seconds": 0.5},
              {"planner": "ICOOT", "success": True, "length": 14.2, "gap": None, "seconds": 0.6}]
    texts = _panel_texts(plots.map_box_figure("m", moving))
    assert texts == [[], ["no exact optimum:\nthe map moves"], []]
    stuck = [{**r, "success": False, "length": None} for r in moving]
    texts = _panel_texts(plots.map_box_figure("m", stuck))
    assert texts == [["no successful run"], ["no successful run"], []]
