"""``reproduce TABLE --add NAME``: a plugin optimizer measured beside a seed paper's table at
its setting. The table's rows, verdicts and statistics are those of the run without ``--add``;
the added cells are the runs a local ``bench`` gives at the same setting, with a marker against
the table's proposed algorithm; ``--from`` judges them again; bad uses exit 2 naming --add."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from test_service_e2e import ENV, PY

PLUGIN = textwrap.dedent('''
    from swarmpath.optimizers import register
    from swarmpath.optimizers.gwo import GWO


    @register
    class AddedGWO(GWO):
        """GWO with a steeper a-schedule (a test plugin)."""

        name = "AddedGWO"
        defaults = {**GWO.defaults, "a_max": 2.3}
''')
TABLE = ["icoot-table2", "-a", "COOT,ICOOT", "-f", "F1,F9", "--runs", "3", "--no-origin-check",
         "-j", "1"]


def cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([PY, "-m", "swarmpath.cli", *args], capture_output=True, text=True,
                          env=ENV, timeout=900)


@pytest.fixture(scope="module")
def plugin(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("added") / "added_gwo.py"
    path.write_text(PLUGIN)
    return path


@pytest.fixture(scope="module")
def added_doc(plugin) -> dict:
    out = cli("reproduce", *TABLE, "--add", "AddedGWO", "--json", "--plugin", str(plugin))
    assert out.returncode == 0, out.stderr
    return dict(json.loads(out.stdout))


def test_the_table_is_judged_as_without_add_and_the_added_runs_are_benchs(added_doc, plugin):
    plain = cli("reproduce", *TABLE, "--json")
    assert plain.returncode == 0, plain.stderr
    alone = json.loads(plain.stdout)
    assert added_doc["cells"] == alone["cells"] and added_doc["counts"] == alone["counts"]
    stats = dict(added_doc["statistics"])
    added = stats.pop("added")
    assert stats == alone["statistics"]  # the table's markers, ranks and curves unchanged
    assert added_doc["setting"]["added"] == ["AddedGWO"]
    assert added["reference"] == "ICOOT"
    assert [(c["algorithm"], c["function"]) for c in added["cells"]] == [
        ("AddedGWO", "F1"), ("AddedGWO", "F9")]
    bench = cli("bench", "-a", "AddedGWO", "-f", "F1,F9", "-d", "30", "--runs", "3", "--agents",
                "30", "--iterations", "500", "--seed", "1", "--json", "--plugin", str(plugin))
    assert bench.returncode == 0, bench.stderr
    runs = {c["function"]: c["best_fitness"] for c in json.loads(bench.stdout)["cells"]}
    for c in added["cells"]:
        assert c["runs"] == runs[c["function"]]  # the same runs, run for run
        assert c["marker"] in ("+", "=", "-")


def test_the_table_output_shows_the_added_cells(plugin):
    out = cli("reproduce", *TABLE, "--add", "AddedGWO", "--format", "markdown", "--plugin",
              str(plugin))
    assert out.returncode == 0, out.stderr
    assert "--add AddedGWO" in out.stdout  # the command line that made it
    assert "Added at the table's setting" in out.stdout
    assert "| F1 | AddedGWO |" in out.stdout and "| F9 | AddedGWO |" in out.stdout


def test_from_judges_the_added_cells_again(added_doc, plugin, tmp_path):
    saved = tmp_path / "saved.json"
    saved.write_text(json.dumps(added_doc))
    again = cli("reproduce", "--from", str(saved), "--json", "--plugin", str(plugin))
    assert again.returncode == 0, again.stderr
    doc = json.loads(again.stdout)
    assert doc["statistics"]["added"]["cells"] == added_doc["statistics"]["added"]["cells"]
    assert doc["cells"] == added_doc["cells"]


@pytest.mark.parametrize("args, says", [
    (["icoot-table2", "--add", "ICOOT"], "column of icoot-table2 already"),
    (["icoot-table2", "--add", "NoSuchGWO"], "NoSuchGWO"),
    (["icoot-maps", "--add", "GWO"], "map table"),
    (["icoot-table2", "--add", "GWO", "--format", "csv"], "--format csv"),
])
def test_bad_uses_exit_2_naming_add(args, says):
    out = cli("reproduce", *args)
    assert out.returncode == 2, out.stdout[-2000:]
    assert "--add:" in out.stderr and says in out.stderr, out.stderr
