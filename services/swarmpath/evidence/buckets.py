"""Difficulty curves: success and gap per MovingAI scenario bucket (pure, no I/O).

A MovingAI ``.scen`` file groups its start/goal pairs into *buckets* by the octile length of their
optimal path (bucket b holds lengths in [4b, 4b + 4) on the benchmark sets of Sturtevant 2012,
"Benchmarks for Grid-Based Pathfinding", IEEE TCIAIG 4(2)); the field reports a planner's success
and path quality per bucket, so a difficulty curve shows where it stops coping. ``swarmpath plan
--scen`` records each map's bucket; :func:`bucket_rows` summarizes the runs per planner and
bucket, :func:`swarmpath.evidence.plots.difficulty_figure` draws the curve.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Iterable, Mapping
from typing import Any

__all__ = ["bucket_rows"]


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
    cells: dict[tuple[str, int], list[Mapping[str, Any]]] = {}
    planners: list[str] = []
    for r in runs:
        bucket = buckets.get(str(r.get("map")))
        if bucket is None:
            continue
        planner = str(r.get("planner"))
        if planner not in planners:
            planners.append(planner)
        cells.setdefault((planner, int(bucket)), []).append(r)
    out = []
    for planner in planners:
        for bucket in sorted(b for p, b in cells if p == planner):
            rows = cells[(planner, bucket)]
            ok = [r for r in rows if r.get("success") is True]
            gaps = [g for g in (_finite(r.get("gap")) for r in ok) if g is not None]
            out.append({
                "planner": planner, "bucket": bucket,
                "pairs": len({r.get("map") for r in rows}), "runs": len(rows),
                "successes": len(ok), "success_rate": len(ok) / len(rows),
                "gap_median": statistics.median(gaps) if gaps else None,
                "gap_mean": statistics.fmean(gaps) if gaps else None,
            })
    return out
