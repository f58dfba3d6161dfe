"""Options shared by the commands that run or report a study (bench, audit, reproduce, plan,
results): one declaration each, so their names, help texts and defaults cannot drift apart."""

from __future__ import annotations

from typing import Annotated, Any

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
        "--backend", metavar="auto|numpy|numba",
        help="auto (default): compiled kernels where the study has them, else the reference; "
        "numpy: the reference; numba: compiled kernels giving the reference's numbers run for "
        "run, and what has no kernel is refused. The numbers are the same either way.",
    ),
]
StatOpt = Annotated[
    str,
    typer.Option("--stat", metavar="mean|median",
                 help="What the table reports and ranks by: mean with std, or median with the "
                 "interquartile range (also the bold cells, Friedman ranks and Bayesian test)."),
]
RopeOpt = Annotated[
    str,
    typer.Option("--rope", metavar="WIDTH|PCT%",
                 help="Region of practical equivalence of the Bayesian comparison: a width in "
                 "the function's units (1e-8) or relative to the larger distance to the optimum "
                 "(1%)."),
]
TableFormatOpt = Annotated[
    str, typer.Option("--format", metavar="table|latex",
                      help="table: the terminal table; latex: a booktabs table with a caption.")
]


def check_stat(stat: str) -> str:
    from swarmpath.cli.core import InputError
    from swarmpath.evidence.stats import STATS

    if stat not in STATS:
        raise InputError("--stat", f"{stat!r} is not one of {', '.join(STATS)}")
    return stat


def check_rope(text: str) -> Any:
    """The ``--rope`` option as a :class:`swarmpath.evidence.bayes.Rope` (InputError if bad)."""
    from swarmpath.cli.core import InputError
    from swarmpath.evidence.bayes import parse_rope

    try:
        return parse_rope(text)
    except ValueError as exc:
        raise InputError("--rope", str(exc)) from None


def check_format(fmt: str, allowed: tuple[str, ...]) -> str:
    from swarmpath.cli.core import InputError

    if fmt not in allowed:
        raise InputError("--format", f"{fmt!r} is not one of {', '.join(allowed)}")
    return fmt
