"""``swarmpath check optimizer|function|planner NAME``: the conformance gate (swarmpath.testing)."""

from __future__ import annotations

import json
import sys
from typing import Annotated

import typer

from swarmpath.cli.core import CommandFailed, InputError, app

KINDS = ("optimizer", "function", "planner")


@app.command()
def check(
    kind: Annotated[str, typer.Argument(help="optimizer, function or planner.")],
    names: Annotated[list[str], typer.Argument(help="Registered names (built-in or plugin).")],
    processes: Annotated[
        bool, typer.Option("--processes/--no-processes",
                           help="Optimizers: also run in -j 2 children and a worker slot.")
    ] = True,
    bias: Annotated[
        bool, typer.Option("--bias/--no-bias", help="Optimizers: print the origin-bias figure.")
    ] = True,
    as_json: Annotated[bool, typer.Option("--json", help="One JSON document.")] = False,
) -> None:
    """Check that an extension keeps swarmpath's contract before it is compared: for an
    optimizer reproducibility (alone, in a batch, in another process, in a worker slot), no
    hidden random state, budget honesty, bounds and parameter errors, with its origin-bias
    figure as information; for a function its shape, values, determinism and minimum; for a
    planner the episode contract. Exit 0 when every property holds, 1 naming each that fails."""
    from swarmpath.testing import check_function, check_planner
    from swarmpath.testing.optimizer import check_optimizers

    if kind not in KINDS:
        raise InputError("KIND", f"must be one of {', '.join(KINDS)}, got {kind!r}")
    try:
        if kind == "optimizer":
            from swarmpath.optimizers import get_optimizer

            for name in names:
                get_optimizer(name)
            reports = check_optimizers(names, processes=processes, bias=bias,
                                       raise_on_failure=False)
        elif kind == "function":
            reports = [check_function(name, raise_on_failure=False) for name in names]
        else:
            reports = [check_planner(name, raise_on_failure=False) for name in names]
    except (KeyError, ValueError) as exc:
        raise InputError("NAME", str(exc.args[0] if exc.args else exc)) from None
    if not as_json:
        for report in reports:
            typer.echo(f"{kind} {report.name}:")
            for line in report.lines():
                typer.echo(f"  {line}")
    if as_json:
        sys.stdout.write(json.dumps([r.to_dict() for r in reports]) + "\n")
    failing = [f"{r.name} ({', '.join(p.name for p in r.failures)})" for r in reports if not r.ok]
    if failing:
        raise CommandFailed(f"{kind} {'; '.join(failing)} fails the conformance check")
