"""`swarmpath bench` statistics: markers, counts, Friedman ranks, --reference, --json, --plot."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from scipy import stats
from typer.testing import CliRunner

from swarmpath.cli import app
from swarmpath.evidence import compare, report
from swarmpath.optimizers import list_optimizers
from test_cli_bench import parse_markers, parse_table

# three registered optimizers (the Friedman test needs three); GWO listed last = the reference
ALGOS = [*[a for a in list_optimizers() if a != "GWO"][:2], "GWO"]
SMALL = ["--agents", "6", "--iterations", "10", "--runs", "6", "--seed", "2", "-j", "1"]
ARGS = ["bench", "-a", ",".join(ALGOS), "-f", "F1,F5,F6", "-d", "2,3", *SMALL]
runner = CliRunner()


@pytest.fixture(scope="module")
def doc() -> dict:
    result = runner.invoke(app, [*ARGS, "--json"])
    assert result.exit_code == 0, result.stderr
    return json.loads(result.stdout)


def test_json_tests_equal_scipy_with_holm_over_the_table(doc: dict) -> None:
    st = doc["statistics"]["comparison"]
    assert st["reference"] == "GWO" and st["alpha"] == 0.05 and st["correction"] == "holm"
    cells = {(c["function"], c["dim"], c["algorithm"]): c for c in doc["cells"]}
    raw = []
    for c in doc["cells"]:
        if c["algorithm"] == "GWO":
            assert c["test"]["marker"] is None and c["test"]["p"] is None
            continue
        ref = cells[(c["function"], c["dim"], "GWO")]
        x = [float(v) for v in c["best_fitness"]]
        y = [float(v) for v in ref["best_fitness"]]
        if len(set(x + y)) == 1:
            expected = (len(x) * len(y) / 2, 1.0)
        else:
            r = stats.mannwhitneyu(x, y, alternative="two-sided")
            expected = (r.statistic, r.pvalue)
        assert c["test"]["p"] == pytest.approx(expected[1])
        raw.append((c, expected))
    assert len(raw) == 2 * 3 * 2  # two algorithms x three functions x two dims: one family
    m = len(raw)
    ordered = sorted(raw, key=lambda item: item[1][1])
    running = 0.0
    for i, (c, (u, p)) in enumerate(ordered):  # Holm's step-down, written out
        running = max(running, min(1.0, (m - i) * p))
        assert c["test"]["p_holm"] == pytest.approx(running)
        n = len(c["best_fitness"]) ** 2
        want = "=" if running >= 0.05 else ("+" if u < n / 2 else "-")
        assert c["test"]["marker"] == want
    counts = st["counts"]
    for a in ALGOS[:2]:
        mine = [c["test"]["marker"] for c, _ in raw if c["algorithm"] == a]
        assert counts[a] == {k: mine.count(k) for k in "+=-"}


def test_json_friedman_per_dim_from_the_averages(doc: dict) -> None:
    fried = {f["dim"]: f for f in doc["statistics"]["friedman"]}
    assert set(fried) == {2, 3}
    for dim, f in fried.items():
        table = np.array([[next(c["stats"]["avg"] for c in doc["cells"]
                                if (c["function"], c["dim"], c["algorithm"]) == (fn, dim, a))
                           for a in ALGOS] for fn in ("F1", "F5", "F6")], dtype=float)
        ranks = stats.rankdata(table, axis=1).mean(axis=0)
        assert [f["mean_ranks"][a] for a in ALGOS] == pytest.approx(ranks.tolist())
        if np.all(stats.rankdata(table, axis=1) == stats.rankdata(table, axis=1)[:, :1]):
            assert f["p"] == 1.0
        else:
            assert f["p"] == pytest.approx(stats.friedmanchisquare(*table.T).pvalue)
        assert f["nemenyi_cd"] == pytest.approx(compare.nemenyi_cd(3, 3))
        assert set(f["posthoc"]) == set(ALGOS[:2])


def test_table_markers_counts_and_friedman_lines_match_the_json(doc: dict) -> None:
    result = runner.invoke(app, ARGS)
    assert result.exit_code == 0, result.stderr
    markers = parse_markers(result.stdout)
    by_cell = {(c["function"], c["dim"], c["algorithm"]): c["test"]["marker"]
               for c in doc["cells"]}
    for (function, dim), printed in markers.items():
        assert printed == [by_cell[(function, dim, a)] for a in ALGOS]
    assert parse_table(result.stdout)[("F1", 2, "avg")][0][0].isdigit()  # values still parse
    counts = doc["statistics"]["comparison"]["counts"]
    for a in ALGOS[:2]:
        line = next(ln for ln in result.stdout.splitlines() if ln.split()[:1] == [a])
        assert "{+}/{=}/{-}".format(**counts[a]) in line
    assert "Friedman D=2 over 3 functions" in result.stdout
    assert "Friedman D=3 over 3 functions" in result.stdout
    assert "worse than GWO" in result.stdout


def test_reference_option_changes_the_reference() -> None:
    result = runner.invoke(app, [*ARGS, "--reference", ALGOS[0].lower(), "--json"])
    assert result.exit_code == 0, result.stderr
    doc = json.loads(result.stdout)
    assert doc["settings"]["reference"] == ALGOS[0]
    assert set(doc["statistics"]["comparison"]["counts"]) == set(ALGOS[1:])
    assert all(c["test"]["reference"] == ALGOS[0] for c in doc["cells"])


def test_bad_reference_is_one_line_naming_the_option() -> None:
    result = runner.invoke(app, [*ARGS, "--reference", "NOPE"])
    assert result.exit_code == 2 and result.stdout == ""
    assert result.stderr.strip().splitlines() == [
        f"swarmpath bench: error: --reference: 'NOPE' is not one of the compared algorithms "
        f"({', '.join(ALGOS)})"
    ]


def test_one_algorithm_has_no_markers() -> None:
    result = runner.invoke(app, ["bench", "-a", "GWO", "-f", "F1", "-d", "2", *SMALL])
    assert result.exit_code == 0, result.stderr
    assert parse_markers(result.stdout) == {("F1", 2): [None]}
    assert "Friedman" not in result.stdout
    doc = json.loads(runner.invoke(app, ["bench", "-a", "GWO", "-f", "F1", "-d", "2", *SMALL,
                                         "--json"]).stdout)
    assert doc["statistics"]["comparison"]["counts"] == {}


def test_plot_writes_a_cd_diagram_per_dimension(tmp_path: Path) -> None:
    out = tmp_path / "figs"
    result = runner.invoke(app, [*ARGS, "--plot", str(out)])
    assert result.exit_code == 0, result.stderr
    assert sorted(p.name for p in out.glob("cd-*")) == ["cd-D2.png", "cd-D3.png"]
    with Image.open(out / "cd-D2.png") as img:
        assert img.format == "PNG" and img.size[0] > 400
        pixels = np.asarray(img.convert("L"))
    assert (pixels < 128).mean() > 0.005  # something is drawn in black
    bad = runner.invoke(app, [*ARGS, "--plot", str(out / "cd-D2.png")])
    assert bad.exit_code == 2 and "--plot" in bad.stderr


def test_statistics_of_cells_with_inf_runs_are_strict_json() -> None:
    def cell(a: str, values: list[float]) -> report.Cell:
        return report.Cell(a, "F1", 2, list(range(len(values))), values, [1] * len(values), 0.0)

    cells = [cell("A", [math.inf] * 4), cell("B", [1.0, 2.0, 3.0, 4.0]), cell("C", [0.0] * 4)]
    tests = report.statistics(cells, ["A", "B", "C"])
    # infinite runs rank worst: every run of A is above every run of the reference C
    assert tests.marker(cells[0]) == "-" and tests.marker(cells[2]) is None
    json.dumps(report.study_to_json({}, cells, 0.0, "x", tests), allow_nan=False)
