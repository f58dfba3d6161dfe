"""Summaries of planning runs, one row per (planner, map): the papers' "Mean" row and more.

Pure functions over run records (``RunOutcome.to_dict()`` dicts, or any mapping with the same
keys), shared by ``swarmpath plan`` and the REST service. Rules:

* ``success_rate``, ``collisions`` (total; by cause ``robot_driven_contacts`` and
  ``obstacle_driven_contacts``, see :func:`swarmpath.metrics.contact_causes`), ``error_*``,
  ``seconds_*``, ``iterations_mean`` and ``steps_mean`` are over **all** runs;
* ``length_*``, ``gap_*``, ``smoothness_mean``, ``travel_time_mean`` and the field's path
  metrics (:data:`PATH_METRICS`: each the mean of the runs' values) are over the **successful**
  runs only (a failed run's length measures how far it got, not a path), and are ``None`` when
  no run succeeded; ``cpu_seconds_*`` (the planner's CPU time) are over all runs, beside the
  wall time ``seconds_*``;
* ``std`` is the sample standard deviation (ddof=1, 0 for one value), as in
  :func:`swarmpath.evidence.stats.describe`;
* ``min_clearance`` is the smallest over all runs; every value is JSON-safe (no NaN or inf:
  ``None`` instead).

``failures`` counts the runs per failure reason (empty when every run succeeded) and
``failure_classes`` per class of :mod:`swarmpath.planners.failures` (why they failed).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

from swarmpath.evidence.stats import describe
from swarmpath.failure_classes import count_classes
from swarmpath.path_metrics import PATH_METRICS

__all__ = ["PATH_METRICS", "finite_or_none", "json_safe", "path_metric_means", "summarize",
           "summarize_cell"]


def finite_or_none(value: Any) -> float | None:
    """A finite float, or None (for None, NaN and +-inf)."""
    if value is None:
        return None
    v = float(value)
    return v if math.isfinite(v) else None


def json_safe(value: Any) -> Any:
    """A copy of ``value`` with every non-finite float replaced by None (lists, tuples, dicts)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Mapping):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v) for v in value]
    return value


def _stats(values: list[float]) -> dict[str, float | None]:
    vals = [v for v in values if v is not None and math.isfinite(v)]
    if not vals:
        return {"mean": None, "std": None, "median": None, "min": None, "max": None}
    d = describe(vals)
    return {"mean": d["avg"], "std": d["std"], "median": d["median"], "min": d["min"],
            "max": d["max"]}


def _get(run: Any, key: str) -> Any:
    if isinstance(run, Mapping):
        return run.get(key)
    return getattr(run, key, None)


def _mean(values: Iterable[Any]) -> float | None:
    vals = [float(v) for v in values if finite_or_none(v) is not None]
    return sum(vals) / len(vals) if vals else None


def path_metric_means(successful: Iterable[Any]) -> dict[str, float | None]:
    """Mean of each of :data:`PATH_METRICS` and of ``travel_time`` over ``successful`` runs
    (None where no run has a finite value)."""
    rows = list(successful)
    out = {key: _mean(_get(r, key) for r in rows) for key in PATH_METRICS}
    out["travel_time_mean"] = _mean(_get(r, "travel_time") for r in rows)
    return out


def summarize_cell(runs: Iterable[Any]) -> dict[str, Any]:
    """One summary row for runs of a single (planner, map); see the module docstring."""
    rows = list(runs)
    if not rows:
        raise ValueError("summarize_cell() needs at least one run")
    ok = [r for r in rows if bool(_get(r, "success"))]
    length = _stats([float(_get(r, "length")) for r in ok])
    gap = _stats([_get(r, "gap") for r in ok if _get(r, "gap") is not None])
    error = _stats([float(_get(r, "error")) for r in rows])
    seconds = _stats([float(_get(r, "seconds")) for r in rows])
    cpu = _stats([float(_get(r, "cpu_seconds") or 0.0) for r in rows])
    smooth = _stats([float(_get(r, "smoothness")) for r in ok])
    maybe = [finite_or_none(_get(r, "min_clearance")) for r in rows]
    clearances = [c for c in maybe if c is not None]
    failures: dict[str, int] = {}
    for r in rows:
        if not _get(r, "success"):
            reason = str(_get(r, "reason") or "failed")
            failures[reason] = failures.get(reason, 0) + 1
    optimum = finite_or_none(_get(rows[0], "optimum"))
    return json_safe({
        "planner": _get(rows[0], "planner"),
        "map": _get(rows[0], "map"),
        "runs": len(rows),
        "successes": len(ok),
        "success_rate": len(ok) / len(rows),
        "collisions": sum(int(_get(r, "collisions") or 0) for r in rows),
        "robot_driven_contacts": sum(int(_get(r, "robot_driven_contacts") or 0) for r in rows),
        "obstacle_driven_contacts": sum(int(_get(r, "obstacle_driven_contacts") or 0)
                                        for r in rows),
        "length_mean": length["mean"],
        "length_std": length["std"],
        "length_median": length["median"],
        "length_min": length["min"],
        "length_max": length["max"],
        "error_mean": error["mean"],
        "seconds_mean": seconds["mean"],
        "seconds_median": seconds["median"],
        "cpu_seconds_mean": cpu["mean"],
        "cpu_seconds_median": cpu["median"],
        "iterations_mean": sum(float(_get(r, "iterations") or 0) for r in rows) / len(rows),
        "steps_mean": sum(float(_get(r, "steps") or 0) for r in rows) / len(rows),
        "smoothness_mean": smooth["mean"],
        "min_clearance": min(clearances) if clearances else None,
        "optimum": optimum,
        "gap_mean": gap["mean"],
        "gap_median": gap["median"],
        "gap_max": gap["max"],
        **path_metric_means(ok),
        "failures": failures,
        "failure_classes": count_classes(_get(r, "failure_class") for r in rows
                                         if not _get(r, "success")),
    })


def summarize(runs: Iterable[Any]) -> list[dict[str, Any]]:
    """Summary rows per (planner, map), in the order each pair first appears in ``runs``."""
    cells: dict[tuple[Any, Any], list[Any]] = {}
    for r in runs:
        cells.setdefault((_get(r, "planner"), _get(r, "map")), []).append(r)
    return [summarize_cell(rows) for rows in cells.values()]
