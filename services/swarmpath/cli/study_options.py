"""Options shared by the commands that run a benchmark study (bench, audit, reproduce): one
declaration each, so their names, help texts and defaults cannot drift apart."""

from __future__ import annotations

from typing import Annotated

import typer

AlgorithmsOpt = Annotated[
    str, typer.Option("--algorithms", "-a", help="Comma-separated names, or 'all'.")
]
FunctionsOpt = Annotated[
    str, typer.Option("--functions", "-f", help="Names and ranges: F1-F13, F1,F5,F6-floor.")
]
DimsOpt = Annotated[str, typer.Option("--dims", "-d", help="Comma-separated dimensions.")]
AgentsOpt = Annotated[int, typer.Option(help="Population size.")]
IterationsOpt = Annotated[int, typer.Option(help="Iterations per run.")]
SeedOpt = Annotated[int, typer.Option(help="Study seed; run r uses its own stream of it.")]
BackendOpt = Annotated[
    str,
    typer.Option(
        "--backend", metavar="numpy|numba",
        help="numpy: the reference; numba: compiled kernels giving the reference's numbers run "
        "for run (numba: the 'fast' extra); what has no kernel is refused.",
    ),
]
