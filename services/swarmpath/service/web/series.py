"""The dashboard's plain functions over numpy arrays: the log-spaced curve grid and curve
sampling, interquartile bands, box-plot statistics, path thinning and failure kinds (used by
:mod:`swarmpath.service.web.aggregates`, which re-exports them)."""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from swarmpath.failure_classes import known_class

GRID_POINTS = 64  # iterations sampled per convergence curve
PATH_POINTS = 150  # points kept per map path
MAX_OUTLIERS = 40  # outliers listed per box (the most extreme ones)


def curve_grid(iterations: int, points: int = GRID_POINTS) -> np.ndarray:
    """Iteration numbers 1..iterations, log-spaced, first and last included, unique, ascending."""
    if iterations < 1:
        raise ValueError("iterations must be >= 1")
    raw = np.geomspace(1.0, float(iterations), num=min(points, iterations))
    grid = np.unique(np.rint(raw).astype(np.int64))
    grid[0], grid[-1] = 1, iterations
    return np.unique(grid)


def sample_curve(curve: Sequence[float], grid: np.ndarray, stride: int = 1) -> np.ndarray:
    """The curve's values at the grid's iterations (``curve[i]`` = best after iteration i + 1).

    A thinned curve (``stride`` > 1: samples 0, s, 2s, ... plus the last one) is read at the
    latest sample at or before each iteration, which for a best-so-far curve is an upper bound.
    Iterations past the curve's end take its last value."""
    values = np.asarray(curve, dtype=np.float64)
    if values.size == 0:
        return np.full(grid.shape, np.nan)
    index = grid - 1  # 0-based iteration index
    if stride > 1:
        length = int(grid[-1])  # the unthinned curve has one value per iteration
        regular = (length - 1) // stride + 1
        at = np.arange(values.size, dtype=np.int64) * stride
        if values.size == regular + 1:  # the last value was appended after the regular ones
            at[-1] = length - 1
        pos = np.searchsorted(at, index, side="right") - 1
    else:
        pos = index
    return values[np.clip(pos, 0, values.size - 1)]


def band(rows: np.ndarray) -> dict[str, list[float]]:
    """Per column of ``rows`` (runs x points): the median and the interquartile range (25th and
    75th percentiles, linear interpolation). Columns of all-NaN give NaN."""
    if rows.shape[0] == 0:
        nan = [math.nan] * rows.shape[1]
        return {"median": nan, "q1": list(nan), "q3": list(nan)}
    x = rows.astype(np.float64)
    if np.isnan(x).any():  # nanquantile works column by column: only when needed
        with warnings.catch_warnings():  # an all-NaN column (no run sent a curve) gives NaN
            warnings.simplefilter("ignore", RuntimeWarning)
            q1, med, q3 = np.nanquantile(x, [0.25, 0.5, 0.75], axis=0)
    else:
        with np.errstate(invalid="ignore"):
            q1, med, q3 = np.quantile(x, [0.25, 0.5, 0.75], axis=0)
    return {"median": med.tolist(), "q1": q1.tolist(), "q3": q3.tolist()}


def box_stats(values: Sequence[float] | np.ndarray) -> dict[str, Any] | None:
    """Tukey box plot of the finite values: quartiles, whiskers at the most extreme values within
    1.5 IQR of the box, outliers beyond (at most MAX_OUTLIERS, the most extreme), mean, n.
    None without a finite value."""
    x = np.asarray(values, dtype=np.float64)
    x = np.sort(x[np.isfinite(x)])
    if x.size == 0:
        return None
    q1, med, q3 = (float(v) for v in np.quantile(x, [0.25, 0.5, 0.75]))
    iqr = q3 - q1
    inside = x[(x >= q1 - 1.5 * iqr) & (x <= q3 + 1.5 * iqr)]
    out = x[(x < q1 - 1.5 * iqr) | (x > q3 + 1.5 * iqr)]
    if out.size > MAX_OUTLIERS:
        order = np.argsort(-np.abs(out - med), kind="stable")[:MAX_OUTLIERS]
        out = np.sort(out[order])
    return {
        "n": int(x.size), "min": float(x[0]), "max": float(x[-1]), "mean": float(x.mean()),
        "q1": q1, "median": med, "q3": q3,
        "lo": float(inside[0]), "hi": float(inside[-1]), "outliers": out.tolist(),
    }


def thin_path(path: Sequence[Sequence[float]], points: int = PATH_POINTS) -> list[list[float]]:
    """At most ``points`` rows [x, y, t] of a path, evenly spaced, first and last kept, rounded
    to a millimetre (and a millisecond)."""
    p = np.asarray(path, dtype=np.float64).reshape(-1, 3) if len(path) else np.zeros((0, 3))
    if p.shape[0] > points:
        idx = np.unique(np.linspace(0, p.shape[0] - 1, points).round().astype(np.int64))
        p = p[idx]
    return np.round(p, 3).tolist()


def _number(v: Any) -> float | None:
    if isinstance(v, bool) or not isinstance(v, int | float):
        return None
    return float(v) if math.isfinite(v) else None


def failure_kind(metrics: Mapping[str, Any]) -> str:
    """Why a map run failed, in one word: its ``failure_class`` (:mod:`swarmpath.planners.
    failures`: collision, oscillating, boxed-in, progressing, ...); for runs recorded without
    one, from the reason: collision, stall (the planner gave up or stopped moving), timeout
    (time or step limit), or other."""
    kind = known_class(metrics.get("failure_class"))
    if kind is not None:
        return kind
    reason = str(metrics.get("reason") or "")
    if (_number(metrics.get("collisions")) or 0) > 0 or reason.startswith("collided"):
        return "collision"
    if "gave up" in reason or "stall" in reason:
        return "stall"
    if "limit" in reason:
        return "timeout"
    return "other"
