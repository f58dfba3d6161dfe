"""Wide tables that fit the terminal: a summary with 48 columns printed as one rich table had
every header cut to ``…`` even at 400 columns (issue 25). Here the columns are split into
several tables, each repeating the row's identity columns (planner and map, or algorithm,
function and dimension) and each no wider than the console; no header or cell is ever cut.
Columns empty in every row are left out and named under the tables."""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence
from typing import Any

from rich.cells import cell_len
from rich.table import Table

#: Columns that name a row; repeated in every part of a split table.
IDENTITY = ("algorithm", "function", "dim", "planner", "map", "id")
#: A column's width beyond its content in rich's default table (a space each side, one rule).
_COLUMN_OVERHEAD = 3


def _width(name: str, cells: Sequence[str]) -> int:
    return max([cell_len(name), *(cell_len(c) for c in cells)]) + _COLUMN_OVERHEAD


def split_columns(columns: Sequence[str], cells: dict[str, list[str]], width: int
                  ) -> list[list[str]]:
    """The columns in groups, in their order, each group preceded by the identity columns and
    no wider than ``width`` (a column wider than that on its own gets a group of its own)."""
    keys = [c for c in columns if c in IDENTITY]
    rest = [c for c in columns if c not in IDENTITY]
    base = 1 + sum(_width(c, cells[c]) for c in keys)  # 1: the table's closing rule
    groups: list[list[str]] = []
    used = width
    for c in rest:
        w = _width(c, cells[c])
        if not groups or used + w > width:
            groups.append([*keys])
            used = base
        groups[-1].append(c)
        used += w
    return groups or [keys]


def fitted_tables(title: str, columns: Sequence[str], rows: Sequence[dict[str, Any]],
                  width: int, cell: Callable[[Any], str], left: Collection[str] = ()
                  ) -> tuple[list[Table], list[str]]:
    """Rich tables showing every non-empty column of ``rows`` whole, each at most ``width``
    wide, and the names of the columns left out because no row has a value in them."""
    cells = {c: [cell(r.get(c)) for r in rows] for c in columns}
    empty = [c for c in columns if rows and c not in IDENTITY and not any(cells[c])]
    shown = [c for c in columns if c not in empty]
    groups = split_columns(shown, cells, width)
    tables = []
    for i, group in enumerate(groups):
        part = f" ({i + 1}/{len(groups)})" if len(groups) > 1 else ""
        table = Table(title=title + part, title_justify="left")
        for c in group:
            table.add_column(c, justify="left" if c in left else "right", no_wrap=True)
        for j in range(len(rows)):
            table.add_row(*(cells[c][j] for c in group))
        tables.append(table)
    return tables, empty
