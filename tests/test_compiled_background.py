"""Backend "auto" on a cold cache (:mod:`swarmpath.optimizers.compiled.ready`): the numpy
reference runs the pieces not compiled yet, with the numbers of the compiled path bit for bit,
and a background process compiles them so that the next process loads them.

No timing is asserted: which backend ran is each Result's (and each bench cell's) record, what
compiled is read from numba's counters and the warm-up's markers.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("numba")

from swarmpath.optimizers import minimize_many
from swarmpath.optimizers.compiled import ready
from swarmpath.world import clearance


@pytest.fixture
def go_cold(monkeypatch, tmp_path):
    """Makes this process see an empty cache directory for the markers (the kernels it loaded
    stay loaded: only whether auto may run them is at stake) with no memory of ready pieces;
    no background compile is started, each request recorded instead (the list returned).
    Called after the compiled runs a test needs, which then load from the tree's cache."""
    from numba.core import config

    asked: list[list[tuple[str, str]]] = []

    def go() -> list[list[tuple[str, str]]]:
        monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path))
        for name, value in (("_READY", set()), ("_REQUESTED", set()), ("_STAMP", []),
                            ("_WRITABLE", [])):
            monkeypatch.setattr(ready, name, value)
        monkeypatch.setattr(ready, "request", lambda wanted: asked.append(list(wanted)))
        monkeypatch.setattr(clearance, "_READY", [False, 0.0])
        return asked

    return go


FIELDS = ("best_fitness", "best_position", "curve", "evaluations", "shifts")


def test_auto_runs_the_reference_for_a_cold_piece_with_the_compiled_numbers(go_cold):
    functions = ["F1", "F9", "bbob:f3@i2"]
    kw = dict(dim=3, agents=6, iterations=5, run_ids=[1, 0], seed=7)
    compiled = minimize_many("GWO", functions, backend="numba", **kw)
    asked = go_cold()
    auto = minimize_many("GWO", functions, **kw)
    assert {r.backend for r in compiled} == {"numba"} and {r.backend for r in auto} == {"numpy"}
    for a, b in zip(compiled, auto, strict=True):
        for field in FIELDS:
            assert np.array_equal(getattr(a, field), getattr(b, field)), (a.function, field)
    wanted = [("function", "F1"), ("function", "F9"), ("function", "bbob:f3"),
              ("algorithm", "GWO")]
    assert asked == [wanted]  # asked for in the background (an instance by its base's name)
    ready.made_ready(wanted[:-1])  # the objectives without the kernel: still the reference
    assert {r.backend for r in minimize_many("GWO", functions, **kw)} == {"numpy"}
    ready.made_ready(wanted[-1:])
    assert {r.backend for r in minimize_many("GWO", functions, **kw)} == {"numba"}


def test_a_marker_written_by_another_process_makes_auto_run_compiled(go_cold):
    from swarmpath.optimizers.compiled import warm

    kw = dict(dim=2, agents=6, iterations=3, runs=1, seed=1)
    minimize_many("SSA", ["F4"], backend="numba", **kw)
    go_cold()
    assert minimize_many("SSA", ["F4"], **kw)[0].backend == "numpy"
    for piece in (("function", "F4"), ("algorithm", "SSA")):
        warm._mark(*piece, warm._source_stamp())  # what the background process writes
    assert minimize_many("SSA", ["F4"], **kw)[0].backend == "numba"


def test_the_map_kernels_wait_for_their_piece(go_cold):
    asked = go_cold()
    assert clearance.resolve("auto") == "numpy" and asked == [[ready.MAP_PIECE]]
    assert clearance.resolve("numba") == "numba"  # as asked: compiled on demand
    ready.made_ready([ready.MAP_PIECE])
    clearance._READY[1] = 0.0  # two seconds later
    assert clearance.resolve("auto") == "numba"


def _run(cache: Path, code: str, *args: str) -> str:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "SWARMPATH_BACKGROUND_COMPILE": "1",
           "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
    out = subprocess.run([sys.executable, "-c", code, *args], env=env, capture_output=True,
                         text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-3000:]
    return out.stdout.splitlines()[-1]


#: a tiny auto run; waits for the background compile it started (if any), then reports which
#: backend ran and what numba compiled or loaded in this process
PROBE = """
import gc, json
from numba.core.dispatcher import Dispatcher
from swarmpath.optimizers import minimize
from swarmpath.optimizers.compiled import ready
res = minimize("SSA", "F4", dim=2, agents=10, iterations=3, runs=2)
codes = [child.wait() for child in ready._CHILDREN]
found = [o for o in gc.get_objects() if isinstance(o, Dispatcher)]
print(json.dumps({"backend": res.backend, "children": codes, "best": res.best_fitness.tolist(),
                  "compiled": sum(sum(d.stats.cache_misses.values()) for d in found),
                  "loaded": sum(sum(d.stats.cache_hits.values()) for d in found)}))
"""


def test_the_background_compile_fills_the_cache_the_next_process_loads(tmp_path):
    first = json.loads(_run(tmp_path, PROBE))
    assert first["backend"] == "numpy" and first["children"] == [0], first
    assert first["compiled"] == 0  # nothing compiled in the study's process
    later = json.loads(_run(tmp_path, PROBE))
    assert later["backend"] == "numba" and later["children"] == [], later
    assert later["compiled"] == 0 and later["loaded"] > 0, later
    assert later["best"] == first["best"]  # the same numbers
    log = next(tmp_path.glob("swarmpath-*/.warm-background.log")).read_text()
    assert "compiled 2 of 2 pieces" in log, log
