"""Results of a benchmark study as the papers print them: pure functions, no I/O.

A study is a grid of cells, one per (function, dim, algorithm), each holding the best fitness of
every run. This module ranks the cells, lays them out as the papers' table (for each function and
dimension the rows min/max/avg/std, one column per algorithm, the best average marked) and turns
them into a JSON-ready document. The CLI (``swarmpath bench``) and the service use it alike.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from rich import box
from rich.table import Table

from swarmpath.evidence import audit, tables
from swarmpath.evidence.benchmark_stats import (
    Statistics,
    benchmark_tests,
    format_p,
    friedman_lines,
    legend,
    statistics,
    tests_to_json,
)
from swarmpath.evidence.stats import describe, json_number, rank

__all__ = [
    "BEST_MARK", "TABLE_STATS", "Cell", "Row", "Statistics", "assign_ranks", "benchmark_tests",
    "cell_to_json", "format_p", "format_value", "friedman_lines", "json_number", "legend",
    "origin_suspects", "plot_runs", "ranking", "render_ranking", "render_table", "statistics",
    "study_to_json", "table_rows", "tests_to_json",
]

# swarmpath.evidence.compare loads scipy.stats (~0.8 s): only when statistics are run
if TYPE_CHECKING:
    pass

#: Rows of the table, in the papers' order.
TABLE_STATS = ("min", "max", "avg", "std")
#: Appended to the best average of each function and dimension (survives non-tty output).
BEST_MARK = tables.BEST_MARK


@dataclass
class Cell:
    """One (algorithm, function, dim) of a study: its runs and their statistics."""

    algorithm: str
    function: str
    dim: int
    run_ids: list[int]
    best_fitness: list[float]  # per run, aligned with run_ids
    evaluations: list[int]  # per run
    seconds: float
    params: dict[str, Any] = field(default_factory=dict)
    #: best so far after each iteration, one list per run (aligned with run_ids); empty if not kept
    curves: list[list[float]] = field(default_factory=list, repr=False)
    stats: dict[str, float] = field(init=False)
    rank: int = 0  # among the algorithms at this (function, dim); set by assign_ranks
    #: CPU seconds of the runs (the computing threads', ``Result.cpu_seconds``) beside the wall
    #: ``seconds``; None when a part of the cell was not measured (see :func:`cpu_total`)
    cpu_seconds: float | None = None
    #: runs per backend that computed them (``Result.backend``: "numpy" or "numba"; backend
    #: "auto" runs numpy while the kernels are not compiled yet); empty when not known
    backends: dict[str, int] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.stats = describe(self.best_fitness)


def cpu_total(values: Iterable[float | None]) -> float | None:
    """The sum of CPU times, or None when any is unknown (a sum missing a part would read as a
    smaller cost, unlike a mean over the measured ones)."""
    total = 0.0
    for v in values:
        if v is None:
            return None
        total += float(v)
    return total


def count_backends(parts: Iterable[tuple[str, int]]) -> dict[str, int]:
    """Runs per backend from (backend, runs) pairs, in sorted order (one cell's parts, or the
    cells merged into one)."""
    out: dict[str, int] = {}
    for backend, runs in parts:
        out[backend] = out.get(backend, 0) + runs
    return dict(sorted(out.items()))


def assign_ranks(cells: Iterable[Cell]) -> None:
    """Rank the algorithms by average best fitness within each (function, dim)."""
    groups: dict[tuple[str, int], list[Cell]] = {}
    for c in cells:
        groups.setdefault((c.function, c.dim), []).append(c)
    for group in groups.values():
        ranks = rank({c.algorithm: c.stats["avg"] for c in group})
        for c in group:
            c.rank = ranks[c.algorithm]


def format_value(v: float, digits: int = 2) -> str:
    """Scientific notation as in the papers (6.59E-28); exact zero as 0; inf as inf."""
    if v == 0:
        return "0"
    if not math.isfinite(v):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")
    return f"{v:.{digits}E}"


@dataclass(frozen=True)
class Row:
    """One printed row: a statistic of one (function, dim) across the algorithms."""

    function: str
    dim: int
    stat: str
    values: tuple[float, ...]  # one per algorithm, in column order (NaN where missing)
    best: tuple[bool, ...]  # marked cells (only on the avg row)


def table_rows(cells: Sequence[Cell], algorithms: Sequence[str]) -> list[Row]:
    """The table's rows: functions and dims in order of first appearance, TABLE_STATS each.

    On each avg row every algorithm whose average equals the lowest is marked (ties all marked).
    """
    by_key = {(c.function, c.dim, c.algorithm): c for c in cells}
    groups = list(dict.fromkeys((c.function, c.dim) for c in cells))
    rows: list[Row] = []
    for function, dim in groups:
        present = [by_key.get((function, dim, a)) for a in algorithms]
        for stat in TABLE_STATS:
            values = tuple(math.nan if c is None else c.stats[stat] for c in present)
            if stat == "avg":
                finite = [v for v in values if not math.isnan(v)]
                low = min(finite) if finite else math.nan
                best = tuple(v == low for v in values)
            else:
                best = (False,) * len(values)
            rows.append(Row(function, dim, stat, values, best))
    return rows


def render_table(
    cells: Sequence[Cell],
    algorithms: Sequence[str],
    title: str | None = None,
    caption: str | None = None,
    digits: int = 2,
    tests: Statistics | None = None,
    origin: bool = False,
) -> Table:
    """The paper-style table as a rich Table (print it with any rich Console). With ``tests``,
    each location (avg or median, by ``tests.stat``) is followed by its marker against the
    reference (``+``, ``=``, ``-``), bold with ``*`` when best and ``~`` when not significantly
    worse than the best, and the effect rows follow (:mod:`swarmpath.evidence.tables`). With
    ``origin`` (an untransformed study), the averages of origin-suspect cells
    (:func:`origin_suspects`) carry ``audit.ORIGIN_MARK``; print ``audit.ORIGIN_FOOTNOTE`` under
    the table when there are any."""
    grid = study_grid(cells, algorithms, digits, tests, origin)
    return tables.to_rich(grid, title, caption)


def study_grid(cells: Sequence[Cell], algorithms: Sequence[str], digits: int = 2,
               tests: Statistics | None = None, origin: bool = False) -> tables.Grid:
    """The study's table as a :class:`swarmpath.evidence.tables.Grid` (terminal or LaTeX)."""
    compared = tests is not None and len(algorithms) > 1
    rows = tables.study_rows(cells, tests if compared else None, origin)
    return tables.benchmark_grid(rows, algorithms, tests.stat if tests else "mean", digits,
                                 compared, tests.reference if tests else None)


def origin_suspects(cells: Iterable[Cell]) -> set[tuple[str, int, str]]:
    """(function, dim, algorithm) of the cells whose runs reached exact zeros or values below
    1e-100 on a function whose optimum is at the origin (meaningful for untransformed studies)."""
    return {
        (c.function, c.dim, c.algorithm)
        for c in cells
        if audit.origin_suspect(c.function, c.best_fitness)
    }


def ranking(cells: Sequence[Cell], algorithms: Sequence[str]) -> list[dict[str, Any]]:
    """Per algorithm: how many (function, dim) it has the best average in, its mean rank, and
    the wall and CPU seconds of its cells (summed; CPU None when a cell's is unknown)."""
    out = []
    for a in algorithms:
        mine = [c for c in cells if c.algorithm == a]
        out.append(
            {
                "algorithm": a,
                "best": sum(1 for c in mine if c.rank == 1),
                "of": len(mine),
                "mean_rank": (sum(c.rank for c in mine) / len(mine)) if mine else math.nan,
                "seconds": sum(c.seconds for c in mine),
                "cpu_seconds": cpu_total(c.cpu_seconds for c in mine),
            }
        )
    return out


def render_ranking(
    cells: Sequence[Cell], algorithms: Sequence[str], tests: Statistics | None = None
) -> Table:
    """Per algorithm: best averages, mean rank over the cells, the wall time and CPU time of its
    cells (``time (s)``, ``CPU (s)``: "-" when not measured) and, with ``tests``, the +/=/-
    counts against the reference and the Friedman mean rank per dimension (with the marker of
    the Holm post-hoc against the reference)."""
    table = Table(box=box.SIMPLE_HEAD, pad_edge=False)
    table.add_column("algorithm")
    table.add_column("best avg", justify="right")
    table.add_column("mean rank", justify="right")
    table.add_column("time (s)", justify="right")
    table.add_column("CPU (s)", justify="right")
    counts = tests.comparison.counts() if tests else {}
    verdicts = tests.bayes.verdict_counts() if tests and tests.bayes else {}
    if tests:
        table.add_column(f"+/=/- vs {tests.reference}", justify="right")
        if tests.bayes:
            table.add_column("better/equiv./worse/undecided", justify="right")
        for dim in tests.friedman:
            table.add_column(f"Friedman D={dim}", justify="right")
    for r in ranking(cells, algorithms):
        a = r["algorithm"]
        cpu = r["cpu_seconds"]
        cols = [a, f"{r['best']}/{r['of']}", f"{r['mean_rank']:.2f}", f"{r['seconds']:.2f}",
                "-" if cpu is None else f"{cpu:.2f}"]
        if tests:
            n = counts.get(a)
            cols.append("ref" if n is None else f"{n['+']}/{n['=']}/{n['-']}")
            if tests.bayes:
                v = verdicts.get(a)
                cols.append("ref" if v is None else "/".join(str(x) for x in v.values()))
            for f in tests.friedman.values():
                post = f.posthoc.get(a, {}).get("marker", " ")
                cols.append(f"{f.mean_ranks[a]:.2f} {post}")
        table.add_row(*cols)
    return table


def plot_runs(cells: Iterable[Cell]) -> list[dict[str, Any]]:
    """One dict per run (algorithm, function, dim, run, best_fitness, curve): what
    :func:`swarmpath.evidence.plots.write_benchmark_plots` draws."""
    return [
        {"algorithm": c.algorithm, "function": c.function, "dim": c.dim, "run": run,
         "best_fitness": value, "curve": c.curves[i] if i < len(c.curves) else None}
        for c in cells
        for i, (run, value) in enumerate(zip(c.run_ids, c.best_fitness, strict=True))
    ]


def cell_to_json(
    c: Cell, tests: Statistics | None = None, origin: bool = False
) -> dict[str, Any]:
    out = {
        "algorithm": c.algorithm,
        "function": c.function,
        "dim": c.dim,
        "stats": {k: json_number(v) for k, v in c.stats.items()},
        "rank": c.rank,
        "seconds": c.seconds,
        "cpu_seconds": c.cpu_seconds,
        "backends": c.backends,
        "evaluations": sum(c.evaluations),
        "params": c.params,
        "run_ids": c.run_ids,
        "best_fitness": [json_number(v) for v in c.best_fitness],
        "run_evaluations": c.evaluations,
    }
    if origin:
        out["origin_suspect"] = audit.origin_suspect(c.function, c.best_fitness)
    if tests is not None:
        fields = tables.test_fields(tests, (c.function, c.dim), c.algorithm)
        out["test"] = {"reference": tests.reference, "stat": tests.stat,
                       **{k: json_number(v) if isinstance(v, float) else v
                          for k, v in fields.items() if k != "best"},
                       "best": c.algorithm in tests.best.get((c.function, c.dim), set())}
    return out


def study_to_json(
    settings: Mapping[str, Any],
    cells: Sequence[Cell],
    seconds: float,
    version: str,
    tests: Statistics | None = None,
) -> dict[str, Any]:
    """The whole study as one JSON-ready document (with ``tests``: each cell's ``test`` and the
    document's ``statistics``, see :func:`tests_to_json`). Untransformed studies (settings
    ``transform`` none or absent) give each cell ``origin_suspect``."""
    origin = settings.get("transform", "none") == "none"
    algorithms = list(settings.get("algorithms", dict.fromkeys(c.algorithm for c in cells)))
    doc = {
        "swarmpath": version,
        "settings": dict(settings),
        "seconds": seconds,
        "cpu_seconds": cpu_total(c.cpu_seconds for c in cells),
        "cells": [cell_to_json(c, tests, origin) for c in cells],
        "ranking": [
            {**r, "mean_rank": json_number(r["mean_rank"])} for r in ranking(cells, algorithms)
        ],
    }
    if tests is not None:
        doc["statistics"] = tests_to_json(tests)
    return doc
