"""Summary statistics of a study's runs, as the papers' tables report them.

``describe`` gives min, max, avg, std, median, the quartiles q1 and q3 and the interquartile
range iqr = q3 - q1 of the best fitness of the runs; ``std`` is the sample standard deviation
(ddof=1, MATLAB's ``std``), the quartiles interpolate linearly between order statistics (numpy's
default, R's type 7). ``rank`` orders algorithms by their average (or median: ``--stat``).

Infinite values (a run that never evaluated a finite point) are handled without NaN or warnings:
any infinite value makes ``avg`` infinite and ``std`` infinite, unless every value is identical
(then ``std`` is 0). Only +inf and -inf together leave ``avg`` undefined (NaN); NaN input is not
expected (the optimizers report NaN objective values as +inf).
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

#: Significance level of the statistical tests (:mod:`swarmpath.evidence.compare`); here so
#: that modules which only name it do not load scipy.stats.
ALPHA = 0.05

__all__ = ["STATS", "describe", "json_clean", "json_number", "location", "rank",
           "resolve_reference", "spread"]

#: The statistic a table reports and ranks by (``--stat``): mean with std, or median with IQR.
STATS = ("mean", "median")


def location(stats: Mapping[str, float], stat: str = "mean") -> float:
    """The cell's avg (stat mean) or median from its :func:`describe`."""
    return stats["median" if stat == "median" else "avg"]


def spread(stats: Mapping[str, float], stat: str = "mean") -> float:
    """std (stat mean) or iqr (stat median) from :func:`describe`."""
    return stats["iqr" if stat == "median" else "std"]


def describe(values: ArrayLike) -> dict[str, float]:
    """min, max, avg, std (ddof=1; 0.0 for one value), median, q1, q3 and iqr of ``values``
    (any shape)."""
    x = np.asarray(values, dtype=float).ravel()
    if x.size == 0:
        raise ValueError("describe() needs at least one value")
    if np.isnan(x).any():
        raise ValueError("describe() got NaN values")
    lo, hi = float(x.min()), float(x.max())
    if lo == hi:  # identical values (incl. all inf): exact, no rounding noise in avg or std
        return {"min": lo, "max": hi, "avg": lo, "std": 0.0, "median": lo, "q1": lo, "q3": lo,
                "iqr": 0.0}
    finite = np.isfinite(x)
    if finite.all():
        with np.errstate(over="ignore", invalid="ignore"):
            avg = float(np.mean(x))
            std = float(np.std(x, ddof=1))
        if not (math.isfinite(avg) and math.isfinite(std)):
            # The sum or the squares overflowed (values near 1e308): compute on a scaled copy.
            scale = max(abs(lo), abs(hi))
            avg = float(np.mean(x / scale)) * scale
            std = float(np.std(x / scale, ddof=1)) * scale
    else:
        has_pos, has_neg = bool(np.any(x == np.inf)), bool(np.any(x == -np.inf))
        avg = math.nan if has_pos and has_neg else (math.inf if has_pos else -math.inf)
        std = math.inf
    with np.errstate(over="ignore", invalid="ignore"):  # median of {-inf, +inf} is NaN
        median = float(np.median(x))
    if not math.isfinite(median) and finite.all():  # the two middle values overflowed their sum
        middle = np.sort(x)[(x.size - 1) // 2 : x.size // 2 + 1]
        median = float(middle[0] / 2 + middle[-1] / 2)
    ordered = np.sort(x)
    q1, q3 = _quantile(ordered, 0.25), _quantile(ordered, 0.75)
    iqr = 0.0 if q1 == q3 else q3 - q1
    return {"min": lo, "max": hi, "avg": avg, "std": std, "median": median, "q1": q1, "q3": q3,
            "iqr": iqr}


def _quantile(ordered: np.ndarray, q: float) -> float:
    """Linear interpolation between order statistics (numpy's default), exact for inf."""
    h = (ordered.size - 1) * q
    below, above = float(ordered[math.floor(h)]), float(ordered[math.ceil(h)])
    if below == above:
        return below
    return below + (above - below) * (h - math.floor(h))


def rank(avgs: Mapping[str, float]) -> dict[str, int]:
    """Competition ranks of the averages: 1 = lowest; equal values share the smaller rank
    (1, 2, 2, 4). NaN ranks after everything else. Keys keep the order of ``avgs``."""
    values = {k: float(v) for k, v in avgs.items()}
    ordered = sorted(v for v in values.values() if not math.isnan(v))
    out: dict[str, int] = {}
    for key, v in values.items():
        if math.isnan(v):
            out[key] = len(ordered) + 1
        else:
            out[key] = 1 + bisect.bisect_left(ordered, v)  # how many are strictly lower
    return out


def resolve_reference(algorithms: Sequence[str], reference: str | None = None) -> str:
    """The reference among ``algorithms``: ``reference`` (exact name, else case-insensitive) or,
    when None, the last one. Raises ValueError naming the valid choices."""
    if not algorithms:
        raise ValueError("no algorithms to compare")
    if reference is None:
        return algorithms[-1]
    if reference in algorithms:
        return reference
    by_lower = {a.lower(): a for a in algorithms}
    if reference.lower() in by_lower:
        return by_lower[reference.lower()]
    names = ", ".join(algorithms)
    raise ValueError(f"{reference!r} is not one of the compared algorithms ({names})")


def json_number(v: float) -> float | str:
    """JSON has no inf/NaN: they are written as the strings "inf", "-inf", "nan"
    (Python's float() reads them back); finite values stay numbers (round-trip exact)."""
    v = float(v)
    if math.isfinite(v):
        return v
    return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")


def json_clean(v: Any) -> Any:
    """``v`` with every float (in dicts and lists, at any depth) as :func:`json_number`."""
    if isinstance(v, float):
        return json_number(v)
    if isinstance(v, dict):
        return {k: json_clean(x) for k, x in v.items()}
    if isinstance(v, list):
        return [json_clean(x) for x in v]
    return v
