"""``swarmpath audit``: how much each optimizer owes to optima at the origin.

Every optimizer runs every function plain, shifted and shifted+rotated (the same runs and seeds,
through :func:`swarmpath.cli.bench.run_bench`); :func:`swarmpath.evidence.audit.audit` turns the
best values into decades lost per optimizer. The table is what docs/algorithms.md shows.
"""

from __future__ import annotations

import json
import math
import sys
import time
from typing import Annotated

import typer
from rich.console import Console

from swarmpath import __version__
from swarmpath.cli import parallel
from swarmpath.cli.bench import run_bench
from swarmpath.cli.bench_spec import (
    check_range,
    instances_of,
    make_spec,
    parse_instances,
    resolve_functions,
)
from swarmpath.cli.core import InputError, app
from swarmpath.cli.study_options import (
    AgentsOpt,
    AlgorithmsOpt,
    DimsOpt,
    FunctionsOpt,
    InstancesOpt,
    IterationsOpt,
    SeedOpt,
)
from swarmpath.evidence.audit import AUDIT_TRANSFORMS, KUDELA_BIASED, AuditRow, Key, audit
from swarmpath.functions import get_function
from swarmpath.functions.suites.base import CENTRE_SUFFIX, SuiteFunction
from swarmpath.optimizers import ParameterError

FORMATS = ("table", "markdown")
HEADER = (
    "optimizer", "D", "shift: median decades lost", "> 1", "> 3",
    "shift+rotate: median decades lost", "> 1", "> 3", "plain runs at exactly 0",
    "Kudela index", "centre-biased",
)


def audit_lines(rows: list[AuditRow], markdown: bool) -> list[str]:
    """The audit table as text lines (aligned columns, or a markdown table)."""
    body = []
    for r in rows:
        cells = [r.algorithm, str(r.dim)]
        for t in AUDIT_TRANSFORMS[1:]:
            if not r.decades.get(t):  # only suite functions: no shift+rotate
                cells += ["-", "-", "-"]
                continue
            cells += [f"{r.median(t):+.1f}", str(r.losing(t, 1.0)), str(r.losing(t, 3.0))]
        cells.append(f"{r.exact_zeros} of {r.plain_runs}")
        cells += [f"{r.centre_bias_index():.3g}", "yes" if r.centre_biased() else "no"]
        body.append(cells)
    if markdown:
        out = ["| " + " | ".join(HEADER) + " |", "|" + "---|" * len(HEADER)]
        return out + ["| " + " | ".join(c) + " |" for c in body]
    widths = [max(len(h), *(len(c[i]) for c in body)) for i, h in enumerate(HEADER)]
    fmt = [lambda s, w=w: s.ljust(w) for w in widths[:1]] + [
        lambda s, w=w: s.rjust(w) for w in widths[1:]
    ]
    return ["  ".join(f(c) for f, c in zip(fmt, cells, strict=True))
            for cells in [list(HEADER), *body]]


@app.command("audit")
def audit_command(
    algorithms: AlgorithmsOpt = "all",
    functions: FunctionsOpt = "F1-F13",
    dims: DimsOpt = "30",
    runs: Annotated[int, typer.Option(help="Independent runs per cell and transform.")] = 10,
    agents: AgentsOpt = 30,
    iterations: IterationsOpt = 500,
    seed: SeedOpt = 1,
    instances: InstancesOpt = None,
    jobs: Annotated[
        int, typer.Option("--jobs", "-j", help="Processes (0: one per CPU). Numbers do not change.")
    ] = 0,
    fmt: Annotated[
        str, typer.Option("--format", help="table or markdown.")
    ] = "table",
    as_json: Annotated[
        bool, typer.Option("--json", help="Print one JSON document (every function's decades).")
    ] = False,
    maps: Annotated[
        str | None,
        typer.Option("--maps", "-m", help="Audit path planners instead: their invariance on "
                     "these maps (presets or paths, as swarmpath plan takes them) and on their "
                     "rotated, mirrored, translated and start/goal-swapped copies."),
    ] = None,
    planners: Annotated[
        str, typer.Option("--planners", "-p", help="With --maps: comma-separated planner "
                          "names, or 'all'.")
    ] = "all",
    params: Annotated[
        str | None, typer.Option(help='With --maps: planner parameters, as swarmpath plan '
                                 'takes them: \'{"MFB": {"agents": 10}}\'.')
    ] = None,
) -> None:
    """Run every optimizer plain, shifted and shifted+rotated; print per optimizer the decades
    lost (median over functions of log10 of the mean-gap ratio), the functions losing more than
    1 and 3 decades, the plain runs that ended at exactly 0, and Kudela's centre-bias index
    (geometric mean of the shifted / plain mean-gap ratios; biased above 10). A suite function
    (bbob, cec2017, cec2022; --instances) is compared with itself translated so that its
    optimum is the origin. With --maps: the planners' invariance certificate
    (swarmpath.evidence.map_audit)."""
    if maps is not None:
        from swarmpath.cli.audit_maps import map_audit

        check_range("--jobs", jobs, 0, parallel.MAX_JOBS)
        map_audit(planners, maps, runs, seed, params, jobs, as_json)
        return
    if fmt not in FORMATS:
        raise InputError("--format", f"must be one of {', '.join(FORMATS)}, got {fmt!r}")
    check_range("--jobs", jobs, 0, parallel.MAX_JOBS)
    names = instances_of(resolve_functions(functions), parse_instances(instances))
    suite = [f for f in names if isinstance(get_function(f), SuiteFunction)]
    plain = [f for f in names if f not in suite]
    specs = [(t, make_spec(algorithms, ",".join(plain), dims, runs, agents, iterations, seed,
                           transform=t)) for t in (AUDIT_TRANSFORMS if plain else ())]
    if suite:  # an instance against itself translated to the origin: Kudela's shift on suites
        specs.append(("suite", make_spec(
            algorithms, ",".join(suite + [f + CENTRE_SUFFIX for f in suite]), dims, runs,
            agents, iterations, seed)))
    base = specs[0][1]
    stderr = Console(stderr=True)
    started = time.perf_counter()
    values: dict[Key, list[float]] = {}
    for role, spec in specs:
        try:
            cells = run_bench(spec, jobs=jobs or parallel.usable_cpus())
        except ParameterError as exc:
            raise InputError("--algorithms", str(exc)) from None
        for c in cells:
            values[_key(role, c.algorithm, c.function, c.dim)] = list(c.best_fitness)
        stderr.print(f"{role}: done ({time.perf_counter() - started:.0f} s)", highlight=False)
    rows = audit(values, base.algorithms, names, base.dims)
    seconds = time.perf_counter() - started
    if as_json:
        doc = {
            "swarmpath": __version__,
            "settings": {**base.settings(), "functions": names,
                         "transforms": list(AUDIT_TRANSFORMS)},
            "seconds": seconds,
            "rows": [_finite(r.to_json()) for r in rows],
        }
        sys.stdout.write(json.dumps(doc, allow_nan=False) + "\n")
        return
    for line in audit_lines(rows, fmt == "markdown"):
        print(line)
    print(f"\n{base.runs} runs per cell, {base.agents} agents, {base.iterations} iterations, "
          f"seed {base.seed}; decades lost = log10(mean gap transformed / mean gap plain), "
          f"gap = best - f_min, mean gaps below 1e-300 counted as 1e-300; Kudela index = "
          f"geometric mean over the functions of mean gap shifted / mean gap plain, "
          f"centre-biased above {KUDELA_BIASED:g} (Kudela, Nat. Mach. Intell. 2022; "
          f"arXiv:2301.01984)" + SUITE_NOTE * bool(suite) + f"; {seconds:.0f} s")


SUITE_NOTE = (
    "; suite functions (bbob, cec2017, cec2022): plain = the instance translated so that its "
    "optimum is the origin (<name>@centre), shift = the instance itself, no shift+rotate (the "
    "instance is rotated already)")


def _key(role: str, algorithm: str, function: str, dim: int) -> Key:
    """Where a cell's runs go: a suite cell is the 'shift' of its '@centre' control, which is
    its 'none'."""
    if role != "suite":
        return (algorithm, function, dim, role)
    if function.endswith(CENTRE_SUFFIX):
        return (algorithm, function.removesuffix(CENTRE_SUFFIX), dim, "none")
    return (algorithm, function, dim, "shift")


def _finite(v: object) -> object:
    if isinstance(v, dict):
        return {k: _finite(x) for k, x in v.items()}
    if isinstance(v, float) and not math.isfinite(v):
        return str(v)
    return v
