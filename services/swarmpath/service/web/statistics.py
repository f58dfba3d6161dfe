"""The dashboard's statistics of a job, from its aggregates: +/=/- markers against the job's
reference and Friedman mean ranks (:mod:`swarmpath.evidence.compare`, imported on first use:
scipy)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np


def benchmark_statistics(
    samples: Mapping[tuple[str, int], Mapping[str, np.ndarray]],
    groups: Mapping[tuple[str, int], Mapping[str, Any]],
    algorithms: Sequence[str],
    reference: str | None = None,
) -> dict[str, Any] | None:
    """+/=/- of every algorithm against ``reference`` (default: the last one listed) per
    function x dim (Wilcoxon rank-sum, Holm over the table) and Friedman mean ranks per dimension
    (:mod:`swarmpath.evidence.compare`). None with fewer than two algorithms."""
    if len(algorithms) < 2:
        return None
    from swarmpath.evidence.bayes import DEFAULT_ROPE, compare_bayes
    from swarmpath.evidence.benchmark_stats import f_star
    from swarmpath.evidence.compare import compare_samples, friedman

    comparison = compare_samples(samples, algorithms, reference)
    posterior = compare_bayes(samples, algorithms, comparison.reference, DEFAULT_ROPE, "mean",
                              {key: f_star(*key) for key in samples}, group=lambda key: key[1])
    markers: dict[str, dict[str, str]] = {}
    effects: dict[str, dict[str, dict[str, Any]]] = {}
    for (function, dim), per in samples.items():
        for a in per:
            m = comparison.marker((function, dim), a)
            if m is not None:
                markers.setdefault(f"{function}/{dim}", {})[a] = m
            e = _effects(comparison, posterior, (function, dim), a)
            if e:
                effects.setdefault(f"{function}/{dim}", {})[a] = e
    ranks: dict[str, Any] = {}
    for dim in sorted({d for _, d in groups}):
        values = {f: g["means"] for (f, d), g in groups.items() if d == dim}
        fr = friedman(values, algorithms, reference)
        ranks[str(dim)] = {"mean_ranks": fr.mean_ranks, "p": fr.p, "blocks": len(fr.blocks),
                           "note": fr.note}
    return {"test": comparison.test, "reference": comparison.reference,
            "alpha": comparison.alpha, "markers": markers, "counts": comparison.counts(),
            "effects": effects, "rope": str(posterior.rope),
            "bayes_counts": posterior.verdict_counts(),
            "bayes_across": {str(g): v for g, v in posterior.across.items()},
            "friedman": ranks}


def _effects(comparison: Any, posterior: Any, key: Any, name: str) -> dict[str, Any]:
    """A cell's A12, Hodges-Lehmann shift with its interval and Bayesian P(b/e/w), JSON-safe
    (non-finite numbers as None)."""
    t = comparison.get(key, name)
    post = posterior.get(key, name) if posterior is not None else None
    if t is None and post is None:
        return {}

    def num(v: Any) -> Any:
        return v if isinstance(v, float) and np.isfinite(v) else None

    out: dict[str, Any] = {"a12": None if t is None else t.a12}
    if t is not None and t.shift is not None:
        out.update(shift=num(t.shift.estimate), shift_low=num(t.shift.low),
                   shift_high=num(t.shift.high))
    if post is not None:
        out.update(post.to_json())
    return out


def map_statistics(
    groups: Mapping[str, Mapping[str, Any]], planners: Sequence[str],
    reference: str | None = None,
    samples: Mapping[str, Mapping[str, Mapping[str, Sequence[float]]]] | None = None,
) -> dict[str, Any] | None:
    """Every planner against ``reference`` (default: the last one) per map, each test Holm over
    its table (:mod:`swarmpath.evidence.compare`): success rates (Fisher's exact test, ``markers``)
    and, from ``samples`` (metric -> map -> planner -> values), path lengths of successful runs and
    planning times (Wilcoxon rank-sum, lower is better: ``length_markers``,
    ``seconds_markers``, their +/=/- ``length_counts``, ``seconds_counts``) and the Friedman mean
    ranks of the planners' means over the maps (``friedman``: metric -> ranks), as
    ``swarmpath plan`` and ``swarmpath results`` print them
    (:mod:`swarmpath.evidence.compare_maps`)."""
    if len(planners) < 2:
        return None
    from swarmpath.evidence.compare import compare_samples, compare_success, friedman

    counts = {name: {p: (v["succeeded"], v["runs"] - v["crashed"])
                     for p, v in g["planners"].items()} for name, g in groups.items()}
    comparison = compare_success(counts, planners, reference)
    out = {"test": comparison.test, "reference": comparison.reference,
           "alpha": comparison.alpha, "markers": _markers(comparison, counts),
           "counts": comparison.counts()}
    ranks: dict[str, Any] = {}
    from swarmpath.evidence.bayes import DEFAULT_ROPE, compare_bayes

    for metric, values in (samples or {}).items():
        tests = compare_samples(values, planners, reference)
        out[f"{metric}_markers"] = _markers(tests, values)
        out[f"{metric}_counts"] = tests.counts()
        posterior = compare_bayes(values, planners, tests.reference, DEFAULT_ROPE)
        out[f"{metric}_effects"] = {
            name: {p: e for p in per if (e := _effects(tests, posterior, name, p))}
            for name, per in values.items()}
        means = {name: {p: float(np.mean(v)) for p, v in per.items() if len(v)}
                 for name, per in values.items()}
        fr = friedman(means, planners, comparison.reference)
        ranks[metric] = {"mean_ranks": fr.mean_ranks, "p": fr.p, "blocks": len(fr.blocks),
                         "note": fr.note}
    out["friedman"] = ranks
    return out


def _markers(comparison: Any, table: Mapping[str, Mapping[str, Any]]) -> dict[str, dict[str, str]]:
    markers: dict[str, dict[str, str]] = {}
    for name, per in table.items():
        for p in per:
            m = comparison.marker(name, p)
            if m is not None:
                markers.setdefault(name, {})[p] = m
    return markers
