"""The suite rankings (swarmpath.evidence.rankings, scripts/evidence/rankings.py) against ranks
computed by hand from a real bench document."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import rankdata
from typer.testing import CliRunner

from swarmpath.cli import app
from swarmpath.evidence.rankings import SOLVED, rank_study, ranking_markdown

ROOT = Path(__file__).resolve().parents[1]
ALGOS = ["RS", "CMA-ES", "GWO"]


@pytest.fixture(scope="module")
def doc() -> dict:
    out = CliRunner().invoke(app, ["bench", "-a", ",".join(ALGOS), "-f", "bbob:f1,bbob:f2",
                                   "--instances", "1-2", "-d", "2,3", "--runs", "2",
                                   "--budget-evals", "200xD", "-j", "1", "--json"])
    assert out.exit_code == 0, out.output
    return json.loads(out.stdout)


def test_mean_ranks_counts_and_medians_are_those_of_the_cells(doc):
    rankings = rank_study(doc)
    assert [r.dim for r in rankings] == [2, 3]
    for ranking in rankings:
        cells = [c for c in doc["cells"] if c["dim"] == ranking.dim]
        blocks = sorted({c["function"] for c in cells})
        assert ranking.blocks == len(blocks) == 4
        means = np.array([[next(c["stats"]["avg"] for c in cells
                                if c["function"] == f and c["algorithm"] == a) for a in ALGOS]
                          for f in blocks])
        by_hand = rankdata(means, axis=1).mean(axis=0)
        rows = {r.algorithm: r for r in ranking.rows}
        for j, a in enumerate(ALGOS):
            assert rows[a].mean_rank == pytest.approx(by_hand[j])
            assert rows[a].best_in == int(np.sum(means[:, j] == means.min(axis=1)))
            assert rows[a].solved == int(np.sum(means[:, j] <= SOLVED))
            assert rows[a].median_error == pytest.approx(float(np.median(means[:, j])))
        assert [r.mean_rank for r in ranking.rows] == sorted(r.mean_rank for r in ranking.rows)
        assert rows["RS"].mean_rank > rows["CMA-ES"].mean_rank  # 400-600 points vs a search
        table = ranking_markdown(ranking)
        assert table[2].startswith("| 1 | ") and "(baseline)" in "\n".join(table)
        assert f"over {ranking.blocks} function-instance cells" in table[-1]


def test_the_script_names_the_bench_command_of_each_document(doc, tmp_path):
    path = tmp_path / "bbob.json"
    path.write_text(json.dumps(doc))
    out = subprocess.run([sys.executable, str(ROOT / "scripts/evidence/rankings.py"), str(path)],
                         capture_output=True, text=True, check=True,
                         env={"PYTHONPATH": str(ROOT / "services")})
    assert "## bbob, D = 2" in out.stdout and "## bbob, D = 3" in out.stdout
    assert ("`swarmpath bench -a RS,CMA-ES,GWO -f bbob -d 2,3 --instances 1-2 --runs 2 "
            "--budget-evals 200xD --seed 1 --json`") in out.stdout
    assert out.stdout.count("| 1 | ") == 2
