"""``swarmpath bench --race``: the study raced on this machine, round by round, as the service races
a job with the same ``racing`` settings (docs/statistics.md, Racing).

The rounds and decisions are those of :func:`swarmpath.evidence.racing.race_block`, replayed
after every round from the runs computed so far: it says how many runs each cell may have, and
the runs missing are computed next (:func:`swarmpath.cli.bench.run_bench` with per-cell run
ranges, on one pool of processes for all rounds). Run r of a cell is run r of the unraced study
whatever the round, batch or ``--jobs``, so a raced bench and a raced job of the same study end
with the same allowances, decisions and numbers. A run whose best value is not a number counts
as the worst run, as the service stores it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Annotated, Any

import numpy as np
import typer

from swarmpath.cli.bench_spec import BenchSpec
from swarmpath.cli.core import InputError
from swarmpath.evidence import report
from swarmpath.evidence.group_sequential import SPENDING
from swarmpath.evidence.race_report import study_race
from swarmpath.evidence.race_tests import LookMemo
from swarmpath.evidence.racing import (
    CLOSING,
    EVERY_ROUND,
    PAIRS,
    RaceSettings,
    comparisons_per_block,
    default_design,
    race_block,
)
from swarmpath.parallel import TaskPool

__all__ = ["RaceBlock", "race_blocks", "race_settings", "run_race"]

CellKey = tuple[str, int, str]  # (function, dim, algorithm)

RaceOpt = Annotated[bool, typer.Option(
    "--race", help="Race the cells (docs/statistics.md, Racing): runs in rounds, a cell stops "
    "once its comparisons are decided (an anytime-valid sequence, Pocock-spent rank-sum looks "
    "every round, the rank-sum test at --runs: --race-looks); --runs is the most a cell "
    "gets; the markers are the race's decisions.")]
RaceAlphaOpt = Annotated[float | None, typer.Option(
    "--race-alpha", help="Error rate of all the race's decisions together (Bonferroni over the "
    "comparisons). Default 0.05.")]
RaceMinRunsOpt = Annotated[int | None, typer.Option(
    "--race-min-runs", help="Runs every cell gets before the first decision. Default 10.")]
RaceBatchOpt = Annotated[int | None, typer.Option(
    "--race-batch", help="Runs a racing cell gets per round after the first. Default 10.")]
RaceMarginOpt = Annotated[float | None, typer.Option(
    "--race-margin", help="Equivalence margin on P(run beats the other's run) - 1/2 (Vargha-"
    "Delaney's negligible: 0.06); 0: only differences stop a comparison. Default 0.")]
RaceFinalOpt = Annotated[str | None, typer.Option(
    "--race-final-test", metavar="rank-sum|sign|none", help="The closing look at --runs for the "
    "comparisons still open there (docs/statistics.md, Racing): the full study's rank-sum test, "
    "Holm over them, at half of alpha (default); the sign test at half of alpha; none.")]
RaceLooksOpt = Annotated[str | None, typer.Option(
    "--race-looks", metavar="every-round|none|N,N,...", help="Planned looks (docs/statistics.md, "
    "Racing): at every round after the first, none, or at these run counts (each "
    "--race-min-runs + k x --race-batch, below --runs); each comparison still open there gets "
    "the rank-sum test at a group-sequential level. Default every-round with the rank-sum "
    "closing look, none with the others.")]
RaceLookShareOpt = Annotated[float | None, typer.Option(
    "--race-look-share", help="The planned looks' share of --race-alpha. Default 0.8 with "
    "looks, 0 without.")]
RaceSequenceShareOpt = Annotated[float | None, typer.Option(
    "--race-sequence-share", help="The confidence sequence's share of --race-alpha beside the "
    "rank-sum closing look (which gets the rest). Default 0.05 with looks, 0.5 without.")]
RaceSpendingOpt = Annotated[str | None, typer.Option(
    "--race-spending", metavar="obrien-fleming|pocock", help="How the looks' share is spent "
    "across them (Lan-DeMets type). Default pocock.")]
RaceFutilityOpt = Annotated[float | None, typer.Option(
    "--race-futility", help="Stop a comparison at a look where its predictive power (the "
    "chance, by its own trend, that the closing rank-sum look calls it) is below this; 0 "
    "never. Costs power, never error. Default 0.05 with looks and the rank-sum closing look.")]
RaceRecycleOpt = Annotated[bool | None, typer.Option(
    "--race-recycle/--race-no-recycle", help="At a look, pass the looks' share of alpha of a "
    "comparison declared different to the open comparisons of its block (Holm's step-down). "
    "Default: on with looks.")]
RacePairsOpt = Annotated[str | None, typer.Option(
    "--race-pairs", metavar="reference|all", help="Compare every algorithm with the reference "
    "(default) or every pair.")]


def race_settings(spec: BenchSpec, race: bool, alpha: float | None, min_runs: int | None,
                  batch: int | None, margin: float | None, pairs: str | None,
                  final_test: str | None = None, looks: str | None = None,
                  look_share: float | None = None, sequence_share: float | None = None,
                  spending: str | None = None, futility: float | None = None,
                  recycle: bool | None = None) -> RaceSettings | None:
    """The race of ``--race`` and its options (None without ``--race``), ``--runs`` its
    ``max_runs``; :class:`InputError` naming the option that is wrong."""
    given = {"--race-alpha": alpha, "--race-min-runs": min_runs, "--race-batch": batch,
             "--race-margin": margin, "--race-pairs": pairs,
             "--race-final-test": final_test, "--race-looks": looks,
             "--race-look-share": look_share, "--race-sequence-share": sequence_share,
             "--race-spending": spending, "--race-futility": futility,
             "--race-recycle": recycle}
    if not race:
        for option, value in given.items():
            if value is not None:
                raise InputError(option, "races only with --race")
        return None
    alpha = RaceSettings.alpha if alpha is None else alpha
    min_runs = min(RaceSettings.min_runs, spec.runs) if min_runs is None else min_runs
    batch = RaceSettings.batch if batch is None else batch
    margin = RaceSettings.margin if margin is None else margin
    pairs = RaceSettings.pairs if pairs is None else pairs
    final_test = RaceSettings.final_test if final_test is None else final_test
    if not (math.isfinite(alpha) and 0.0 < alpha < 1.0):
        raise InputError("--race-alpha", f"must be in (0, 1), got {alpha}")
    if not 1 <= min_runs <= spec.runs:
        raise InputError("--race-min-runs", f"must be in [1, --runs ({spec.runs})], got "
                         f"{min_runs}")
    if batch < 1:
        raise InputError("--race-batch", f"must be >= 1, got {batch}")
    if not (math.isfinite(margin) and 0.0 <= margin < 0.5):
        raise InputError("--race-margin", f"must be in [0, 0.5) (on P(run beats the other's "
                         f"run) - 1/2), got {margin}")
    if pairs not in PAIRS:
        raise InputError("--race-pairs", f"must be one of {', '.join(PAIRS)}, got {pairs!r}")
    if final_test not in CLOSING:
        raise InputError("--race-final-test", f"must be one of {', '.join(CLOSING)}, got "
                         f"{final_test!r}")
    if len(spec.algorithms) < 2:
        raise InputError("--algorithms", "a race needs at least two algorithms")
    if spec.pool_instances:
        raise InputError("--pool-instances", "a race decides per instance; pooled rows would "
                         "mix its allowances: race without it")
    plan = default_design(final_test, futility=futility, recycle=recycle,
                          **_planned_looks(looks, look_share, sequence_share, spending))
    try:
        return RaceSettings(max_runs=spec.runs, alpha=alpha, min_runs=min_runs, batch=batch,
                            pairs=pairs, margin=margin, final_test=final_test, **plan)
    except ValueError as e:  # the looks or shares against the rest (RaceSettings says which)
        option = {"looks": "--race-looks", "look_share": "--race-look-share", "sequence_share":
                  "--race-sequence-share", "spending": "--race-spending",
                  "futility": "--race-futility", "recycle": "--race-recycle"}.get(
                      str(e).split(" ", 1)[0].rstrip(":"), "--race-looks")
        raise InputError(option, str(e)) from None


def _planned_looks(looks: str | None, look_share: float | None, sequence_share: float | None,
                   spending: str | None) -> dict[str, Any]:
    """The planned looks' options given, as :class:`RaceSettings` fields (for
    :func:`~swarmpath.evidence.racing.default_design`); a malformed list of run counts is an
    :class:`InputError`."""
    out: dict[str, Any] = {}
    if looks is not None and looks.strip() in (EVERY_ROUND, "none"):
        out["looks"] = EVERY_ROUND if looks.strip() == EVERY_ROUND else ()
    elif looks is not None:
        try:
            out["looks"] = tuple(int(x) for x in looks.split(",") if x.strip())
        except ValueError:
            raise InputError("--race-looks", f"must be {EVERY_ROUND}, none or run counts "
                             f"separated by commas, got {looks!r}") from None
    for option, key, value in (("--race-look-share", "look_share", look_share),
                               ("--race-sequence-share", "sequence_share", sequence_share)):
        if value is not None:
            if not math.isfinite(value):
                raise InputError(option, f"must be a number in [0, 1), got {value}")
            out[key] = value
    if spending is not None:
        if spending not in SPENDING:
            raise InputError("--race-spending", f"must be one of {', '.join(SPENDING)}, got "
                             f"{spending!r}")
        out["spending"] = spending
    return out


@dataclass(frozen=True)
class RaceBlock:
    """One function and dimension: its cells as (the service's cell index, algorithm), the
    reference last; ``block`` the fields its cells share, as the service's race names them."""

    function: str
    dim: int
    members: list[tuple[int, str]]
    block: dict[str, Any]

    @property
    def names(self) -> list[str]:
        return [name for _, name in self.members]


def race_blocks(spec: BenchSpec) -> list[RaceBlock]:
    """The study's blocks in table order. A cell's index is the one a service job of the same
    study gives it (algorithm-major: algorithm, function, dimension)."""
    per_algorithm = len(spec.functions) * len(spec.dims)
    out = []
    for fi, function in enumerate(spec.functions):
        for di, dim in enumerate(spec.dims):
            members = [(ai * per_algorithm + fi * len(spec.dims) + di, a)
                       for ai, a in enumerate(spec.algorithms)]
            members.sort(key=lambda m: m[1] == spec.reference)  # stable: the reference last
            # what a service cell spec holds besides its algorithm, params and iterations
            block = {"agents": spec.agents, "backend": spec.backend, "dim": dim,
                     "function": function, "kind": "benchmark",
                     "max_evaluations": spec.evaluations(dim), "shifted": spec.shifted,
                     "transform": spec.transform}
            out.append(RaceBlock(function, dim, members, block))
    return out


def _values(cell: report.Cell | None) -> np.ndarray:
    """A cell's best values in run order, NaN as the worst (inf): what the service races on."""
    if cell is None:
        return np.empty(0)
    v = np.asarray(cell.best_fitness, dtype=float)
    return np.where(np.isnan(v), np.inf, v)


def _merge(old: report.Cell | None, new: report.Cell) -> report.Cell:
    """A cell's runs so far followed by a round's (runs in order)."""
    if old is None:
        return new
    return report.Cell(
        algorithm=new.algorithm, function=new.function, dim=new.dim,
        run_ids=old.run_ids + new.run_ids, best_fitness=old.best_fitness + new.best_fitness,
        evaluations=old.evaluations + new.evaluations, seconds=old.seconds + new.seconds,
        params=new.params, curves=old.curves + new.curves,
        cpu_seconds=report.cpu_total((old.cpu_seconds, new.cpu_seconds)),
        backends=report.count_backends([*old.backends.items(), *new.backends.items()]))


def run_race(
    spec: BenchSpec,
    settings: RaceSettings,
    jobs: int,
    on_round: Callable[[int, Mapping[CellKey, tuple[int, int]], int], None] | None = None,
    on_step: Callable[[int], None] | None = None,
) -> tuple[list[report.Cell], dict[str, Any]]:
    """The raced study: its cells (the runs the race gave each, in table order, ranked) and the
    race document (``GET /jobs/{id}/race``'s shape). ``on_round(round, runs, total)`` before a
    round is computed: the run ranges it computes, and the study's runs with them."""
    from swarmpath.cli.bench import run_bench

    blocks = race_blocks(spec)
    comparisons = sum(len(comparisons_per_block(b.names, settings.pairs)) for b in blocks)
    cells: dict[CellKey, report.Cell] = {}
    memo = LookMemo()  # the looks' tests from one round's replay to the next
    round_ = 0
    with TaskPool(jobs) as pool:
        while True:
            ranges: dict[CellKey, tuple[int, int]] = {}
            for b in blocks:
                values = {a: _values(cells.get((b.function, b.dim, a))) for a in b.names}
                race = race_block(values, b.names, settings, comparisons, memo=memo)
                for a in b.names:
                    have = values[a].size
                    if race.allowance[a] > have:
                        ranges[(b.function, b.dim, a)] = (have, race.allowance[a])
            if not ranges:
                break
            if on_round is not None:
                used = sum(len(c.run_ids) for c in cells.values())
                on_round(round_, ranges, used + sum(e - f for f, e in ranges.values()))
            for c in run_bench(spec, on_step, jobs, list(ranges), ranges=ranges, pool=pool):
                key = (c.function, c.dim, c.algorithm)
                cells[key] = _merge(cells.get(key), c)
            round_ += 1
    out = [cells[key] for key in spec.cells()]
    report.assign_ranks(out)
    return out, race_document(spec, settings, blocks, comparisons, cells)


def race_document(spec: BenchSpec, settings: RaceSettings, blocks: list[RaceBlock],
                  comparisons: int, cells: dict[CellKey, report.Cell]) -> dict[str, Any]:
    """The race of the computed ``cells``, as ``GET /jobs/{id}/race`` shows a job's."""
    values = [{a: _values(cells.get((b.function, b.dim, a))) for a in b.names} for b in blocks]
    doc = study_race(settings, comparisons, [
        (b.block, race_block(v, b.names, settings, comparisons), b.members)
        for b, v in zip(blocks, values, strict=True)])
    for b, v, state in zip(blocks, values, doc["blocks"], strict=True):
        for c in state["cells"]:
            c["key"] = f"{c['algorithm']}/{b.function}/{b.dim}"
            c["finished_runs"] = int(v[c["algorithm"]].size)
    return doc


def race_summary(race: dict[str, Any]) -> dict[str, Any]:
    """Runs the race used against the unraced study's (``--json``'s ``race_summary``)."""
    from swarmpath.evidence.race_report import race_line

    cells = [c for b in race["blocks"] for c in b["cells"]]
    used = sum(c["runs"] for c in cells)
    full = race["settings"]["max_runs"] * len(cells)
    return {"runs": used, "unraced_runs": full, "fewer": full / max(used, 1),
            "cells_decided": sum(c["reason"] == "decided" for c in cells),
            "cells": len(cells), "line": race_line(race)}


def race_with_progress(spec: BenchSpec, settings: RaceSettings, stderr: Any, jobs: int
                       ) -> tuple[list[report.Cell], dict[str, Any]]:
    """:func:`run_race` with a progress bar per round on ``stderr`` (a rich Console)."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    unraced = len(spec.cells()) * spec.runs
    columns = (TextColumn("{task.description:<16}"), BarColumn(),
               TextColumn("runs {task.fields[used]} (unraced {task.fields[unraced]})"),
               TimeElapsedColumn())
    with Progress(*columns, console=stderr, transient=stderr.is_terminal) as progress:
        task = progress.add_task(f"race x{jobs}", total=1, used=0, unraced=unraced)
        steps = 0

        def on_round(round_: int, ranges: Mapping[CellKey, tuple[int, int]], used: int) -> None:
            nonlocal steps
            steps = 0
            total = sum((end - first) * spec.iterations_for(a, d)
                        for (_f, d, a), (first, end) in ranges.items())
            progress.update(task, description=f"race round {round_}", completed=0,
                            total=max(total, 1), used=used)

        def on_step(rows: int) -> None:
            nonlocal steps
            steps += rows
            progress.update(task, completed=steps)

        cells, race = run_race(spec, settings, jobs, on_round, on_step)
        progress.update(task, description="race done")
    return cells, race
