"""Anytime performance, as COCO and IOHanalyzer report it: pure numpy, no I/O.

A run's trace is its best-so-far error ``f - f*`` (so F8, whose minimum is negative, works on a
log scale like every other function) after each recorded number of function evaluations
(:func:`swarmpath.evidence.ioh.evaluation_points` maps swarmpath's iterations to evaluations).

* **Targets**: IOHanalyzer's default (``get_ECDF_targets(type = "log-linear",
  number_targets = 10)`` in R/DataSetList.R, through ``seq_FV``): 10 values log-spaced between
  the smallest and the largest positive error recorded by any run of any algorithm on the
  function and dimension, both ends included, the smallest raised to 1e-12;
  ``targets="bbob"``: COCO's 51 fixed targets 10^2 ... 10^-8 (5 per decade).
* **Runtime** of a run for a target: the first recorded evaluation count at which its error is
  at most the target (IOHanalyzer's ``get_RT``, ``<=``); infinite when never reached.
* **ECDF**: the share of (run, target) pairs reached within a budget, as a function of the
  budget (the runtime ECDF aggregated over targets). **AUC**: its area over budgets 0 .. B
  divided by B (B: the largest budget of the function and dimension, so algorithms compare on
  one scale), i.e. the mean over pairs of max(0, 1 - runtime / B): IOHanalyzer's
  ``generate_data.AUC`` (normalised, linear budgets) computed exactly rather than by the
  trapezoid rule on 50 points. 1 would be every target at the first evaluation.
* **ERT** of a target (COCO; IOHanalyzer's ``SP``): the evaluations spent by all runs until
  they reached it or stopped, divided by the runs that reached it (infinite when none did),
  with a percentile bootstrap interval over the runs (:data:`RESAMPLES` resamples drawn from
  ``numpy.random.default_rng(seed)``; a resample without a success has an infinite ERT).
* **Fixed budget**: the error each run had reached after a budget (its last record at or
  before it; infinite before its first record), summarised by median and mean over runs;
  budgets log-spaced between the first record and the largest budget.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = [
    "AnytimeCell", "RunTrace", "anytime_group", "bbob_targets", "default_targets", "ecdf_auc",
    "ert", "ert_interval", "fixed_budget", "runtimes",
]

#: IOHanalyzer's default number of log-linear ECDF targets and its lowest log target.
IOH_TARGETS = 10
TARGET_FLOOR = 1e-12
RESAMPLES = 1000
LEVEL = 0.95
#: Budgets of the fixed-budget table and points of the ECDF curve (IOHanalyzer samples 50).
BUDGETS = 5
ECDF_POINTS = 50


@dataclass(frozen=True)
class RunTrace:
    """One run: evaluation counts (strictly increasing) and the best-so-far error after each."""

    evaluations: np.ndarray
    errors: np.ndarray

    @property
    def budget(self) -> int:
        return int(self.evaluations[-1]) if self.evaluations.size else 0


def default_targets(traces: Iterable[RunTrace], number: int = IOH_TARGETS) -> np.ndarray:
    """IOHanalyzer's default targets (module doc), descending (easiest first)."""
    values = [t.errors[np.isfinite(t.errors) & (t.errors > 0)] for t in traces]
    positive = np.concatenate(values) if values else np.empty(0)
    lo = max(TARGET_FLOOR, float(positive.min())) if positive.size else TARGET_FLOOR
    hi = max(TARGET_FLOOR, float(positive.max())) if positive.size else TARGET_FLOOR
    # geomspace keeps both ends exact: the best value recorded is a target that run reaches
    return np.unique(np.geomspace(lo, hi, number))[::-1]


def bbob_targets() -> np.ndarray:
    """COCO's 51 targets 10^2 ... 10^-8, five per decade, descending."""
    return 10.0 ** np.linspace(2.0, -8.0, 51)


def _best_so_far(t: RunTrace) -> np.ndarray:
    return np.minimum.accumulate(np.where(np.isnan(t.errors), np.inf, t.errors))


def runtimes(traces: Sequence[RunTrace], targets: np.ndarray) -> np.ndarray:
    """(runs, targets): the first evaluation count with error <= target (inf: never)."""
    out = np.full((len(traces), targets.size), np.inf)
    for i, t in enumerate(traces):
        if not t.errors.size:
            continue
        best = _best_so_far(t)
        # best is non-increasing: the first index with best <= target, by a search on -best
        idx = np.searchsorted(-best, -targets, side="left")
        hit = idx < best.size
        out[i, hit] = t.evaluations[idx[hit]]
    return out


def ecdf_auc(times: np.ndarray, budget: float) -> float:
    """Area under the runtime ECDF over budgets 0 .. ``budget``, divided by ``budget``."""
    if times.size == 0 or budget <= 0:
        return math.nan
    return float(np.mean(np.clip(1.0 - times / budget, 0.0, None)))


def ecdf_curve(times: np.ndarray, budgets: np.ndarray) -> np.ndarray:
    """The share of (run, target) pairs reached within each budget."""
    flat = np.sort(times.ravel())
    return np.searchsorted(flat, budgets, side="right") / max(1, flat.size)


def ert(times: np.ndarray, budgets: np.ndarray) -> float:
    """Expected running time of one target: ``times`` (runs,) and each run's budget."""
    hits = np.isfinite(times) & (times <= budgets)
    if not hits.any():
        return math.inf
    return float(np.sum(np.where(hits, times, budgets)) / hits.sum())


def ert_interval(times: np.ndarray, budgets: np.ndarray, seed: int = 0,
                 resamples: int = RESAMPLES, level: float = LEVEL) -> tuple[float, float]:
    """Percentile bootstrap interval of :func:`ert` over the runs."""
    n = times.size
    if n == 0:
        return math.nan, math.nan
    idx = np.random.default_rng(seed).integers(0, n, size=(resamples, n))
    t, b = times[idx], budgets[idx]
    hits = np.isfinite(t) & (t <= b)
    spent = np.sum(np.where(hits, t, b), axis=1)
    count = hits.sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        values = np.sort(np.where(count > 0, spent / np.maximum(count, 1), np.inf))
    lo = values[math.floor((1 - level) / 2 * (resamples - 1))]
    hi = values[math.ceil((1 + level) / 2 * (resamples - 1))]
    return float(lo), float(hi)


def fixed_budget(traces: Sequence[RunTrace], budgets: np.ndarray) -> np.ndarray:
    """(runs, budgets): the error each run had reached after each budget."""
    out = np.full((len(traces), budgets.size), np.inf)
    for i, t in enumerate(traces):
        if not t.errors.size:
            continue
        best = _best_so_far(t)
        idx = np.searchsorted(t.evaluations, budgets, side="right") - 1
        ok = idx >= 0
        out[i, ok] = best[idx[ok]]
    return out


@dataclass
class AnytimeCell:
    """One algorithm on one function and dimension."""

    runs: int
    ert: list[float]  # per target
    ert_low: list[float]
    ert_high: list[float]
    hits: list[int]  # runs that reached each target
    auc: float
    ecdf: list[float]  # at the group's ecdf budgets
    budget_median: list[float]  # fixed budget: median error per budget
    budget_mean: list[float]
    times: np.ndarray = field(repr=False, default_factory=lambda: np.empty((0, 0)))

    def to_json(self) -> dict[str, Any]:
        return {"runs": self.runs, "ert": self.ert, "ert_low": self.ert_low,
                "ert_high": self.ert_high, "hits": self.hits, "auc": self.auc,
                "ecdf": self.ecdf, "fixed_budget_median": self.budget_median,
                "fixed_budget_mean": self.budget_mean}


@dataclass
class AnytimeGroup:
    """Every algorithm on one function and dimension, on shared targets and budgets."""

    targets: list[float]
    budget: int  # the largest budget (the AUC's B)
    ecdf_budgets: list[float]
    fixed_budgets: list[int]
    cells: dict[str, AnytimeCell]
    target_set: str = "iohanalyzer"

    @classmethod
    def from_json(cls, doc: Mapping[str, Any]) -> AnytimeGroup:
        """The group back from :meth:`to_json` ("inf" strings read as floats; no runtimes)."""
        def nums(v: Sequence[Any]) -> list[float]:
            return [float(x) for x in v]

        cells = {a: AnytimeCell(int(c["runs"]), nums(c["ert"]), nums(c["ert_low"]),
                                nums(c["ert_high"]), [int(h) for h in c["hits"]],
                                float(c["auc"]), nums(c["ecdf"]),
                                nums(c["fixed_budget_median"]), nums(c["fixed_budget_mean"]))
                 for a, c in doc["algorithms"].items()}
        return cls(nums(doc["targets"]), int(doc["budget"]), nums(doc["ecdf_budgets"]),
                   [int(b) for b in doc["fixed_budgets"]], cells,
                   str(doc.get("target_set", "iohanalyzer")))

    def to_json(self) -> dict[str, Any]:
        return {"targets": self.targets, "target_set": self.target_set, "budget": self.budget,
                "ecdf_budgets": self.ecdf_budgets, "fixed_budgets": self.fixed_budgets,
                "algorithms": {a: c.to_json() for a, c in self.cells.items()}}


def _summary(values: np.ndarray, how: str) -> float:
    finite_or_inf = values[~np.isnan(values)]
    if finite_or_inf.size == 0:
        return math.nan
    if how == "median":
        return float(np.sort(finite_or_inf)[(finite_or_inf.size - 1) // 2]) if np.isinf(
            finite_or_inf).any() else float(np.median(finite_or_inf))
    with np.errstate(invalid="ignore"):
        return float(np.mean(finite_or_inf))


def anytime_group(traces: Mapping[str, Sequence[RunTrace]], targets: str = "iohanalyzer",
                  seed: int = 0) -> AnytimeGroup:
    """The anytime statistics of every algorithm's runs on one function and dimension."""
    everything = [t for runs in traces.values() for t in runs]
    target = bbob_targets() if targets == "bbob" else default_targets(everything)
    budget = max((t.budget for t in everything), default=0)
    first = min((int(t.evaluations[0]) for t in everything if t.evaluations.size),
                default=1)
    ecdf_x = np.unique(np.geomspace(1.0, max(1.0, budget), ECDF_POINTS).round())
    fixed = np.unique(np.geomspace(max(1, first), max(1, budget), BUDGETS).round()
                      ).astype(np.int64)
    cells = {}
    for algorithm, runs in traces.items():
        times = runtimes(runs, target)
        budgets = np.array([t.budget for t in runs], dtype=float)
        erts, lows, highs = [], [], []
        for j in range(target.size):
            erts.append(ert(times[:, j], budgets))
            lo, hi = ert_interval(times[:, j], budgets, seed)
            lows.append(lo)
            highs.append(hi)
        errors = fixed_budget(runs, fixed.astype(float))
        cells[algorithm] = AnytimeCell(
            len(runs), erts, lows, highs, [int(v) for v in np.isfinite(times).sum(axis=0)],
            ecdf_auc(times, float(budget)), ecdf_curve(times, ecdf_x).tolist(),
            [_summary(errors[:, k], "median") for k in range(fixed.size)],
            [_summary(errors[:, k], "mean") for k in range(fixed.size)], times)
    return AnytimeGroup(target.tolist(), int(budget), ecdf_x.tolist(), fixed.tolist(), cells,
                        targets)


def trace_of(curve: Sequence[float], f_star: float, iterations: int, evaluations: int,
             agents: int, stride: int = 1) -> RunTrace:
    """A run's trace from its best-so-far curve (one value per iteration, or thinned by
    ``stride``) and its evaluation count (:func:`swarmpath.evidence.ioh.evaluation_points`)."""
    from swarmpath.evidence.ioh import evaluation_points

    values = np.asarray(curve, dtype=float)
    points = evaluation_points(values.size, iterations, evaluations, stride, agents)
    err = np.maximum(values - f_star, 0.0)
    return RunTrace(np.asarray(points, dtype=float), err)


def study_groups(cells: Iterable[Any], agents: int, iterations: int,
                 targets: str = "iohanalyzer", seed: int = 0) -> dict[tuple[str, int],
                                                                      AnytimeGroup]:
    """Per (function, dim) the anytime statistics of a study's ``report.Cell`` objects (those
    with curves; the same ``agents`` and ``iterations`` for every cell, as ``bench`` runs)."""
    from swarmpath.evidence.benchmark_stats import f_star

    by_group: dict[tuple[str, int], dict[str, list[RunTrace]]] = {}
    for c in cells:
        if not c.curves:
            continue
        fs = f_star(c.function, c.dim)
        by_group.setdefault((c.function, c.dim), {})[c.algorithm] = [
            trace_of(curve, fs, iterations, int(e), agents)
            for curve, e in zip(c.curves, c.evaluations, strict=False)]
    return {key: anytime_group(traces, targets, seed) for key, traces in by_group.items()}


def groups_to_json(groups: Mapping[tuple[str, int], AnytimeGroup]) -> list[dict[str, Any]]:
    from swarmpath.evidence.stats import json_clean

    return [json_clean({"function": f, "dim": d, **g.to_json()}) for (f, d), g in groups.items()]


def grid_ecdf(points: np.ndarray, rows: Mapping[str, np.ndarray],
              number: int = IOH_TARGETS) -> dict[str, Any]:
    """The runtime ECDF on a sampled grid (the dashboard's: best-so-far errors of each run at
    log-spaced iterations ``points``; ``rows``: algorithm -> (runs, points), NaN where a run
    sent no curve): IOHanalyzer's default targets over every algorithm's values, per algorithm
    the share of (run, target) pairs reached at each point (exact at the points: the errors are
    best-so-far) and the area under it over 0 .. the last point, divided by it. Vectorized over
    runs, points and targets (a page of a 78,000-run job)."""
    arrays = {name: np.asarray(rs, dtype=float).reshape(-1, points.size)
              for name, rs in rows.items()}
    values = np.concatenate([a.ravel() for a in arrays.values()]) if arrays else np.empty(0)
    targets = default_targets([RunTrace(np.arange(values.size, dtype=float), values)], number)
    out: dict[str, Any] = {"targets": targets.tolist(), "points": points.tolist(),
                           "algorithms": {}}
    x = points.astype(float)
    last = float(x[-1]) if x.size else 0.0
    for name, arr in arrays.items():
        arr = arr[~np.all(np.isnan(arr), axis=1)]
        if arr.shape[0] == 0:
            continue
        reached = np.where(np.isnan(arr), np.inf, arr)[:, :, None] <= targets[None, None, :]
        curve = reached.mean(axis=(0, 2))  # (points,)
        hit = reached.any(axis=1)  # (runs, targets)
        first = np.where(hit, x[np.argmax(reached, axis=1)], np.inf)
        out["algorithms"][name] = {"ecdf": curve.tolist(), "auc": ecdf_auc(first, last)}
    return out
