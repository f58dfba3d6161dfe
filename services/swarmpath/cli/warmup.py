"""``swarmpath warmup``: compile the numba kernels once (after an install, before a farm starts),
so that no study pays for it at its first run."""

from __future__ import annotations

import fcntl
import json
import os
import re
import shutil
import sys
from pathlib import Path
from typing import Annotated

import typer

from swarmpath.cli.core import InputError, app


@app.command()
def warmup(
    algorithms: Annotated[
        str | None, typer.Option("--algorithms", "-a",
                                 help="Comma-separated algorithms (default: every one with a "
                                 "kernel).")
    ] = None,
    functions: Annotated[
        str | None, typer.Option("--functions", "-f",
                                 help="Functions or ranges (default: every one with a compiled "
                                 "objective).")
    ] = None,
    suites: Annotated[
        bool, typer.Option("--suites/--no-suites", help="Without --functions: also the "
                           "suites' objectives (BBOB, CEC; --no-suites: the built-in functions "
                           "only, a suite's objective then compiles at the first study that "
                           "runs it, about 1-4 s of CPU each).")
    ] = True,
    if_cold: Annotated[
        bool, typer.Option("--if-cold", help="Only the pieces this tree's cache lacks (none when "
                           "a warm-up or a study made them since the compiled sources last "
                           "changed): scripts/_venv.sh runs --if-cold --no-suites after an "
                           "install.")
    ] = False,
    jobs: Annotated[
        int, typer.Option("--jobs", "-j", min=1, help="Processes compiling at once, each piece "
                          "by one of them (scripts/_venv.sh: 2).")
    ] = 1,
    prune: Annotated[
        bool, typer.Option("--prune", help="First remove the other trees' numba cache "
                           "directories beside this tree's (swarmpath-<hash>: one per version of "
                           "the compiled sources; in use ones kept). --if-cold does it by itself "
                           "in the package's own __pycache__ (without NUMBA_CACHE_DIR, which "
                           "other trees may share).")
    ] = False,
    as_json: Annotated[bool, typer.Option("--json", help="One JSON document.")] = False,
) -> None:
    """Compile (or load from numba's cache) the compiled kernels and objectives that backend
    "auto" and "numba" run (without --algorithms and --functions also the clearance and sensing
    kernels every map run calls), and print the CPU seconds each took: a fresh environment's first
    study then starts without compiling. The cache is per installed tree and shared by every
    process of it (workers' slots included). With --if-cold only what the cache lacks: nothing
    (and no output) when it is filled."""
    from swarmpath.functions import expand_function_names
    from swarmpath.optimizers.compiled.warm import (
        algorithms_with_kernels,
        cold,
        functions_with_objectives,
        pieces,
        warm_in_processes,
    )

    try:
        algos = algorithms_with_kernels(
            None if algorithms is None else [a.strip() for a in algorithms.split(",") if a.strip()])
    except KeyError as exc:
        raise InputError("--algorithms", str(exc.args[0] if exc.args else exc)) from None
    try:
        names = functions_with_objectives(
            None if functions is None else expand_function_names(functions))
    except (KeyError, ValueError) as exc:
        raise InputError("--functions", str(exc.args[0] if exc.args else exc)) from None
    if functions is None and not suites:
        names = [n for n in names if ":" not in n]  # a suite's functions are "suite:name"
    if prune or (if_cold and not os.environ.get("NUMBA_CACHE_DIR")):
        from numba.core import config

        removed = prune_cache_dirs(str(config.CACHE_DIR))  # type: ignore[attr-defined]
        if removed and not as_json:
            typer.echo(f"swarmpath warmup: removed {len(removed)} cache directories of other "
                       f"versions of the compiled sources ({sum(removed.values()) / 1e6:.0f} MB)",
                       err=True)
    # the map runs' kernels with a warm-up of everything (not with a list of pieces)
    maps = algorithms is None and functions is None
    if if_cold and not as_json:
        missing = cold(pieces(algos, names, maps))
        if not missing:
            return
        typer.echo(f"swarmpath warmup: compiling the {len(missing)} pieces (numba kernels, "
                   "objectives) this tree's cache lacks, once per installed tree (seconds of CPU "
                   "each)", err=True)
    done = warm_in_processes(algos, names, jobs=jobs, maps=maps, cold_only=if_cold)
    if as_json:
        sys.stdout.write(json.dumps([{"kind": w.kind, "name": w.name, "cpu_seconds": w.seconds}
                                     for w in done]) + "\n")
        return
    if if_cold:  # the install's warm-up: one line
        typer.echo(f"swarmpath warmup: compiled {len(done)} pieces in "
                   f"{sum(w.seconds for w in done):.0f} s of CPU", err=True)
        return
    for w in done:
        typer.echo(f"{w.kind:9} {w.name:10} {w.seconds:7.2f} s CPU")
    typer.echo(f"{'total':20} {sum(w.seconds for w in done):7.2f} s CPU")


def prune_cache_dirs(current: str) -> dict[str, int]:
    """Remove the directories beside ``current`` (this tree's numba cache directory,
    ``versioned_cache_dir``) that another version of the compiled sources made
    (``swarmpath-<16 hex digits>``), except those in use (a warm-up's or a background compile's
    lock held in them); returns the bytes each removed one held. Every edit of the compiled
    sources makes a new one (a full cache is about 100 MB), and nothing else removes them."""
    here = Path(current)
    removed: dict[str, int] = {}
    if not here.parent.is_dir():
        return removed
    for old in sorted(here.parent.iterdir()):
        if (old.name == here.name or not old.is_dir()
                or not re.fullmatch(r"swarmpath-[0-9a-f]{16}", old.name) or _in_use(old)):
            continue
        size = sum(f.stat().st_size for f in old.rglob("*") if f.is_file())
        shutil.rmtree(old, ignore_errors=True)
        if not old.exists():
            removed[old.name] = size
    return removed


def _in_use(directory: Path) -> bool:
    """Whether a process holds one of the warm-up's locks in ``directory``."""
    for lock in directory.glob(".warm-*.lock"):
        try:
            fd = os.open(lock, os.O_RDWR)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return True
        finally:
            os.close(fd)
    return False
