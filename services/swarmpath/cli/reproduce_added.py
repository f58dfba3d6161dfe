"""``reproduce TABLE --add NAME``: your algorithm beside a paper's table, at the paper's setting.

The added algorithms run the table's functions, dimension, agents, iterations and runs with the
study's seed (a cell's runs do not depend on the other cells, so the table's own columns get
the same numbers as without ``--add``). They have no published value, so no verdict: each added
cell reports its measured statistics and its rank-sum marker against the table's proposed
algorithm (its last column), Holm-corrected over the added cells only. The table's own rows,
verdicts and markers are computed without them, exactly as without ``--add``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from rich.console import Console
from rich.table import Table

from swarmpath.cli.core import InputError
from swarmpath.evidence import report
from swarmpath.evidence.reference import BenchmarkTable
from swarmpath.evidence.report import format_value
from swarmpath.evidence.stats import describe

OPTION = "--add"


def parse_added(add: str | None, table: BenchmarkTable) -> list[str]:
    """The registered optimizers ``--add`` names (canonical names, in order); InputError naming
    ``--add`` for an unknown name or a column the table already has."""
    if add is None:
        return []
    from swarmpath.optimizers import get_optimizer

    out: list[str] = []
    for raw in (n.strip() for n in add.split(",")):
        if not raw:
            continue
        try:
            name = get_optimizer(raw).name
        except KeyError as exc:
            raise InputError(OPTION, str(exc.args[0])) from None
        if name in table.algorithms:
            raise InputError(OPTION, f"{name} is a column of {table.name} already")
        if name not in out:
            out.append(name)
    if not out:
        raise InputError(OPTION, "names no algorithm")
    return out


def added_statistics(cells: Sequence[report.Cell], added: Sequence[str],
                     reference: str) -> dict[str, Any]:
    """The added cells as the ``--json`` document carries them (``statistics.added``): per cell
    its runs, statistics and marker against ``reference``."""
    pool = [c for c in cells if c.algorithm in (*added, reference)]
    tests = report.statistics(pool, [*added, reference], reference=reference)
    out = []
    for c in pool:
        if c.algorithm not in added:
            continue
        out.append({"algorithm": c.algorithm, "function": c.function, "dim": c.dim,
                    **describe(c.best_fitness), "marker": tests.marker(c),
                    "runs": [float(v) for v in c.best_fitness]})
    return {"reference": reference, "cells": out}


_COLUMNS = ["function", "algorithm", "avg", "median", "min", "max", "std"]


def _lines(added: Mapping[str, Any]) -> list[list[str]]:
    return [[c["function"], c["algorithm"],
             f"{format_value(c['avg'], 2)} {c['marker'] or ''}".strip(),
             *(format_value(c[k], 2) for k in ("median", "min", "max", "std"))]
            for c in added["cells"]]


def _title(added: Mapping[str, Any]) -> str:
    return (f"added at the table's setting (no published value; +/=/-: rank-sum test against "
            f"{added['reference']}, Holm-corrected over the added cells, alpha 0.05)")


def print_added(statistics: Mapping[str, Any] | None) -> None:
    """The added cells' table under the verdicts (nothing when nothing was added)."""
    added = (statistics or {}).get("added")
    if not added:
        return
    table = Table(title=_title(added))
    for h in _COLUMNS:
        table.add_column(h, overflow="fold")
    for line in _lines(added):
        table.add_row(*line)
    Console().print(table)


def markdown_added(statistics: Mapping[str, Any] | None) -> str:
    """The same as markdown lines ('' when nothing was added)."""
    added = (statistics or {}).get("added")
    if not added:
        return ""
    title = _title(added)
    rows = [_COLUMNS, ["---"] * len(_COLUMNS), *_lines(added)]
    return f"\n{title[0].upper()}{title[1:]}:\n\n" + "".join(
        "| " + " | ".join(r) + " |\n" for r in rows)
