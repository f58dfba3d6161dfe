"""numba's on-disk cache: every module with cached kernels uses the versioned directory.

numba picks a kernel's cache directory when its ``@njit`` runs; a module imported before
``swarmpath.optimizers.compiled`` had its kernels cached next to its own file, keyed on that
file only (stale kernels after an edit of a file they call into). The modules are found by
scanning the package for ``@njit(cache=True`` (no hand list); nothing is compiled here.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("numba")

import swarmpath

PACKAGE = Path(swarmpath.__file__).resolve().parent
CACHED = re.compile(r"^@njit\(\s*cache\s*=\s*True", re.MULTILINE)


def _cached_kernel_modules() -> list[str]:
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if CACHED.search(path.read_text()):
            parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
            found.append(".".join(p for p in parts if p != "__init__"))
    return found


MODULES = _cached_kernel_modules()

#: for each module named: a child forked from a process that has imported numba but no swarmpath
#: module (a fresh interpreter per module cost 0.6-1 s of CPU, mostly numpy's and numba's own
#: import) imports it first, then reports the cache paths of its kernels
_PROBE = """
import importlib, json, os, sys
from numba.core import config
from numba.core.dispatcher import Dispatcher

def probe(name):
    first = not any(m == "swarmpath" or m.startswith("swarmpath.") for m in sys.modules)
    module = importlib.import_module(name)
    from swarmpath.optimizers.compiled import versioned_cache_dir
    paths = sorted({v._cache._cache_path for v in vars(module).values()
                    if isinstance(v, Dispatcher) and v.__module__ == module.__name__
                    and hasattr(v._cache, "_cache_path")})
    return {"first": first, "paths": paths, "config": config.CACHE_DIR,
            "versioned": versioned_cache_dir()}

seen = {}
for name in sys.argv[1:]:
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(r)
        try:
            os.write(w, json.dumps(probe(name)).encode())
        finally:
            os._exit(0)
    os.close(w)
    with os.fdopen(r, "rb") as pipe:
        out = pipe.read()
    os.waitpid(pid, 0)
    seen[name] = json.loads(out) if out else {"error": "the child reported nothing"}
print(json.dumps(seen))
"""


@pytest.fixture(scope="module")
def first_imports() -> dict[str, dict]:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["PYTHONPATH"] = os.pathsep.join([str(PACKAGE.parent), env.get("PYTHONPATH", "")])
    out = subprocess.run(
        [sys.executable, "-c", _PROBE, *MODULES],
        env=env, capture_output=True, text=True, timeout=300, check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_the_scan_finds_the_kernel_modules() -> None:
    assert "swarmpath.planners.compiled" in MODULES
    assert "swarmpath.optimizers.compiled.coot" in MODULES
    assert "swarmpath.world.optimum_compiled" in MODULES


def test_every_kernel_module_is_hashed_into_the_cache_dir() -> None:
    from swarmpath.optimizers.compiled import compiled_sources

    hashed = {path.resolve() for path in compiled_sources()}
    for name in MODULES:
        path = PACKAGE.parent.joinpath(*name.split(".")).with_suffix(".py")
        assert path.resolve() in hashed, name


@pytest.mark.parametrize("name", MODULES)
def test_a_kernel_module_imported_first_caches_in_the_versioned_dir(
        name: str, first_imports: dict[str, dict]) -> None:
    seen = first_imports[name]
    assert seen.get("first"), (name, seen)  # no swarmpath module was imported before it
    assert seen["config"] == seen["versioned"]
    assert seen["paths"], f"{name}: no cached kernel found"
    for path in seen["paths"]:
        # numba appends the source's folder to CACHE_DIR: the versioned dir is a prefix
        assert path.startswith(seen["versioned"]), (name, path)


def test_no_cached_kernel_calls_itself() -> None:
    """A recursive ``@njit(cache=True)`` function compiles, but loaded from the cache in the
    next process it crashes (an unresolved symbol of itself; numba 0.6x): MFB's mean loudness
    did, so recursion is written with explicit stacks (``functions.pairwise_sum``)."""
    import ast

    recursive = []
    for name in MODULES:
        path = PACKAGE.parent.joinpath(*name.split(".")).with_suffix(".py")
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef) and any(
                    "njit" in ast.unparse(d) for d in node.decorator_list):
                calls = {c.func.id for c in ast.walk(node)
                         if isinstance(c, ast.Call) and isinstance(c.func, ast.Name)}
                if node.name in calls:
                    recursive.append(f"{name}.{node.name}")
    assert not recursive
