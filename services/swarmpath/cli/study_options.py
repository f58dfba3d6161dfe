"""Options shared by the commands that run a benchmark study (bench, audit, reproduce): one
declaration each, so their names, help texts and defaults cannot drift apart."""

from __future__ import annotations

from typing import Annotated

import typer

AlgorithmsOpt = Annotated[
    str, typer.Option("--algorithms", "-a", help="Comma-separated names, or 'all'.")
]
FunctionsOpt = Annotated[
    str, typer.Option("--functions", "-f", help="Names, ranges and suites: F1-F13, F1,F5,"
                      "F6-floor, bbob, bbob:f1-f5, cec2017, cec2022:F1-F4.")
]
InstancesOpt = Annotated[
    str | None,
    typer.Option("--instances", metavar="1-15",
                 help="Suite instances, each its own cell (bbob: COCO's instance ids; CEC: 1, "
                 "the official data). Default: instance 1."),
]
BudgetOpt = Annotated[
    str | None,
    typer.Option("--budget-evals", metavar="N|NxD",
                 help="Evaluations per run instead of --iterations (NxD: N times the dimension, "
                 "CEC's 10000xD); each algorithm gets the iterations that spend it, and no "
                 "evaluation past it counts."),
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
