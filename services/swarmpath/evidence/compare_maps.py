"""Statistics of a map study (planners x maps), as :mod:`swarmpath.evidence.compare` does for
benchmarks.

Pure functions over run records (``RunOutcome.to_dict()`` dicts, or any mapping with the keys
``planner``, ``map``, ``success``, ``length``, ``seconds``), shared by ``swarmpath plan`` and the
service. Per map, every planner against the reference planner (default: the last one listed):

* **path length**: Wilcoxon rank-sum test over the *successful* runs only (a failed run's length
  measures how far it got, not a path; the same rule as the summaries), shorter is better;
* **planning time** (``seconds``): Wilcoxon rank-sum test over all runs, less is better;
* **success rate**: Fisher's exact test on (successes, runs), higher is better.

Each measure is its own Holm family over the table (maps x planners other than the reference).
Over the maps, the Friedman test ranks the planners by mean length (maps where a planner never
succeeded are left out) and by mean planning time. A planner without successful runs on a map
has no length test there (marker None). Values that are not finite numbers count as missing.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from swarmpath.evidence.compare import ALPHA, Comparison, Friedman, compare_samples, compare_success
from swarmpath.evidence.compare import friedman as friedman_test

__all__ = ["MEASURES", "MapStatistics", "map_statistics"]

#: The compared measures, in print order.
MEASURES = ("success", "length", "seconds")


@dataclass(frozen=True)
class MapStatistics:
    comparisons: dict[str, Comparison]  # measure -> its table of tests
    friedman: dict[str, Friedman]  # "length", "seconds" -> the test over the maps

    @property
    def reference(self) -> str:
        return self.comparisons["length"].reference

    def marker(self, measure: str, map_name: str, planner: str) -> str | None:
        return self.comparisons[measure].marker(map_name, planner)

    def to_json(self) -> dict[str, Any]:
        """JSON-ready (no NaN or inf: None instead)."""
        return _finite({
            "reference": self.reference,
            "comparisons": {m: c.to_json(key_fields=("map",)) for m, c in
                            self.comparisons.items()},
            "friedman": {m: f.to_json() for m, f in self.friedman.items()},
        })


def _finite(v: Any) -> Any:
    if isinstance(v, float):
        return v if math.isfinite(v) else None
    if isinstance(v, dict):
        return {k: _finite(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_finite(x) for x in v]
    return v


def _number(v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float):
        return math.nan
    return float(v) if math.isfinite(v) else math.nan


def _mean(xs: list[float]) -> float:
    vals = [x for x in xs if not math.isnan(x)]
    return sum(vals) / len(vals) if vals else math.nan


def map_statistics(
    runs: Iterable[Mapping[str, Any]],
    planners: Sequence[str] | None = None,
    reference: str | None = None,
    alpha: float = ALPHA,
) -> MapStatistics:
    """The tests of a map study; ``planners`` default to their order of first appearance."""
    length: dict[str, dict[str, list[float]]] = {}
    seconds: dict[str, dict[str, list[float]]] = {}
    success: dict[str, dict[str, list[int]]] = {}
    seen: dict[str, None] = {}
    for r in runs:
        p, m = str(r.get("planner")), str(r.get("map"))
        seen.setdefault(p)
        ok = r.get("success") is True
        counts = success.setdefault(m, {}).setdefault(p, [0, 0])
        counts[0] += ok
        counts[1] += 1
        seconds.setdefault(m, {}).setdefault(p, []).append(_number(r.get("seconds")))
        lengths = length.setdefault(m, {}).setdefault(p, [])
        if ok:
            lengths.append(_number(r.get("length")))
    names = list(planners) if planners is not None else list(seen)
    comparisons = {
        "success": compare_success(
            {m: {p: (c[0], c[1]) for p, c in v.items()} for m, v in success.items()},
            names, reference, alpha),
        "length": compare_samples(length, names, reference, alpha),
        "seconds": compare_samples(seconds, names, reference, alpha),
    }
    ref = comparisons["length"].reference
    fried = {
        measure: friedman_test({m: {p: _mean(v) for p, v in per.items()}
                                for m, per in table.items()}, names, ref, alpha)
        for measure, table in (("length", length), ("seconds", seconds))
    }
    return MapStatistics(comparisons, fried)
