"""A published table beside the measured one: verdict per cell, counts, the JSON document.

Pure functions over :mod:`swarmpath.evidence.reference` (the published tables and the reviewed
reasons) and measured runs (per-run best values of a benchmark cell; per-run outcomes of a map
cell). ``swarmpath reproduce`` runs the study and calls these.

Benchmark cells compare the measured mean with the published avg on a log scale:
``log10(measured / published)``, computed on ``f - f_min`` (so F8, whose minimum is
-418.98 x dim, compares gaps to the optimum; for every other function f_min = 0) with both
values raised to the function's floating-point floor (the value its kernel returns at the
optimum, times 4; the smallest normal float where that is 0), so that two values at the floor
give 0. Verdict: ``matches`` within one decade, ``better`` / ``worse`` beyond it, and
``not comparable`` when the published avg is illegible or contradicts its own min/max.

Map cells compare the mean executed length of the successful runs with the published mean
distance: ``matches`` within 10 %, else ``better`` (shorter) or ``worse``. ``not comparable``:
lengths in other units (RFO-GWO's), a published static-goal distance shorter than the straight
line from start to goal, or no successful run.

A cell off by more than the tolerance is explained when ``reasons.yaml`` has its key, or --
benchmark cells only -- when every measured run lies inside the published [min, max] (the
averages then differ only by the weight of a few bad runs in a mean over many, see
:func:`inside_published_range`); otherwise it is counted as unexplained.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from swarmpath.evidence.reference import BenchmarkTable, MapTable, Reason, cell_key
from swarmpath.evidence.stats import describe
from swarmpath.functions import get_function

DECADE = 1.0
MAP_TOLERANCE = 0.10
MATCHES, BETTER, WORSE, NOT_COMPARABLE = "matches", "better", "worse", "not comparable"
VERDICTS = (MATCHES, BETTER, WORSE, NOT_COMPARABLE)
#: map-table column -> the run-outcome field measuring it (absent: no measured counterpart)
MEASURED_FIELD = {"distance_m": "length", "error_m": "error"}
#: what a map row keeps of each run outcome (enough to judge the cell again: ``--from``)
OUTCOME_FIELDS = ("run", "success", "length", "error", "seconds", "collisions", "optimum",
                  "reason")


@dataclass(frozen=True)
class Row:
    """One cell of a reproduction (benchmark: who = algorithm, where = function; map: who =
    planner, where = map)."""

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

    @property
    def unexplained(self) -> bool:
        return self.verdict in (BETTER, WORSE) and self.reason is None

    def to_json(self, kind: str) -> dict[str, Any]:
        ident = ({"function": self.where, "dim": self.dim, "algorithm": self.who}
                 if kind == "benchmark" else {"planner": self.who, "map": self.where})
        return {
            **ident, "published": self.published, "measured": self.measured,
            "runs": self.runs, "log10_ratio": self.log10_ratio, "verdict": self.verdict,
            "reason": self.reason, "evidence": self.evidence, "unexplained": self.unexplained,
            **self.extra,
        }


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


def verdict_of(ratio: float | None, tolerance: float) -> str:
    if ratio is None or math.isnan(ratio):
        return NOT_COMPARABLE
    if abs(ratio) <= tolerance:
        return MATCHES
    return BETTER if ratio < 0 else WORSE


def inconsistent(cell: Mapping[str, float | None]) -> bool:
    """The printed avg contradicts the printed min/max of the same cell."""
    lo, hi, avg = cell.get("min"), cell.get("max"), cell.get("avg")
    if avg is None:
        return False
    return (lo is not None and avg < lo) or (hi is not None and avg > hi)


def benchmark_rows(
    table: BenchmarkTable,
    runs: Mapping[tuple[str, str], Sequence[float]],
    reasons: Mapping[str, Reason],
) -> list[Row]:
    """One row per (function, algorithm) of ``table`` that has measured ``runs``, table order."""
    dim = table.dim
    rows = []
    for function in table.functions:
        fmin = get_function(function).f_min_for(dim)
        floor = function_floor(function, dim)
        for algorithm in table.algorithms:
            values = runs.get((function, algorithm))
            if values is None:
                continue
            published = dict(table.cells[(function, algorithm)])
            measured = describe(values)
            key = cell_key(table.name, algorithm, function, dim)
            auto: str | None = None
            ratio: float | None = None
            if published["avg"] is None:
                auto = "the published avg is illegible in the seed text"
            elif inconsistent(published):
                note = table.note_for(function, algorithm) or ""
                auto = f"the published cell contradicts itself: {note}".rstrip(": ")
            else:
                ratio = log10_ratio(measured["avg"] - fmin, published["avg"] - fmin, floor)
            verdict = verdict_of(ratio, DECADE)
            if verdict in (BETTER, WORSE):
                auto = inside_published_range(published, values, fmin, floor)
            reason = reasons.get(key)
            text = reason.reason if reason is not None else auto
            evidence = reason.evidence if reason is not None else (
                "the measured runs of this cell (--json: runs)" if auto and ratio is not None
                else None)
            rows.append(Row(
                key, algorithm, function, dim, published, measured,
                [float(v) for v in values],
                None if ratio is None else round(ratio, 3), verdict,
                text if verdict != MATCHES or reason is not None else None,
                evidence if verdict != MATCHES or reason is not None else None, {},
            ))
    return rows


def inside_published_range(
    published: Mapping[str, float | None], values: Sequence[float], fmin: float, floor: float
) -> str | None:
    """The automatic explanation of an average more than a decade off: every measured run lies
    inside the published [min, max] (a published min at the floor admits any run down to it).
    Then the averages differ only by how the few worst of the published runs weigh in a mean
    of many runs (COOT-family averages over 1000 runs sit near max / 1000)."""
    lo, hi = published.get("min"), published.get("max")
    if lo is None or hi is None or not values:
        return None
    lo_gap, hi_gap = lo - fmin, max(hi - fmin, floor)
    gaps = [v - fmin for v in values]
    if all((lo_gap <= floor or g >= lo_gap) and g <= hi_gap for g in gaps):
        avg = published["avg"]
        weight = ""
        if avg is not None and avg - fmin > 0 and hi_gap / (avg - fmin) >= 10:
            weight = f"; the published avg is max / {hi_gap / (avg - fmin):.0f}"
        return (f"all {len(values)} measured runs lie inside the published [min, max]{weight}: "
                "the averages differ by the weight of rare bad runs, not by the runs' range")
    return None


def straight_line(scenario: Any) -> float:
    return math.dist(scenario.start, scenario.goal)


def map_rows(
    table: MapTable,
    outcomes: Mapping[tuple[str, str], Sequence[Mapping[str, Any]]],
    reasons: Mapping[str, Reason],
    scenarios: Mapping[str, Any],
) -> list[Row]:
    """One row per (planner, map) of ``table`` that has measured ``outcomes``, table order."""
    rows = []
    column = table.compare
    for (planner, map_name), cell in table.cells.items():
        runs = outcomes.get((planner, map_name))
        if runs is None:
            continue
        published: dict[str, float | None] = {"avg": cell.mean[column]}
        printed = cell.runs.get(column)
        if printed:
            p = describe(printed)
            published.update(min=p["min"], max=p["max"], std=p["std"])
        for other, value in cell.mean.items():
            if other != column:
                published[other] = value
        ok = [r for r in runs if r.get("success")]
        field_ = MEASURED_FIELD.get(column)
        # the executed lengths are shown even when the published column has no counterpart
        values = [float(r[field_ or "length"]) for r in ok]
        measured = describe(values) if values else None
        optima = [float(r["optimum"]) for r in runs if r.get("optimum") is not None]
        extra = {
            "success": f"{len(ok)}/{len(runs)}",
            "seconds_median": float(np.median([float(r.get("seconds") or 0.0) for r in runs])),
            "collisions": int(sum(int(r.get("collisions") or 0) for r in runs)),
            "optimum": float(np.mean(optima)) if optima else None,
            "outcomes": [{k: r.get(k) for k in OUTCOME_FIELDS} for r in runs],
        }
        scenario = scenarios[map_name]
        line = straight_line(scenario)
        auto: str | None = None
        ratio: float | None = None
        if field_ is None:
            auto = f"published in {table.columns[column]!r}, which has no measured counterpart"
        elif measured is None:
            auto = "no successful run"
        elif scenario.goal_motion is None and cell.mean[column] < line:
            auto = (f"the published mean {cell.mean[column]:.4f} m is shorter than the "
                    f"{line:.4f} m straight line from start to goal")
        else:
            ratio = math.log10(measured["avg"] / cell.mean[column])
        if ratio is not None and abs(10**ratio - 1.0) <= MAP_TOLERANCE:
            verdict = MATCHES  # within 10 % either way
        else:
            verdict = verdict_of(ratio, 0.0)
        key = cell_key(table.name, planner, map_name)
        reason = reasons.get(key)
        text = reason.reason if reason is not None else auto
        rows.append(Row(
            key, planner, map_name, None, published, measured, values,
            None if ratio is None else round(ratio, 4), verdict,
            text if verdict != MATCHES or reason is not None else None,
            reason.evidence if reason is not None else None, extra,
        ))
    return rows


def counts(rows: Sequence[Row], order: Sequence[str]) -> dict[str, dict[str, int]]:
    """Per algorithm or planner (in ``order``): how many cells got each verdict."""
    out = {who: dict.fromkeys(VERDICTS, 0) for who in order}
    for r in rows:
        out.setdefault(r.who, dict.fromkeys(VERDICTS, 0))[r.verdict] += 1
    return out


def summary_line(rows: Sequence[Row]) -> str:
    return f"{len(rows)} cells, {sum(r.unexplained for r in rows)} unexplained"


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
