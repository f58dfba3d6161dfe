"""Difficulty curves: success and gap per MovingAI scenario bucket (pure, no I/O).

A MovingAI ``.scen`` file groups its start/goal pairs into *buckets* by the octile length of their
optimal path (bucket b holds lengths in [4b, 4b + 4) on the benchmark sets of Sturtevant 2012,
"Benchmarks for Grid-Based Pathfinding", IEEE TCIAIG 4(2)); the field reports a planner's success
and path quality per bucket, so a difficulty curve shows where it stops coping. ``swarmpath plan
--scen`` records each map's bucket; :func:`bucket_rows` summarizes the runs per planner and
bucket, :func:`swarmpath.evidence.plots.difficulty_figure` draws the curve. The service counts
its runs per cell (summaries, dashboard) and calls :func:`bucket_curve`, which both share.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

__all__ = ["BucketCell", "bucket_curve", "bucket_rows"]


def _finite(v: Any) -> float | None:
    if v is None or isinstance(v, bool):
        return None
    try:
        f = float(v)
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) else None


def bucket_rows(runs: Iterable[Mapping[str, Any]],
                buckets: Mapping[str, int]) -> list[dict[str, Any]]:
    """One row per (planner, bucket), planners in order of appearance, buckets ascending:
    ``planner``, ``bucket``, ``pairs`` (maps of that bucket the planner ran), ``runs``,
    ``successes``, ``success_rate``, and over the successful runs with an exact optimum
    ``gap_median`` and ``gap_mean`` (None when there is none). Runs on maps without a bucket
    are left out."""
    cells: dict[tuple[str, str], BucketCell] = {}
    for r in runs:
        name = str(r.get("map"))
        bucket = buckets.get(name)
        if bucket is None:
            continue
        key = (str(r.get("planner")), name)
        cell = cells.get(key)
        if cell is None:
            cell = cells[key] = BucketCell(key[0], name, int(bucket))
        cell.runs += 1
        if r.get("success") is True:
            cell.successes += 1
            gap = _finite(r.get("gap"))
            if gap is not None:
                cell.gaps.append(gap)
    return bucket_curve(cells.values())


@dataclass
class BucketCell:
    """What the difficulty curve needs of one planner x map: its bucket, the runs, the
    successful ones and their gaps (those with an exact optimum)."""

    planner: str
    map: str
    bucket: int
    runs: int = 0
    successes: int = 0
    gaps: list[float] = field(default_factory=list)


def bucket_curve(cells: Iterable[BucketCell]) -> list[dict[str, Any]]:
    """The rows of :func:`bucket_rows` from cells already counted (the service's summaries and
    dashboard keep their runs per cell): the gaps of a bucket's maps are pooled, so the median
    is over its successful runs, not a median of medians. Cells without runs are left out."""
    groups: dict[tuple[str, int], list[BucketCell]] = {}
    planners: list[str] = []
    for cell in cells:
        if cell.runs <= 0:
            continue
        if cell.planner not in planners:
            planners.append(cell.planner)
        groups.setdefault((cell.planner, int(cell.bucket)), []).append(cell)
    out = []
    for planner in planners:
        for bucket in sorted(b for p, b in groups if p == planner):
            group = groups[(planner, bucket)]
            runs = sum(c.runs for c in group)
            ok = sum(c.successes for c in group)
            gaps = [g for c in group for g in c.gaps]
            out.append({
                "planner": planner, "bucket": bucket,
                "pairs": len({c.map for c in group}), "runs": runs,
                "successes": ok, "success_rate": ok / runs,
                "gap_median": statistics.median(gaps) if gaps else None,
                "gap_mean": statistics.fmean(gaps) if gaps else None,
            })
    return out
