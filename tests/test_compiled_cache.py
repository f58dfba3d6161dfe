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

_PROBE = """
import importlib, json, sys
from numba.core import config
from numba.core.dispatcher import Dispatcher
module = importlib.import_module(sys.argv[1])
from swarmpath.optimizers.compiled import versioned_cache_dir
paths = sorted({v._cache._cache_path for v in vars(module).values()
                if isinstance(v, Dispatcher) and v.__module__ == module.__name__
                and hasattr(v._cache, "_cache_path")})
print(json.dumps({"paths": paths, "config": config.CACHE_DIR, "versioned": versioned_cache_dir()}))
"""


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
def test_a_kernel_module_imported_first_caches_in_the_versioned_dir(name: str) -> None:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["PYTHONPATH"] = os.pathsep.join([str(PACKAGE.parent), env.get("PYTHONPATH", "")])
    out = subprocess.run(
        [sys.executable, "-c", _PROBE, name],
        env=env, capture_output=True, text=True, timeout=120, check=True,
    )
    seen = json.loads(out.stdout.strip().splitlines()[-1])
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
