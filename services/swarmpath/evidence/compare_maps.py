"""Statistics of a map study (planners x maps), as :mod:`swarmpath.evidence.compare` does for
benchmarks.

Pure functions over run records (``RunOutcome.to_dict()`` dicts, or any mapping with the keys
``planner``, ``map``, ``success``, ``length``, ``seconds``), shared by ``swarmpath plan`` and the
service. Per map, every planner against the reference planner (default: the last one listed):

* **path length**: Wilcoxon rank-sum test over the *successful* runs only (a failed run's length
  measures how far it got, not a path; the same rule as the summaries), shorter is better;
* **gap** to the exact optimum (length / optimum - 1): the same over the successful runs of maps
  that have an optimum (none with moving obstacles), smaller is better;
* **planning time** (``seconds``): Wilcoxon rank-sum test over all runs, less is better;
* **success rate**: Fisher's exact test on (successes, runs), higher is better.

Each measure is its own Holm family over the table (maps x planners other than the reference);
every rank-sum test carries its effect sizes (A12, Hodges-Lehmann shift with its 95 % interval:
:mod:`swarmpath.evidence.effect`), and length, gap and time get the Bayesian comparison with a
declared rope (:mod:`swarmpath.evidence.bayes`: per map and, over the maps, the signed-rank test).
Over the maps, the Friedman test ranks the planners by mean length (maps where a planner never
succeeded are left out) and by mean planning time. A planner without successful runs on a map
has no length test there (marker None). Values that are not finite numbers count as missing.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from swarmpath.evidence.bayes import DEFAULT_ROPE, BayesComparison, Rope, compare_bayes
from swarmpath.evidence.compare import ALPHA, Comparison, Friedman, compare_samples, compare_success
from swarmpath.evidence.compare import friedman as friedman_test

__all__ = ["MEASURES", "SAMPLED", "MapStatistics", "map_statistics"]

#: The compared measures, in print order.
MEASURES = ("success", "length", "gap", "seconds")
#: The measures with samples (rank-sum tests, effect sizes, Bayesian comparison).
SAMPLED = ("length", "gap", "seconds")


@dataclass(frozen=True)
class MapStatistics:
    comparisons: dict[str, Comparison]  # measure -> its table of tests
    friedman: dict[str, Friedman]  # "length", "seconds" -> the test over the maps
    bayes: dict[str, BayesComparison] = field(default_factory=dict)  # length, gap, seconds

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
            "bayes": {m: b.to_json(("map",)) for m, b in self.bayes.items()},
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
    rope: Rope | None = None,
    stat: str = "mean",
) -> MapStatistics:
    """The tests of a map study; ``planners`` default to their order of first appearance;
    ``rope`` and ``stat``: the Bayesian comparison's (default: 1 % relative, mean)."""
    length: dict[str, dict[str, list[float]]] = {}
    gap: dict[str, dict[str, list[float]]] = {}
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
        gaps = gap.setdefault(m, {}).setdefault(p, [])
        if ok:
            lengths.append(_number(r.get("length")))
            g = _number(r.get("gap"))
            if not math.isnan(g):
                gaps.append(g)
    names = list(planners) if planners is not None else list(seen)
    comparisons = {
        "success": compare_success(
            {m: {p: (c[0], c[1]) for p, c in v.items()} for m, v in success.items()},
            names, reference, alpha),
        "length": compare_samples(length, names, reference, alpha),
        "gap": compare_samples(gap, names, reference, alpha),
        "seconds": compare_samples(seconds, names, reference, alpha),
    }
    ref = comparisons["length"].reference
    fried = {
        measure: friedman_test({m: {p: _mean(v) for p, v in per.items()}
                                for m, per in table.items()}, names, ref, alpha)
        for measure, table in (("length", length), ("seconds", seconds))
    }
    posterior = {
        measure: compare_bayes(table, names, ref, rope or DEFAULT_ROPE, stat)
        for measure, table in (("length", length), ("gap", gap), ("seconds", seconds))
    }
    return MapStatistics(comparisons, fried, posterior)
