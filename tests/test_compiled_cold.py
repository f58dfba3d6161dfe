"""A fresh environment's first study does not compile: ``swarmpath warmup --if-cold`` (what
scripts/_venv.sh runs after an install) fills the tree's numba cache, a later process loads
every kernel from it, ``bench --backend numba`` compiles only what the cache lacks, in the
parent, after one line that says so (backend auto compiles nothing in the study:
tests/test_compiled_background.py), and ``warmup --prune`` removes other versions' caches.

Each test runs the CLI in subprocesses on a numba cache of its own (``NUMBA_CACHE_DIR``), so
"cold" is really cold; the kernels are the cheap ones (SSA, GWO, F4). No timing is asserted:
whether something compiled is read from numba's own counters (a dispatcher's cache misses, a
cfunc's cache hits) and from the warm-up's markers.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("numba")

HINT = "compiling the numba kernels this study needs"

#: a run of an algorithm on a function with the kernels, then numba's counters of every
#: dispatcher and of the function's cfunc: what compiled in this process and what was loaded
PROBE = """
import gc, json, sys
from numba.core.dispatcher import Dispatcher
from swarmpath.optimizers import minimize
from swarmpath.optimizers.compiled import objectives
minimize(sys.argv[1], sys.argv[2], dim=3, agents=10, iterations=3, runs=2, backend="numba")
found = [o for o in gc.get_objects() if isinstance(o, Dispatcher)]
print(json.dumps({
    "compiled": sorted(f"{d.py_func.__module__}.{d.py_func.__qualname__}" for d in found
                       if sum(d.stats.cache_misses.values())),
    "loaded": sum(sum(d.stats.cache_hits.values()) for d in found),
    "cfuncs": [c.cache_hits for c in objectives._COMPILED.values()],  # each loaded or not
}))
"""


def run(cache: Path, *args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache),
           "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
    out = subprocess.run([sys.executable, *args], env=env, capture_output=True, text=True,
                         timeout=900)
    assert out.returncode == 0, out.stderr[-3000:]
    return out


def cli(cache: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return run(cache, "-m", "swarmpath.cli", *args)


def test_the_install_warm_up_fills_the_cache_that_later_processes_load(tmp_path):
    first = cli(tmp_path, "warmup", "--if-cold", "-a", "SSA", "-f", "F4", "-j", "2")  # _venv.sh's
    assert "compiling the 2 pieces" in first.stderr and "compiled 2 pieces" in first.stderr
    # a later process runs the kernel: nothing compiles, the kernel and objective are loaded
    probe = json.loads(run(tmp_path, "-c", PROBE, "SSA", "F4").stdout.splitlines()[-1])
    assert probe["compiled"] == [] and probe["loaded"] > 0, probe
    assert probe["cfuncs"] and all(hits > 0 for hits in probe["cfuncs"]), probe
    # the install's warm-up again (a refresh of .venv): nothing to do, nothing printed
    again = cli(tmp_path, "warmup", "--if-cold", "-a", "SSA", "-f", "F4")
    assert again.stdout == "" and again.stderr == ""
    # a study's first run on backend numba compiles only what the cache lacks (GWO), in one
    # line that says so (backend auto runs numpy meanwhile: tests/test_compiled_background.py)
    study = ("bench", "-a", "SSA,GWO", "-f", "F4", "-d", "2", "--runs", "1", "--agents", "10",
             "--iterations", "2", "-j", "1", "--backend", "numba")
    hints = [line for line in cli(tmp_path, *study).stderr.splitlines() if HINT in line]
    assert len(hints) == 1 and "GWO" in hints[0] and "SSA" not in hints[0], hints
    assert HINT not in cli(tmp_path, *study).stderr  # the first run marked what it compiled
    probe = json.loads(run(tmp_path, "-c", PROBE, "GWO", "F4").stdout.splitlines()[-1])
    assert probe["compiled"] == [] and probe["loaded"] > 0, probe


def test_a_piece_is_cold_again_once_the_compiled_sources_change(monkeypatch, tmp_path):
    """numba compiles a kernel again when its source's time stamp changed: so do the markers."""
    from numba.core import config

    from swarmpath.optimizers.compiled import warm as warm_module

    wanted = [("function", "F4"), ("algorithm", "SSA")]
    warm_module.warm(["SSA"], ["F4"])  # in this process's cache (loaded when it is filled)
    assert warm_module.cold(wanted) == []
    # the markers below in a directory of their own: a stale stamp left in the tree's cache
    # would make backend auto run the reference for these pieces in other tests' processes
    monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path))
    assert warm_module.cold(wanted) == wanted
    warm_module.warm(["SSA"], ["F4"])  # loaded in this process already: marked there
    assert warm_module.cold(wanted) == []
    monkeypatch.setattr(warm_module, "_source_stamp", lambda: "the sources after an edit")
    assert warm_module.cold(wanted) == wanted
    done = warm_module.warm(["SSA"], ["F4"], cold_only=True)
    assert [(w.kind, w.name) for w in done] == wanted and warm_module.cold(wanted) == []
    assert warm_module.warm(["SSA"], ["F4"], cold_only=True) == []


def test_the_install_warm_up_leaves_the_suites_to_their_first_study(monkeypatch, tmp_path):
    """scripts/_venv.sh runs ``warmup --if-cold --no-suites``: every kernel, the built-in
    functions' objectives and the map kernels, not the 60-odd BBOB and CEC objectives (a suite
    study compiles the ones it runs); a plain ``warmup`` makes every piece."""
    from typer.testing import CliRunner

    from swarmpath.cli import app
    from swarmpath.optimizers.compiled import kernel_names
    from swarmpath.optimizers.compiled import warm as warm_module

    asked: list[tuple[list[str], list[str], bool, bool]] = []

    def record(algorithms, functions, *, maps=None, cold_only=False, **_kw):
        asked.append((list(algorithms), list(functions), maps, cold_only))
        return []

    monkeypatch.setattr(warm_module, "warm", record)
    monkeypatch.setattr(warm_module, "cold", lambda wanted: list(wanted))
    # a cache of its own: --if-cold in the package's __pycache__ would prune this tree's others
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    line = Path(__file__).parents[1].joinpath("scripts", "_venv.sh").read_text()
    assert "swarmpath warmup --if-cold --no-suites" in line
    for args in (["--if-cold", "--no-suites"], []):
        out = CliRunner().invoke(app, ["warmup", *args])
        assert out.exit_code == 0, out.output
    (algos, builtin, maps, cold_only), (_, everything, _, plain) = asked
    assert algos == kernel_names() and maps and cold_only and not plain
    assert "F1" in builtin and "F13" in builtin and not any(":" in n for n in builtin)
    assert set(builtin) < set(everything) and "bbob:f1" in everything


#: compiles (or loads) the objectives named on the command line, then each cfunc's cache hits
OBJECTIVES = """
import json, sys
from swarmpath.functions import get_function
from swarmpath.optimizers.compiled.objectives import _compiled
print(json.dumps({name: _compiled(get_function(name)).cache_hits for name in sys.argv[1:]}))
"""


def test_a_suite_objective_is_loaded_from_the_cache_by_a_later_process(tmp_path):
    """A BBOB objective (one code for the 24 functions, each calling its own raw function)
    compiled in one process is loaded by the next, like the built-ins' and the CEC ones (its
    raw function was a closure cell, which numba's cache key pickles with a random id: every
    process compiled it again, and a slot's warm-up spent most of its time on it)."""
    names = ["bbob:f1", "bbob:f2", "F4"]
    first = json.loads(run(tmp_path, "-c", OBJECTIVES, *names).stdout.splitlines()[-1])
    assert first == dict.fromkeys(names, 0), first  # a cold cache: compiled here
    later = json.loads(run(tmp_path, "-c", OBJECTIVES, *names).stdout.splitlines()[-1])
    assert all(hits > 0 for hits in later.values()), later


def test_no_registered_objective_is_a_closure():
    """numba's cache keys a closure by its cells pickled; a compiled function among them
    pickles differently in every process, so such an objective never loads from the cache.
    Every registered objective (built-ins, suites) is a plain function."""
    from swarmpath.optimizers.compiled import objectives

    objectives.compiled_names()  # registers the suites' objectives
    closures = [name for name, population in objectives._POPULATIONS.items()
                if population.__closure__]
    assert closures == [], closures


def test_warmup_prune_removes_the_cache_directories_of_other_versions_only(tmp_path, monkeypatch):
    """Each version of the compiled sources caches in a directory of its own; ``--prune`` (and
    ``--if-cold`` in the package's own __pycache__) removes the others, not one in use (a
    warm-up's lock held), nor anything else there."""
    import fcntl

    from numba.core import config
    from typer.testing import CliRunner

    from swarmpath.cli import app
    from swarmpath.optimizers.compiled import warm as warm_module

    current, old, busy, other = (tmp_path / name for name in (
        "swarmpath-0123456789abcdef", "swarmpath-aaaaaaaaaaaaaaaa", "swarmpath-bbbbbbbbbbbbbbbb",
        "notes"))
    for directory in (current, busy, other):
        directory.mkdir()
    monkeypatch.setattr(config, "CACHE_DIR", str(current))
    monkeypatch.setattr(warm_module, "warm_in_processes", lambda *_a, **_kw: [])
    monkeypatch.setattr(warm_module, "cold", lambda wanted: [])  # nothing to compile
    fd = os.open(busy / ".warm-function-F1.lock", os.O_RDWR | os.O_CREAT)
    fcntl.flock(fd, fcntl.LOCK_EX)  # a warm-up of that version is running
    try:
        for args, env, removed in ((["--prune", "-a", "SSA", "-f", "F4"], "/elsewhere", True),
                                   (["--if-cold"], None, True),  # the package's __pycache__
                                   (["--if-cold"], "/elsewhere", False)):  # maybe shared
            old.mkdir()
            (old / "kernel.nbc").write_bytes(b"x" * 2_000_000)
            if env is None:
                monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
            else:
                monkeypatch.setenv("NUMBA_CACHE_DIR", env)
            out = CliRunner().invoke(app, ["warmup", *args])
            assert out.exit_code == 0, out.output
            assert old.exists() is not removed, args
            assert ("removed 1 cache directories" in out.stderr) is removed, out.stderr
            assert current.is_dir() and busy.is_dir() and other.is_dir()
            if not removed:
                (old / "kernel.nbc").unlink()
                old.rmdir()
    finally:
        os.close(fd)
