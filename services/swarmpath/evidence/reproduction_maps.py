"""The map half of a reproduction: a published map table's cells beside measured planner runs.

Map cells compare the mean executed length of the successful runs with the published mean
distance, within 10 % either way (:data:`MAP_TOLERANCE`); the printed runs (ten per cell) are
the paper's range for the exceedance test. A table whose lengths are in units we cannot
reconstruct (``relative_to: PLANNER`` in its file, RFO-GWO's) compares each planner's length
relative to that planner's on the same map -- measured runs over the measured mean of the
reference planner, against the published ratio of means -- so that a ranking the paper reports
can fail. ``not comparable``: lengths in other units without a reference planner, the
reference planner's own cells, a published static-goal distance shorter than the straight line
from start to goal, or no successful run.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from swarmpath.evidence.reference import MapTable, Reason, cell_key
from swarmpath.evidence.reproduction import Row, explained
from swarmpath.evidence.stats import describe
from swarmpath.evidence.verdicts import NOT_COMPARABLE, judge

MAP_TOLERANCE = 0.10
#: map-table column -> the run-outcome field measuring it (absent: no measured counterpart)
MEASURED_FIELD = {"distance_m": "length", "error_m": "error"}
#: what a map row keeps of each run outcome (enough to judge the cell again: ``--from``)
OUTCOME_FIELDS = ("run", "success", "length", "error", "seconds", "collisions", "optimum",
                  "reason")


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
    band = (math.log10(1.0 - MAP_TOLERANCE), math.log10(1.0 + MAP_TOLERANCE))
    relative_to = table.extra.get("relative_to")
    for (planner, map_name), cell in table.cells.items():
        runs = outcomes.get((planner, map_name))
        if runs is None:
            continue
        ok = [r for r in runs if r.get("success")]
        field_ = MEASURED_FIELD.get(column)
        # the executed lengths are shown even when the published column has no counterpart
        lengths = [float(r[field_ or "length"]) for r in ok]
        optima = [float(r["optimum"]) for r in runs if r.get("optimum") is not None]
        extra: dict[str, Any] = {
            "success": f"{len(ok)}/{len(runs)}",
            "seconds_median": float(np.median([float(r.get("seconds") or 0.0) for r in runs])),
            "collisions": int(sum(int(r.get("collisions") or 0) for r in runs)),
            "optimum": float(np.mean(optima)) if optima else None,
            "outcomes": [{k: r.get(k) for k in OUTCOME_FIELDS} for r in runs],
        }
        published = _published(cell, column)
        target: float | None = cell.mean[column]
        values = lengths
        auto: str | None = None
        if field_ is None and relative_to:
            values, target, auto = _relative(table, outcomes, planner, map_name, lengths)
            published = {"avg": target, **{k: v for k, v in published.items() if k != "avg"},
                         column: cell.mean[column]}
            if lengths:
                extra["length_m"] = float(np.mean(lengths))
        elif field_ is None:
            auto = f"published in {table.columns[column]!r}, which has no measured counterpart"
        measured = describe(values) if values else None
        line = straight_line(scenarios[map_name])
        ratio: float | None = None
        if auto is not None:
            pass
        elif measured is None or target is None:
            auto = "no successful run"
        elif scenarios[map_name].goal_motion is None and field_ and target < line:
            auto = (f"the published mean {target:.4f} m is shorter than the "
                    f"{line:.4f} m straight line from start to goal")
        else:
            ratio = math.log10(measured["avg"] / target)
        key = cell_key(table.name, planner, map_name)
        verdict, interval, exc = NOT_COMPARABLE, None, None
        if ratio is not None and target is not None:
            printed = cell.runs.get(column)
            j = judge(values, target, key, ratio, band, low=published.get("min"),
                      high=published.get("max"), n_paper=len(printed or []))
            verdict, interval, exc = j.verdict, j.interval, j.exceedance
        rows.append(Row(
            key, planner, map_name, None, published, measured, values,
            None if ratio is None else round(ratio, 4), verdict, extra=extra,
            interval=interval, exceedance=exc, tolerance=band,
            **explained(reasons.get(key), verdict, exc, auto),
        ))
    return rows


def _published(cell: Any, column: str) -> dict[str, float | None]:
    """The printed mean of the compared column (and the min/max/std of its printed runs), then
    the other columns' means."""
    published: dict[str, float | None] = {"avg": cell.mean[column]}
    printed = cell.runs.get(column)
    if printed:
        p = describe(printed)
        published.update(min=p["min"], max=p["max"], std=p["std"])
    for other, value in cell.mean.items():
        if other != column:
            published[other] = value
    return published


def _relative(
    table: MapTable,
    outcomes: Mapping[tuple[str, str], Sequence[Mapping[str, Any]]],
    planner: str,
    map_name: str,
    lengths: Sequence[float],
) -> tuple[list[float], float | None, str | None]:
    """Each run's length over the reference planner's mean length on the map, the published
    ratio of means, and why the cell cannot be compared (None: it can)."""
    reference = str(table.extra["relative_to"])
    column = table.compare
    base = [float(r["length"]) for r in outcomes.get((reference, map_name), [])
            if r.get("success")]
    if not base:
        return [], None, f"no successful run of {reference}, the reference of the ratios"
    if planner == reference:  # its own runs over its mean, shown beside the others' ratios
        return [x / float(np.mean(base)) for x in lengths], None, (
            f"the reference of the length ratios (published in {table.columns[column]!r}, "
            "which has no measured counterpart)")
    published = table.cells[(planner, map_name)].mean[column]
    ratio = published / table.cells[(reference, map_name)].mean[column]
    mean = float(np.mean(base))
    return [x / mean for x in lengths], ratio, None
