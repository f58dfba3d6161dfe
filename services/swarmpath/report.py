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
from typing import Any

from rich import box
from rich.table import Table
from rich.text import Text

from swarmpath.stats import describe, rank

#: Rows of the table, in the papers' order.
TABLE_STATS = ("min", "max", "avg", "std")
#: Appended to the best average of each function and dimension (survives non-tty output).
BEST_MARK = "*"


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
    stats: dict[str, float] = field(init=False)
    rank: int = 0  # among the algorithms at this (function, dim); set by assign_ranks

    def __post_init__(self) -> None:
        self.stats = describe(self.best_fitness)


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
) -> Table:
    """The paper-style table as a rich Table (print it with any rich Console)."""
    table = Table(title=title, caption=caption, box=box.SIMPLE_HEAD, pad_edge=False)
    table.add_column("F", no_wrap=True)
    table.add_column("D", justify="right", no_wrap=True)
    table.add_column("", no_wrap=True)
    for a in algorithms:
        table.add_column(a, justify="right", no_wrap=True)
    rows = table_rows(cells, algorithms)
    for i, row in enumerate(rows):
        first = i == 0 or (rows[i - 1].function, rows[i - 1].dim) != (row.function, row.dim)
        last = i + 1 == len(rows) or (rows[i + 1].function, rows[i + 1].dim) != (
            row.function,
            row.dim,
        )
        texts = []
        for v, marked in zip(row.values, row.best, strict=True):
            s = "-" if math.isnan(v) else format_value(v, digits)
            # Every number gets one trailing character so that marked and unmarked ones align.
            texts.append(Text(s + BEST_MARK, style="bold") if marked else Text(s + " "))
        table.add_row(
            row.function if first else "",
            str(row.dim) if first else "",
            row.stat,
            *texts,
            end_section=last,
        )
    return table


def ranking(cells: Sequence[Cell], algorithms: Sequence[str]) -> list[dict[str, Any]]:
    """Per algorithm: how many (function, dim) it has the best average in, and its mean rank."""
    out = []
    for a in algorithms:
        mine = [c for c in cells if c.algorithm == a]
        out.append(
            {
                "algorithm": a,
                "best": sum(1 for c in mine if c.rank == 1),
                "of": len(mine),
                "mean_rank": (sum(c.rank for c in mine) / len(mine)) if mine else math.nan,
            }
        )
    return out


def render_ranking(cells: Sequence[Cell], algorithms: Sequence[str]) -> Table:
    table = Table(box=box.SIMPLE_HEAD, pad_edge=False)
    table.add_column("algorithm")
    table.add_column("best avg", justify="right")
    table.add_column("mean rank", justify="right")
    for r in ranking(cells, algorithms):
        table.add_row(r["algorithm"], f"{r['best']}/{r['of']}", f"{r['mean_rank']:.2f}")
    return table


def json_number(v: float) -> float | str:
    """JSON has no inf/NaN: they are written as the strings "inf", "-inf", "nan"
    (Python's float() reads them back); finite values stay numbers (round-trip exact)."""
    v = float(v)
    if math.isfinite(v):
        return v
    return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")


def cell_to_json(c: Cell) -> dict[str, Any]:
    return {
        "algorithm": c.algorithm,
        "function": c.function,
        "dim": c.dim,
        "stats": {k: json_number(v) for k, v in c.stats.items()},
        "rank": c.rank,
        "seconds": c.seconds,
        "evaluations": sum(c.evaluations),
        "params": c.params,
        "run_ids": c.run_ids,
        "best_fitness": [json_number(v) for v in c.best_fitness],
        "run_evaluations": c.evaluations,
    }


def study_to_json(
    settings: Mapping[str, Any], cells: Sequence[Cell], seconds: float, version: str
) -> dict[str, Any]:
    """The whole study as one JSON-ready document."""
    algorithms = list(settings.get("algorithms", dict.fromkeys(c.algorithm for c in cells)))
    return {
        "swarmpath": version,
        "settings": dict(settings),
        "seconds": seconds,
        "cells": [cell_to_json(c) for c in cells],
        "ranking": [
            {**r, "mean_rank": json_number(r["mean_rank"])} for r in ranking(cells, algorithms)
        ],
    }
