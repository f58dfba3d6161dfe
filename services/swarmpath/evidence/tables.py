"""The paper-style benchmark table as a model, drawn in the terminal (rich) or as LaTeX.

One row dict per (algorithm, function, dim) cell, the same fields for ``swarmpath bench`` (from
its runs, :func:`study_rows`) and for a job's REST summary (its rows): the statistics of
:func:`swarmpath.evidence.stats.describe`, ``origin_suspect``, the test against the reference
(``marker``, ``p_holm``), its effect sizes (``a12``, ``shift``, ``shift_low``, ``shift_high``),
the Bayesian posterior (``p_better``, ``p_equivalent``, ``p_worse``, ``verdict``) and whether
the cell is the best or statistically similar to it (``best``, ``similar``); a raced study's
rows add ``race_*`` (:data:`swarmpath.evidence.race_report.RACE_COLUMNS`).

:func:`benchmark_grid` lays them out: per function and dimension the rows min, max and the
location and spread of ``--stat`` (avg and std, or median and iqr), then, with a reference, the
rows A12, shift, 95 % CI and P(b/e/w) (a raced study: A12, A paired, P(b/e/w) and race); one
column per algorithm. Pure functions, no I/O.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from rich import box
from rich.table import Table
from rich.text import Text

#: After the best location of each function and dimension, and after those not significantly
#: worse than it (both bold).
BEST_MARK, SIMILAR_MARK = "*", "~"
#: The rows of each function and dimension, per --stat.
STAT_ROWS = {"mean": ("min", "max", "avg", "std"), "median": ("min", "max", "median", "iqr")}
EFFECT_ROWS = ("A12", "shift", "95% CI", "P(b/e/w)")
#: A raced study's rows after the location and spread (evidence.race_report): no fixed-sample
#: interval; the race's paired score with its confidence-sequence interval, and per cell its
#: runs, its decision against the reference and the round it stopped in.
RACE_ROWS = ("A12", "A paired", "P(b/e/w)", "race")
#: Every row name that carries no location (no marks, no marker).
NOTE_ROWS = frozenset(EFFECT_ROWS + RACE_ROWS)
_DECISIONS = {"different": "diff", "equivalent": "equiv", "open": "open", "futile": "futile"}


@dataclass(frozen=True)
class TCell:
    """One printed cell: its text, bold or not, its marks (*, ~, °) and its +/=/- marker."""

    text: str
    bold: bool = False
    marks: str = ""
    marker: str | None = None


@dataclass
class Grid:
    """A table: header, alignment per column ("l"/"r"), rows, and the rows ending a section."""

    header: list[str]
    align: list[str]
    rows: list[list[TCell]] = field(default_factory=list)
    section_ends: set[int] = field(default_factory=set)
    #: the marks used, so a renderer can pad every cell of a column to the same width
    mark_width: int = 0
    markers: bool = False
    #: the leading columns that are labels (function, dim, statistic; or map, planner)
    labels: int = 3


def format_value(v: float | None, digits: int = 2) -> str:
    """Scientific notation as in the papers (6.59E-28); exact zero as 0; inf as inf."""
    if v is None:
        return "-"
    if isinstance(v, str):  # JSON's "inf" / "nan"
        v = float(v)
    if v == 0:
        return "0"
    if not math.isfinite(v):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")
    return f"{v:.{digits}E}"


def _num(v: Any) -> float | None:
    if v is None or isinstance(v, bool):
        return None
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def effect_text(row: Mapping[str, Any], name: str, digits: int = 2) -> str:
    """The text of effect row ``name`` for one cell (blank when not tested)."""
    if name == "A12":
        a = _num(row.get("a12"))
        return "" if a is None else f"{a:.2f}"
    if name == "shift":
        s = _num(row.get("shift"))
        return "" if s is None else format_value(s, digits)
    if name == "95% CI":
        lo, hi = _num(row.get("shift_low")), _num(row.get("shift_high"))
        if lo is None or hi is None:
            return ""
        return f"[{format_value(lo, digits)}, {format_value(hi, digits)}]"
    if name == "A paired":
        theta, lo, hi = (_num(row.get(k)) for k in ("race_theta", "race_low", "race_high"))
        if theta is None:
            return ""
        return f"{theta:.2f}" + ("" if lo is None or hi is None else f" [{lo:.2f}, {hi:.2f}]")
    if name == "race":
        return race_text(row)
    ps = [_num(row.get(k)) for k in ("p_better", "p_equivalent", "p_worse")]
    if any(p is None for p in ps):
        return ""
    return "/".join(f"{p:.2f}" for p in ps if p is not None)


def race_text(row: Mapping[str, Any]) -> str:
    """A raced cell's runs, decision against the reference and stopping round: ``40 diff r3``
    (the reference: ``40 r3``), ``60 open racing`` while it races on."""
    runs = row.get("race_runs")
    if runs is None:
        return ""
    decision = row.get("race_decision")
    word = "" if decision is None else _DECISIONS.get(str(decision), str(decision)) + " "
    stop = row.get("race_round")
    when = "racing" if row.get("race_state") == "racing" or stop is None else f"r{stop}"
    return f"{runs} {word}{when}"


def benchmark_grid(
    rows: Sequence[Mapping[str, Any]],
    algorithms: Sequence[str],
    stat: str = "mean",
    digits: int = 2,
    compared: bool = True,
    reference: str | None = None,
) -> Grid:
    """The table of ``rows`` (module doc); ``compared``: show markers and effect rows."""
    by_key = {(r["function"], int(r["dim"]), r["algorithm"]): r for r in rows}
    groups = list(dict.fromkeys((r["function"], int(r["dim"])) for r in rows))
    stats = STAT_ROWS[stat]
    loc_name = stats[2]
    origin = any(r.get("origin_suspect") for r in rows)
    raced = any(r.get("race_runs") is not None for r in rows)
    notes = RACE_ROWS if raced else EFFECT_ROWS
    grid = Grid(["F", "D", "", *algorithms], ["l", "r", "l", *("r" * len(algorithms))],
                mark_width=2 if origin else 1, markers=compared and len(algorithms) > 1)
    from swarmpath.evidence.audit import ORIGIN_MARK

    for function, dim in groups:
        present = [by_key.get((function, dim, a)) for a in algorithms]
        lines = list(stats)
        if grid.markers:
            lines += list(notes)
        for i, name in enumerate(lines):
            cells = []
            for a, r in zip(algorithms, present, strict=True):
                if r is None:
                    cells.append(TCell("-"))
                    continue
                if name in notes:
                    shown = a != reference or name == "race"
                    cells.append(TCell(effect_text(r, name, digits) if shown else ""))
                    continue
                text = format_value(_num(r.get(name)), digits)
                if name != loc_name:
                    cells.append(TCell(text))
                    continue
                marks = (BEST_MARK if r.get("best") else SIMILAR_MARK if r.get("similar")
                         else "")
                if origin and r.get("origin_suspect"):
                    marks = (marks or " ") + ORIGIN_MARK
                bold = bool(r.get("best") or r.get("similar"))
                cells.append(TCell(text, bold, marks, r.get("marker") if grid.markers else None))
            first = i == 0
            grid.rows.append([TCell(function if first else ""), TCell(str(dim) if first else ""),
                              TCell(name), *cells])
        grid.section_ends.add(len(grid.rows) - 1)
    return grid


def to_rich(grid: Grid, title: str | None = None, caption: str | None = None) -> Table:
    """The grid as a rich Table: every number followed by the same number of mark characters
    (and a marker column of 2) so that marked cells align."""
    table = Table(title=title, caption=caption, box=box.SIMPLE_HEAD, pad_edge=False)
    for name, align in zip(grid.header, grid.align, strict=True):
        table.add_column(name, justify="right" if align == "r" else "left", no_wrap=True)
    for i, row in enumerate(grid.rows):
        effect = row[2].text in NOTE_ROWS
        texts = [Text(c.text) for c in row[:3]]
        for c in row[3:]:
            s = c.text
            if not effect:
                s += c.marks.ljust(grid.mark_width)
                if grid.markers:
                    s += " " + (c.marker or " ")
            texts.append(Text(s, style="bold") if c.bold else Text(s))
        table.add_row(*texts, end_section=i in grid.section_ends)
    return table


def study_rows(cells: Iterable[Any], tests: Any = None, origin: bool = False
               ) -> list[dict[str, Any]]:
    """The row dicts of a study's ``report.Cell`` objects with ``report.Statistics``."""
    from swarmpath.evidence.audit import origin_suspect

    out = []
    index = tests.bayes.index() if tests is not None and tests.bayes is not None else {}
    race = None
    if tests is not None and getattr(tests, "race", None):
        from swarmpath.evidence.race_report import cell_fields

        race = cell_fields(tests.race, tests.reference)
    for c in cells:
        key = (c.function, c.dim)
        row: dict[str, Any] = {"algorithm": c.algorithm, "function": c.function, "dim": c.dim,
                               **c.stats}
        if origin:
            row["origin_suspect"] = origin_suspect(c.function, c.best_fitness)
        if tests is not None:
            row.update(test_fields(tests, key, c.algorithm, index))
            if race:
                row.update(race.get((c.function, c.dim, c.algorithm), ({}, None))[0])
        out.append(row)
    mark_best(out, tests.stat if tests is not None else "mean")
    return out


def test_fields(tests: Any, key: tuple[str, int], algorithm: str,
                index: Mapping[tuple[Any, str], Any] | None = None) -> dict[str, Any]:
    """A cell's marker, p-values, effect sizes, posterior and best/similar flags."""
    t = tests.comparison.get(key, algorithm)
    shift = None if t is None else t.shift
    post = (index if index is not None else tests.bayes.index() if tests.bayes else {}).get(
        (key, algorithm))
    similar = tests.similar.get(key, set())
    return {
        "marker": None if t is None else t.marker, "p": None if t is None else t.p,
        "p_holm": None if t is None else t.p_holm, "a12": None if t is None else t.a12,
        "shift": None if shift is None else shift.estimate,
        "shift_low": None if shift is None else shift.low,
        "shift_high": None if shift is None else shift.high,
        "p_better": None if post is None else post.p_better,
        "p_equivalent": None if post is None else post.p_equivalent,
        "p_worse": None if post is None else post.p_worse,
        "verdict": None if post is None else post.verdict,
        "similar": algorithm in similar,
    } | {"best": False}


def mark_best(rows: list[dict[str, Any]], stat: str, similar: bool = True) -> None:
    """Set ``best`` on the rows with the lowest location of their (function, dim) (ties all);
    ``similar`` stays as the tests set it (False without them)."""
    groups: dict[tuple[str, int], list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault((r["function"], int(r["dim"])), []).append(r)
    for group in groups.values():
        values = [_num(r.get("median" if stat == "median" else "avg")) for r in group]
        finite = [v for v in values if v is not None and not math.isnan(v)]
        low = min(finite) if finite else None
        for r, v in zip(group, values, strict=True):
            r["best"] = low is not None and v == low
            r["similar"] = bool(r.get("similar")) and not r["best"] if similar else False


def map_grid(rows: Sequence[Mapping[str, Any]], planners: Sequence[str],
             reference: str | None = None) -> Grid:
    """A map study's comparison (the REST summary's map rows, or ``plan``'s in the same shape):
    per map and planner the success rate, mean length, gap and time, each with its +/=/- marker,
    A12 and Bayesian P(b/e/w) against the reference."""
    header = ["Map", "Planner", "Success"]
    for label in ("Length (m)", "Gap (%)", "Time (s)"):
        header += [label, "A12", "P(b/e/w)"]
    grid = Grid(header, ["l", "l", *("r" * (len(header) - 2))], markers=True, labels=2)
    maps = list(dict.fromkeys(r["map"] for r in rows))
    by_cell = {(r["map"], r["planner"]): r for r in rows}
    for m in maps:
        present = [p for p in planners if (m, p) in by_cell]
        for j, p in enumerate(present):
            r = by_cell[(m, p)]
            rate = _num(r.get("success_rate"))
            cells = [TCell(m if j == 0 else ""), TCell(p),
                     TCell("-" if rate is None else f"{100 * rate:.0f}%",
                           marker=r.get("success_marker"))]
            for measure, key, scale, digits in (("length", "length_mean", 1.0, 3),
                                                ("gap", "gap_mean", 100.0, 2),
                                                ("seconds", "seconds_mean", 1.0, 3)):
                v = _num(r.get(key))
                a12 = _num(r.get(f"{measure}_a12"))
                ps = [_num(r.get(f"{measure}_{k}")) for k in
                      ("p_better", "p_equivalent", "p_worse")]
                cells += [TCell("-" if v is None else f"{scale * v:.{digits}f}",
                                marker=r.get(f"{measure}_marker")),
                          TCell("" if p == reference or a12 is None else f"{a12:.2f}"),
                          TCell("" if p == reference or any(x is None for x in ps) else
                                "/".join(f"{x:.2f}" for x in ps if x is not None))]
            grid.rows.append(cells)
        grid.section_ends.add(len(grid.rows) - 1)
    return grid
