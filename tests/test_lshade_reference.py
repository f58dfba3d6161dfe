"""The L-SHADE reference table (scripts/evidence/lshade_reference.py): the script turns what the
reference executable prints into a table the loader reads, refuses output it did not ask for,
and the checked-in table's statistics are those of the runs it keeps."""

from __future__ import annotations

import math
import stat
import subprocess
import sys
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
import yaml

from swarmpath.evidence import reference

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "scripts" / "evidence" / "lshade_reference.py"
TABLE = "lshade-reference-cec2017-d10"


def fake_exe(tmp_path: Path, line: str) -> Path:
    """An executable with the reference's command line, printing ``line`` formatted per run
    (f, d, r, seed are the arguments and the run; the error is made up)."""
    exe = tmp_path / "fake_lshade"
    exe.write_text(
        f"#!{sys.executable}\n"
        "import sys\n"
        "f, d, runs, seed = map(int, sys.argv[1:5])\n"
        "for r in range(runs):\n"
        f"    print({line!r}.format(f=f, d=d, r=r, s=seed + r, e=f * 10.0 ** -r))\n")
    exe.chmod(exe.stat().st_mode | stat.S_IXUSR)
    (tmp_path / "input_data").mkdir()
    return exe


def run_script(exe: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(SCRIPT), str(exe), str(exe.parent), *args],
                          capture_output=True, text=True)


def test_the_printed_runs_become_a_table_the_loader_reads(tmp_path):
    exe = fake_exe(tmp_path, "{f} {d} {r} {s} {e:.17e}")
    done = run_script(exe, "--runs", "4", "--functions", "3,5-6", "--seed", "7")
    assert done.returncode == 0, done.stderr
    doc = yaml.safe_load(done.stdout)
    table = reference._benchmark(TABLE, doc)
    assert table.functions == ("cec2017:F3", "cec2017:F5", "cec2017:F6")
    assert table.setting["runs"] == 4 and table.setting["dims"] == [10]
    runs = np.array([5 * 10.0 ** -r for r in range(4)])
    cell = table.cells[("cec2017:F5", "L-SHADE")]
    assert cell["avg"] == pytest.approx(runs.mean(), rel=1e-4)
    assert cell["std"] == pytest.approx(runs.std(ddof=1), rel=1e-4)
    assert (cell["min"], cell["max"]) == (pytest.approx(5e-3, rel=1e-4), 5.0)
    assert doc["reference_runs"]["cec2017:F6"] == pytest.approx([6 * 10.0 ** -r
                                                                 for r in range(4)], rel=1e-6)
    assert "--seed 7 --functions 3,5-6" in done.stdout.splitlines()[0]


@pytest.mark.parametrize("line", [
    "{f} {d} {r} {r} {e:.17e}",          # the seed of run r is not SEED + r
    "{f} 30 {r} {s} {e:.17e}",           # another dimension
])
def test_output_the_script_did_not_ask_for_is_refused(tmp_path, line):
    done = run_script(fake_exe(tmp_path, line), "--runs", "3", "--functions", "2")
    assert done.returncode != 0
    assert "unexpected line" in done.stderr


def test_a_workdir_without_the_organisers_data_is_refused(tmp_path):
    exe = fake_exe(tmp_path, "{f} {d} {r} {s} {e:.17e}")
    (tmp_path / "input_data").rmdir()
    done = run_script(exe, "--runs", "3")
    assert done.returncode == 2 and "input_data" in done.stderr


def test_the_checked_in_table_is_the_statistics_of_its_runs():
    text = resources.files("swarmpath.evidence.reference").joinpath(f"{TABLE}.yaml").read_text()
    doc = yaml.safe_load(text)
    table = reference.load(TABLE)
    assert set(doc["reference_runs"]) == set(table.functions)
    for function in table.functions:
        runs = np.array(doc["reference_runs"][function])
        assert len(runs) == table.setting["runs"] == 51
        cell = table.cells[(function, "L-SHADE")]
        expected = {"min": runs.min(), "max": runs.max(), "avg": runs.mean(),
                    "std": runs.std(ddof=1)}
        for s, v in expected.items():
            assert math.isclose(cell[s], v, rel_tol=1e-3, abs_tol=1e-12), (function, s)
        # the reference reports errors below 1e-8 as 0 (the competition's rule)
        assert not np.any((runs > 0) & (runs < 1e-8)), function
