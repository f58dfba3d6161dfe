"""A published table beside the measured one: verdict per cell, counts, the JSON document.

Pure functions over :mod:`swarmpath.evidence.reference` (the published tables and the reviewed
reasons) and measured runs (per-run best values of a benchmark cell; per-run outcomes of a map
cell). ``swarmpath reproduce`` runs the study and calls these; the statistics of a verdict are
:mod:`swarmpath.evidence.verdicts` (table-agnostic).

Benchmark cells are compared on ``f - f_min`` (so F8, whose minimum is -418.98 x dim, compares
gaps to the optimum; for every other function f_min = 0), every value raised to the function's
floating-point floor (the value its kernel returns at the optimum, times 4; the smallest normal
float where that is 0; a table's ``setting.error_floor`` where larger, e.g. COCO's final
target 1e-8 for bbob errors), so that two values at the floor are equal. The log ratio is
``log10(measured mean / published mean)``; the tolerance is one decade, except for F8 (a factor
1.1, :data:`TOLERANCE`): F8's gap of a random point is only about twice a typical published
gap, so a decade around it (0 to -11,900 at 30 dims) accepts every run an optimizer can end
with, while its runs spread by about 10 % of the gap (published std / gap: 7-15 %).

Map cells: :mod:`swarmpath.evidence.reproduction_maps`.

Verdicts (:mod:`~swarmpath.evidence.verdicts`): ``consistent``, ``matches``, ``better``,
``worse``, ``not comparable``. A ``better`` or ``worse`` cell is explained only by a reviewed
reason (``reasons.yaml``) that holds for it (:func:`reason_holds`): the reason states the
direction it explains and, where it explains a tail, the exceedance; otherwise the cell is
counted as unexplained.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from swarmpath.evidence.audit import decades_lost
from swarmpath.evidence.prints import contradiction
from swarmpath.evidence.reference import BenchmarkTable, MapTable, Reason, cell_key
from swarmpath.evidence.stats import describe
from swarmpath.evidence.verdicts import (
    BETTER,
    CONSISTENT,
    DIFFERENT,
    MATCHES,
    NOT_COMPARABLE,
    VERDICTS,
    WORSE,
    Exceedance,
    judge,
)
from swarmpath.functions import get_function

__all__ = [
    "BETTER",
    "CONSISTENT",
    "MATCHES",
    "NOT_COMPARABLE",
    "VERDICTS",
    "WORSE",
    "Row",
    "benchmark_rows",
    "document",
    "reason_holds",
    "summary_line",
]

DECADE = 1.0
#: Tolerance in decades of the functions not compared within a decade (see the module doc).
TOLERANCE: dict[str, float] = {"F8": math.log10(1.1)}


@dataclass(frozen=True)
class Row:
    """One cell of a reproduction (benchmark: who = algorithm, where = function; map: who =
    planner, where = map). ``reason``: the reviewed reason's text, or the note why the cell is
    not comparable; ``claim``: the reviewed reason (None without one); ``holds``: it holds for
    this cell's verdict and exceedance."""

    key: str
    who: str
    where: str
    dim: int | None
    published: dict[str, float | None]
    measured: dict[str, float] | None
    runs: list[float]
    log10_ratio: float | None
    verdict: str
    reason: str | None
    evidence: str | None
    extra: dict[str, Any]
    #: the 95 % bootstrap interval of the measured mean (the table's units)
    interval: tuple[float, float] | None = None
    exceedance: Exceedance | None = None
    claim: Reason | None = None
    holds: bool = False
    tolerance: tuple[float, float] | None = field(default=None, compare=False)

    @property
    def unexplained(self) -> bool:
        return self.verdict in DIFFERENT and not self.holds

    def to_json(self, kind: str) -> dict[str, Any]:
        ident = ({"function": self.where, "dim": self.dim, "algorithm": self.who}
                 if kind == "benchmark" else {"planner": self.who, "map": self.where})
        return {
            **ident, "published": self.published, "measured": self.measured,
            "runs": self.runs, "log10_ratio": self.log10_ratio,
            "tolerance_log10": None if self.tolerance is None else list(self.tolerance),
            "interval95": None if self.interval is None else list(self.interval),
            "exceedance": None if self.exceedance is None else self.exceedance.to_json(),
            "verdict": self.verdict, "reason": self.reason, "evidence": self.evidence,
            "reason_explains": None if self.claim is None else self.claim.direction,
            "reason_exceedance": None if self.claim is None else self.claim.exceedance,
            "reason_holds": self.holds,
            "unexplained": self.unexplained, **self.extra,
        }


def reason_holds(reason: Reason, verdict: str, exceedance: Exceedance | None) -> bool:
    """A reviewed reason explains a cell only in the direction it states (``better``,
    ``worse`` or ``not comparable``) and, when it states an exceedance, only when the runs
    show it: ``none`` -- no departure from the published range on either side; ``above`` /
    ``below`` -- the runs depart beyond the published max / min (and not on the other side)."""
    if reason.direction != verdict:
        return False
    if reason.exceedance is None:
        return True
    if exceedance is None:
        return False
    if reason.exceedance == "none":
        return not exceedance.departs()
    other = "below" if reason.exceedance == "above" else "above"
    return exceedance.side_departs(reason.exceedance) and not exceedance.side_departs(other)


def explained(reason: Reason | None, verdict: str, exceedance: Exceedance | None,
               auto: str | None) -> dict[str, Any]:
    """The Row fields reason, evidence, claim, holds."""
    if reason is None:
        return {"reason": auto, "evidence": None, "claim": None, "holds": False}
    return {"reason": reason.reason, "evidence": reason.evidence, "claim": reason,
            "holds": reason_holds(reason, verdict, exceedance)}


def function_floor(function: str, dim: int) -> float:
    """The smallest gap to f_min that the function's kernel resolves: 4 x its value above f_min
    at the optimum (Ackley's 4.4e-16 -> 1.8e-15, covering MATLAB's 8.9e-16), at least the
    smallest normal float."""
    fn = get_function(function)
    at_optimum = float(fn.evaluate(fn.optimum(dim)[None, :])[0]) - fn.f_min_for(dim)
    return max(4.0 * abs(at_optimum), float(np.finfo(float).tiny))


def log10_ratio(measured: float, published: float, floor: float) -> float:
    """log10 of measured / published gaps, both raised to ``floor`` (gaps are >= 0; an
    infinite measured mean gives +inf)."""
    if math.isnan(measured):
        return math.nan
    if math.isinf(measured):
        return math.inf if measured > 0 else -math.inf
    return math.log10(max(measured, floor)) - math.log10(max(published, floor))


def tolerance_for(function: str) -> float:
    """How many decades a benchmark cell's mean may differ and still match."""
    return TOLERANCE.get(function, DECADE)


def not_comparable(table: BenchmarkTable, function: str, algorithm: str) -> str | None:
    """Why the published cell cannot be compared (None: it can)."""
    published = table.cells[(function, algorithm)]
    if algorithm in table.derived:
        return f"the published {algorithm} column is not a measurement: {table.derived[algorithm]}"
    if published["avg"] is None:
        return "the published avg is illegible in the seed text"
    why = table.contradicts.get(f"{function}/{algorithm}") or contradiction(
        published, int(table.setting["runs"]), get_function(function).f_min_for(table.dim))
    if why is not None:
        note = table.note_for(function, algorithm)
        return f"the published cell contradicts itself: {why}" + (f" ({note})" if note else "")
    return None


def _gap(value: float | None, fmin: float) -> float | None:
    return None if value is None else value - fmin


def benchmark_rows(
    table: BenchmarkTable,
    runs: Mapping[tuple[str, str], Sequence[float]],
    reasons: Mapping[str, Reason],
    shifted: Mapping[tuple[str, str], Sequence[float]] | None = None,
) -> list[Row]:
    """One row per (function, algorithm) of ``table`` that has measured ``runs``, table order.
    ``shifted``: the same runs with the function shifted (``--transform shift``); each row
    then carries them and its decades lost (``extra``; :func:`audit.shift_suspect`)."""
    dim = table.dim
    rows = []
    for function in table.functions:
        fmin = get_function(function).f_min_for(dim)
        # a table may state the precision its errors were recorded at (bbob: COCO's 1e-8)
        floor = max(function_floor(function, dim), float(table.setting.get("error_floor", 0.0)))
        tol = tolerance_for(function)
        for algorithm in table.algorithms:
            values = runs.get((function, algorithm))
            if values is None:
                continue
            published = dict(table.cells[(function, algorithm)])
            measured = describe(values)
            key = cell_key(table.name, algorithm, function, dim)
            auto = not_comparable(table, function, algorithm)
            ratio: float | None = None
            verdict, interval, exc = NOT_COMPARABLE, None, None
            if auto is None and published["avg"] is not None:
                ratio = log10_ratio(measured["avg"] - fmin, published["avg"] - fmin, floor)
                j = judge([v - fmin for v in values], published["avg"] - fmin, key, ratio,
                          (-tol, tol), low=_gap(published["min"], fmin),
                          high=_gap(published["max"], fmin),
                          n_paper=int(table.setting["runs"]), floor=floor)
                verdict, exc = j.verdict, j.exceedance
                if j.interval is not None:  # in the table's units (F8: f, not the gap)
                    interval = (j.interval[0] + fmin, j.interval[1] + fmin)
            extra: dict[str, Any] = {}
            moved = (shifted or {}).get((function, algorithm))
            if moved is not None:
                extra = {"shifted_runs": [float(v) for v in moved],
                         "decades_lost_shift": round(decades_lost(function, dim, values,
                                                                  moved), 3)}
            rows.append(Row(
                key, algorithm, function, dim, published, measured,
                [float(v) for v in values],
                None if ratio is None else round(ratio, 3), verdict,
                extra=extra, interval=interval, exceedance=exc, tolerance=(-tol, tol),
                **explained(reasons.get(key), verdict, exc, auto),
            ))
    return rows


def counts(rows: Sequence[Row], order: Sequence[str]) -> dict[str, dict[str, int]]:
    """Per algorithm or planner (in ``order``): how many cells got each verdict."""
    out = {who: dict.fromkeys(VERDICTS, 0) for who in order}
    for r in rows:
        out.setdefault(r.who, dict.fromkeys(VERDICTS, 0))[r.verdict] += 1
    return out


def summary_line(rows: Sequence[Row]) -> str:
    """``N cells, M unexplained, K consistent``."""
    return (f"{len(rows)} cells, {sum(r.unexplained for r in rows)} unexplained, "
            f"{sum(r.verdict == CONSISTENT for r in rows)} consistent")


def document(
    table: BenchmarkTable | MapTable,
    setting: Mapping[str, Any],
    rows: Sequence[Row],
    statistics: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """The ``--json`` document."""
    order = table.algorithms if isinstance(table, BenchmarkTable) else table.planners
    doc: dict[str, Any] = {
        "table": table.name,
        "source": table.source,
        "published_setting": table.setting,
        "setting": dict(setting),
        "cells": [r.to_json(table.kind) for r in rows],
        "counts": counts(rows, order),
        "unexplained": sum(r.unexplained for r in rows),
        "consistent": sum(r.verdict == CONSISTENT for r in rows),
        "notes": list(table.notes),
    }
    if statistics is not None:
        doc["statistics"] = dict(statistics)
    return _json_safe(doc)


def _json_safe(v: Any) -> Any:
    """inf and NaN as the strings "inf", "-inf", "nan" (JSON has no such numbers)."""
    if isinstance(v, float) and not math.isfinite(v):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")
    if isinstance(v, dict):
        return {k: _json_safe(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_json_safe(x) for x in v]
    return v

