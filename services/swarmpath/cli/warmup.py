"""``swarmpath warmup``: compile the numba kernels once (after an install, before a farm starts),
so that no study pays for it at its first run."""

from __future__ import annotations

import json
import sys
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
    as_json: Annotated[bool, typer.Option("--json", help="One JSON document.")] = False,
) -> None:
    """Compile (or load from numba's cache) the compiled kernels and objectives that backend
    "auto" and "numba" run (without --algorithms and --functions also the clearance and sensing
    kernels every map run calls), and print the CPU seconds each took: a fresh environment's first
    study then starts without compiling. The cache is per installed tree and shared by every
    process of it (workers' slots included)."""
    from swarmpath.functions import expand_function_names
    from swarmpath.optimizers.compiled.warm import (
        algorithms_with_kernels,
        functions_with_objectives,
        warm,
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
    # the map runs' kernels with a warm-up of everything (not with a list of pieces)
    done = warm(algos, names, maps=algorithms is None and functions is None)
    if as_json:
        sys.stdout.write(json.dumps([{"kind": w.kind, "name": w.name, "cpu_seconds": w.seconds}
                                     for w in done]) + "\n")
        return
    for w in done:
        typer.echo(f"{w.kind:9} {w.name:10} {w.seconds:7.2f} s CPU")
    typer.echo(f"{'total':20} {sum(w.seconds for w in done):7.2f} s CPU")
