"""LaTeX tables (``--format latex``): the booktabs source, its markers and caption, and a real
compile with pdflatex where a LaTeX engine is installed (Debian texlive-latex-base and
texlive-latex-recommended, which holds booktabs; .ci/run installs them)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest
from typer.testing import CliRunner

from swarmpath.cli import app
from swarmpath.evidence import latex, report, tables

runner = CliRunner()
SMALL = ["--agents", "6", "--iterations", "8", "--runs", "5", "--seed", "4"]


def _compile(source: str, tmp_path: Path) -> str:
    """pdflatex on a document around ``source``; skips naming the packages when it is absent."""
    engine = shutil.which("pdflatex")
    if engine is None:
        pytest.skip("no LaTeX engine: apt-get install texlive-latex-base "
                    "texlive-latex-recommended (booktabs)")
    found = subprocess.run(["kpsewhich", "booktabs.sty"], capture_output=True, text=True)
    if not found.stdout.strip():
        pytest.skip("booktabs.sty missing: apt-get install texlive-latex-recommended")
    (tmp_path / "t.tex").write_text(latex.document(source), encoding="utf-8")
    done = subprocess.run([engine, "-interaction=nonstopmode", "-halt-on-error", "t.tex"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout[-3000:]
    assert (tmp_path / "t.pdf").stat().st_size > 0
    return done.stdout


def test_cell_text_sets_numbers_as_math_and_escapes() -> None:
    assert latex.cell_text("6.59E-28") == r"$6.59\times10^{-28}$"
    assert latex.cell_text("-1.20E+03") == r"$-1.20\times10^{3}$"
    assert latex.cell_text("[1.00E-01, inf]") == r"[$1.00\times10^{-1}$, $\infty$]"
    assert latex.cell_text("a_b 5% & #1") == r"a\_b 5\% \& \#1"
    assert latex.cell_text("infeasible") == "infeasible"


def _cells() -> list[report.Cell]:
    def cell(a: str, values: list[float]) -> report.Cell:
        return report.Cell(a, "F1", 2, list(range(len(values))), values, [10] * len(values), 0.1)

    return [cell("A", [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]),
            cell("B", [1.5, 2.5, 3.5, 4.5, 5.5, 6.5]),
            cell("C", [30.0, 40.0, 50.0, 60.0, 70.0, 80.0])]


def test_benchmark_grid_bold_markers_and_effect_rows() -> None:
    cells = _cells()
    tests = report.statistics(cells, ["A", "B", "C"])
    grid = report.study_grid(cells, ["A", "B", "C"], tests=tests)
    labels = [row[2].text for row in grid.rows]
    assert labels == ["min", "max", "avg", "std", *tables.EFFECT_ROWS]
    avg = grid.rows[2][3:]
    # A is best; B does not differ from it (rank-sum, Holm): both bold; C is the reference
    assert [c.bold for c in avg] == [True, True, False]
    assert [c.marks for c in avg] == [tables.BEST_MARK, tables.SIMILAR_MARK, ""]
    assert [c.marker for c in avg] == ["+", "+", None]
    a12 = grid.rows[4][3:]
    assert [c.text for c in a12] == ["1.00", "1.00", ""]
    source = latex.grid_to_latex(grid, "caption", "tab:x")
    assert source.count(r"\boldmath") == 2
    assert r"\toprule" in source and r"\bottomrule" in source and r"\label{tab:x}" in source
    assert "$^{+}$" in source


def test_bench_format_latex_compiles(tmp_path: Path) -> None:
    result = runner.invoke(app, ["bench", "-a", "GWO,PSO", "-f", "F1,F5", "-d", "2", *SMALL,
                                 "--format", "latex", "--stat", "median"])
    assert result.exit_code == 0, result.stderr
    source = result.stdout
    assert source.startswith(r"\begin{table}") and r"\begin{tabular}" in source
    assert "5 runs, 6 agents, 8 iterations, seed 4" in source  # the setting
    assert "Wilcoxon rank-sum" in source and "Bayesian bootstrap of the median" in source
    assert " & median & " in source and " & iqr & " in source
    _compile(source, tmp_path)


def test_bad_format_stat_and_rope_are_refused() -> None:
    for args, option in ((["--format", "html"], "--format"), (["--stat", "mode"], "--stat"),
                         (["--rope", "abc"], "--rope")):
        result = runner.invoke(app, ["bench", "-a", "GWO", "-f", "F1", "-d", "2", *args])
        assert result.exit_code == 2 and option in result.stderr


def test_results_latex_of_benchmark_and_map_summaries_compiles(tmp_path: Path) -> None:
    import numpy as np

    from swarmpath.cli.results import summary_latex
    from swarmpath.evidence.stats import describe
    from swarmpath.service.summary_stats import benchmark_statistics, map_statistics

    rng = np.random.default_rng(0)
    rows, values = [], []
    for f in ("F1", "F8"):
        for a, shift in (("GWO", 0.0), ("PSO", 2.0), ("ICOOT", 1.0)):
            v = (rng.random(6) + shift).tolist()
            rows.append({"algorithm": a, "function": f, "dim": 2, "runs": 6, **describe(v)})
            values.append(v)
    doc = benchmark_statistics(rows, values, ["GWO", "PSO", "ICOOT"])
    source = summary_latex("j1", {"kind": "benchmark", "rows": rows, "statistics": doc,
                                  "partial": False})
    assert "swarmpath job j1 (benchmark): F1, F8 in 2 dimensions" in source
    assert source.count(r"\boldmath") >= 2 and " & A12 & " in source
    maps = []
    runs = []
    for p, length in (("ICOOT", 10.0), ("MFB", 11.0)):
        cell = [{"success": True, "length": length + 0.1 * i, "gap": 0.01 * i, "seconds": 1.0}
                for i in range(5)]
        maps.append({"planner": p, "map": "m1", "success_rate": 1.0, "length_mean": length,
                     "gap_mean": 0.02, "seconds_mean": 1.0, "runs": 5})
        runs.append(cell)
    mdoc = map_statistics(maps, runs, ["ICOOT", "MFB"])
    msource = summary_latex("j2", {"kind": "map", "rows": maps, "statistics": mdoc,
                                   "partial": True})
    assert "(map (partial)): m1" in msource and "100\\%$^{=}$" in msource
    assert "$^{+}$" in msource  # ICOOT's lengths are all shorter than MFB's
    _compile(source + msource, tmp_path)


def test_reproduce_format_latex_and_out_anytime(tmp_path: Path) -> None:
    """A narrowed benchmark table: its booktabs form compiles, and --out draws the anytime
    figure (runtime ECDF and ERT) beside the markdown and the ratio plot."""
    args = ["reproduce", "icoot-table2", "--runs", "2", "--algorithms", "PSO,ICOOT",
            "--functions", "F1", "--no-origin-check", "--jobs", "1"]
    result = runner.invoke(app, [*args, "--format", "latex", "--out", str(tmp_path / "out")])
    assert result.exit_code == 0, result.stderr
    source = result.stdout
    assert r"\begin{tabular}" in source and "Wilcoxon rank-sum" in source
    assert "icoot-table2" in source and " & PSO & " in source
    assert (tmp_path / "out" / "icoot-table2-anytime" / "anytime_F1_d30.png").stat().st_size > 0
    _compile(source, tmp_path)
